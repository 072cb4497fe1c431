#!/usr/bin/env bash
# The demo (builds are done by `make demo`): a reel of twelve OpenArena
# textures is encoded into one vds stream at 240x180, streamed by `vds serve`
# over a pseudo-terminal at 115,200 baud to the client firmware on the
# host-native board (which writes the frames, a Y4M video and a contact
# sheet) and over TCP to the same firmware on the Cortex-M4 board in QEMU
# (which reports its instruction counts). Both boards' frame CRCs must equal
# the encoder's reconstruction. Then the Stanford bunny (glmark2-data) as a
# progressive model at 2 KB/s to the host-native board, drawn after every
# level; a walkthrough of the OpenArena map oa_dm4 at 2 KB/s to both
# boards; a terrain flight over a Trigger Rally map, served live to both
# boards as they send their poses up, and steered on the host board; then the client self-test on both boards and the size of the
# client's parts. Everything goes to out/demo/; the summary
# is out/demo/report.md.
set -euo pipefail
BUILD=${1:-build/host-release}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT="$ROOT/out/demo"
VDS="$ROOT/$BUILD/encoder/vds"
CM4="$ROOT/$BUILD/cm4/firmware_sim"
PK3=/usr/share/games/openarena/baseoa/pak4-textures.pk3
rm -rf "$OUT"
mkdir -p "$OUT/src"
[ -f "$PK3" ] || { echo "demo: $PK3 not found; run scripts/fetch-data.sh" >&2; exit 1; }

echo "demo: 1/8 taking twelve textures from $(basename "$PK3")"
python3 "$ROOT/scripts/demo_reel.py" "$OUT/src" "$PK3"

echo "demo: 2/8 encoding, then streaming to both boards at 115,200 baud (about a minute)"
python3 "$ROOT/tests/tools/e2e_boards.py" --vds "$VDS" --host-board "$ROOT/$BUILD/firmware_sim/vds_fw_client_host" \
  --qemu qemu-system-arm --elf "$CM4/vds_fw_client.elf" --work "$OUT" --quality 75 \
  --inputs "$OUT"/src/*.tga --report "$OUT/run.json" > "$OUT/end_to_end.log" 2>&1 || {
  tail -n 30 "$OUT/end_to_end.log"
  echo "demo: the end-to-end run failed (log: out/demo/end_to_end.log)" >&2
  exit 1
}
grep -E '^(encoder|host|cortex-m4) *:|^end-to-end' "$OUT/end_to_end.log"

echo "demo: 3/8 the Stanford bunny as a progressive model at 2 KB/s to the host-native board, then to the Cortex-M4 board (about a minute)"
MODEL=/usr/share/glmark2/models/bunny.obj
[ -f "$MODEL" ] || { echo "demo: $MODEL not found; run scripts/fetch-data.sh" >&2; exit 1; }
python3 "$ROOT/scripts/demo_model.py" --vds "$VDS" --host-board "$ROOT/$BUILD/firmware_sim/vds_fw_client_host" \
  --model "$MODEL" --out "$OUT/model" --qemu qemu-system-arm --elf "$CM4/vds_fw_client.elf" > "$OUT/model.md" || {
  cat "$OUT/model.md"
  echo
  cat "$OUT/walk.md"
  echo "demo: the model run failed (log: out/demo/model/serve.log)" >&2
  exit 1
}
grep -E '^(`|The same stream)' "$OUT/model.md"

echo "demo: 4/8 a walkthrough of oa_dm4 at 2 KB/s (vds path, vds encode-walk) to both boards, each frame at its time (about two minutes)"
python3 "$ROOT/scripts/demo_walk.py" --vds "$VDS" --host-board "$ROOT/$BUILD/firmware_sim/vds_fw_client_host" \
  --qemu qemu-system-arm --elf "$CM4/vds_fw_client.elf" --out "$OUT/walk" > "$OUT/walk.md" || {
  cat "$OUT/walk.md"
  echo "demo: the walkthrough run failed (logs: out/demo/walk/)" >&2
  exit 1
}
grep -E '^(`|On the Cortex)' "$OUT/walk.md"

echo "demo: 5/8 a terrain flight over the Trigger Rally map grass, served live (vds serve-terrain) to both boards as they send their poses up, then steered on the host board"
mkdir -p "$OUT/terrain"
TERRAIN_OK=1
for board in host qemu; do
  FW="$ROOT/$BUILD/firmware_sim/vds_fw_client_host"
  [ "$board" = qemu ] && FW="$CM4/vds_fw_client.elf"
  "$VDS" serve-terrain grass --frames 100 --rate 4000 --board "$board" --firmware "$FW" --board-out "$OUT/terrain/$board" \
    --stream-out "$OUT/terrain/$board.vds" > "$OUT/terrain/$board.log" 2>&1 || TERRAIN_OK=0
  grep -E '^grass \(live\): [0-9]+ frames made|^  replay ' "$OUT/terrain/$board.log" | sed "s/^/  $board: /"
done
# The same flight steered on the host board by a controls script, as a
# viewer's keys would steer it (--window: the window's own keys and mouse).
cat > "$OUT/terrain/steer.controls" <<'CONTROLS'
# FRAMES FORWARD RIGHT UP TURN TILT [fast]: the flight, then a turning climb
20 0 0 0 0 0
40 1 0 0 4.5 0
20 1 0 1 4.5 -0.5
20 0 0 0 -3 0
CONTROLS
"$VDS" serve-terrain grass --frames 100 --rate 4000 --board host --firmware "$ROOT/$BUILD/firmware_sim/vds_fw_client_host" \
  --controls "$OUT/terrain/steer.controls" --board-out "$OUT/terrain/steered" > "$OUT/terrain/steered.log" 2>&1 || TERRAIN_OK=0
grep -E "^grass \(live\): [0-9]+ frames drawn from the viewer|^  replay " "$OUT/terrain/steered.log" | sed "s/^/  host, steered: /"
[ "$TERRAIN_OK" = 1 ] || { echo "demo: the terrain run failed (logs: out/demo/terrain/)" >&2; exit 1; }

echo "demo: 6/8 client self-test on the host board and on the Cortex-M4 board (QEMU mps2-an386)"
BOARDS=$(python3 "$ROOT/tests/tools/compare_boards.py" --host "$ROOT/$BUILD/firmware_sim/vds_fw_selftest_host" \
  --qemu qemu-system-arm --elf "$CM4/vds_fw_selftest.elf")
echo "$BOARDS" | grep -E '^boards'

echo "demo: 7/8 Cortex-M4 size of the client library and the link"
SIZE_TABLE=$(python3 "$ROOT/tests/tools/check_freestanding.py" \
  --cxx arm-none-eabi-g++ --nm arm-none-eabi-nm --size arm-none-eabi-size --out "$OUT/linkcheck" \
  --lib "decoder=$ROOT/$BUILD/cm4/decoder/libvds_decoder.a" \
  --lib "transport_core=$ROOT/$BUILD/cm4/transport/libvds_transport_core.a")

echo "demo: 8/8 writing the report"
{
  python3 "$ROOT/scripts/client_report.py" --run "$OUT/run.json" --elf "$CM4/vds_fw_client.elf" \
    --map "$CM4/vds_fw_client.map" --title "vds demo: twelve textures to a simulated client" --images-dir host |
    sed "s|$OUT/||g"
  echo
  echo "Frames the host-native board displayed: \`out/demo/host/frames/\`, video \`out/demo/host/frames.y4m\`"
  echo "(and \`frames.mp4\` when ffmpeg is installed). Stream: \`out/demo/e2e.vds\`; logs: \`out/demo/end_to_end.log\`."
  echo
  cat "$OUT/model.md"
  echo
  cat "$OUT/walk.md"
  echo
  echo "## Terrain, live"
  echo
  echo "\`vds serve-terrain grass --frames 100 --rate 4000 --board host|qemu\`: the client plays the flight the stream"
  echo "gives it and sends its pose up the link's pose channel; the server answers the newest pose it has."
  echo "Every frame each board showed equals the replay of the stream it was sent. Frames from the host board:"
  echo "\`out/demo/terrain/host/frames/\`, contact sheet \`out/demo/terrain/host/contact_sheet.png\`."
  echo
  echo '```'
  for board in host qemu; do grep -E '^grass \(live\): [0-9]+ frames made|^  replay |^  client stats' "$OUT/terrain/$board.log"; done
  echo '```'
  echo
  echo "Steered: the same flight on the host board with \`--controls out/demo/terrain/steer.controls\` (what the"
  echo "window's keys give with \`--window\`): the client sends its steered pose up, the server draws it, and the"
  echo "frames still equal the replay (\`out/demo/terrain/steered/contact_sheet.png\`)."
  echo
  echo '```'
  grep -E '^grass \(live\): [0-9]+ frames drawn from the viewer|^  replay ' "$OUT/terrain/steered.log"
  echo '```'
  echo
  echo "## Client self-test, host board against the Cortex-M4 board"
  echo
  echo '```'
  echo "$BOARDS" | grep -E '^(check|count|info|boards)' | sort -u
  echo '```'
  echo
  echo "## Client library and link on the Cortex-M4 (freestanding link check)"
  echo
  echo '```'
  echo "$SIZE_TABLE"
  echo '```'
} > "$OUT/report.md"
sed -n '/^## The link/,/^## Flash/p' "$OUT/report.md" | grep -E '^\|' || true
grep -E '^\*\*Minimum RAM' "$OUT/report.md" || true
echo "demo: report written to out/demo/report.md, frames in out/demo/host/"
