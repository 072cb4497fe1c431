#!/usr/bin/env bash
# Link benchmark: goodput and framing overhead in simulated time, goodput
# against a device that drains slowly (bench_link), the client's link RAM
# from the Cortex-M4 build, and the link on the Cortex-M4 board in QEMU
# (bench/link_boards.py: the rate the board drains, goodput at four line
# rates, and a soak of the demo reel and the bunny model with every core
# busy and idle; about 25 minutes). Writes bench/results/link.md.
# Usage: bench/run_link.sh [BUILD_DIR] [MiB per row, default 8] [soak runs per row, default 30]
#   (BUILD_DIR default build/host-release: encoder/vds, bench/bench_link and cm4/)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
MIB=${2:-8}
RUNS=${3:-30}
OUT=$ROOT/bench/results/link.md
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
PK3=/usr/share/games/openarena/baseoa/pak4-textures.pk3
MODEL=/usr/share/glmark2/models/bunny.obj
for f in "$BUILD/encoder/vds" "$BUILD/cm4/firmware_sim/vds_fw_client.elf" "$PK3" "$MODEL"; do
  [ -e "$f" ] || { echo "run_link: $f not found (make bench builds and fetches everything)" >&2; exit 1; }
done
cmake --build "$BUILD" -j2 --target bench_link >/dev/null

ARMFLAGS="-std=c++20 -mcpu=cortex-m4 -mthumb -mfloat-abi=soft -O2 -ffreestanding -fno-exceptions -fno-rtti -fno-threadsafe-statics -fstack-usage"
INC="-I$ROOT/decoder/include -I$ROOT/transport/core/include"
arm-none-eabi-g++ $ARMFLAGS $INC -c "$ROOT/bench/m4/link_ram.cpp" -o "$TMP/link_ram.o"
for f in link arq frame cobs; do
  arm-none-eabi-g++ $ARMFLAGS $INC -c "$ROOT/transport/core/src/$f.cpp" -o "$TMP/$f.o"
done
sym_size() { printf '%d' "0x$(arm-none-eabi-nm -S -C "$TMP/link_ram.o" | awk -v s="$1" '$4==s {print $2}')"; }
LINK=$(sym_size g_link)
WS=$(sym_size g_link_workspace)
STACK=$(cat "$TMP"/*.su | sort -t$'\t' -k2 -n -r | head -6)

# The Cortex-M4 board: the demo reel (twelve OpenArena textures, quality 75)
# and the bunny as a progressive model, as make demo streams them.
python3 "$ROOT/scripts/demo_reel.py" "$TMP/reel" "$PK3" >/dev/null
"$BUILD/encoder/vds" encode-frames "$TMP"/reel/*.tga -o "$TMP/reel.vds" --size 240x180 --quality 75 >/dev/null
"$BUILD/encoder/vds" encode-mesh "$MODEL" -o "$TMP/bunny.vds" >/dev/null
BOARDS_OK=0
python3 "$ROOT/bench/link_boards.py" --build "$BUILD" --reel "$TMP/reel.vds" --model "$TMP/bunny.vds" \
  --runs "$RUNS" --work "$TMP/boards" --out "$TMP/boards.md" >/dev/null || BOARDS_OK=1

{
  echo "# Link benchmark"
  echo
  REL=${BUILD#"$ROOT"/}
  echo "Produced by \`bench/run_link.sh $REL $MIB $RUNS\` (\`$REL/bench/bench_link $MIB\` in simulated time;"
  echo "RAM from \`arm-none-eabi-g++ $ARMFLAGS\` on \`bench/m4/link_ram.cpp\`, sizes read with"
  echo "\`arm-none-eabi-nm -S\`; the Cortex-M4 board by \`bench/link_boards.py --runs $RUNS\`). Date: $(date -u +%Y-%m-%d)."
  echo
  "$BUILD/bench/bench_link" "$MIB" | sed 1,2d
  echo
  echo "## Client-side RAM (Cortex-M4 build, device_config: 4 x 1 KiB stream window)"
  echo
  echo "| object | bytes |"
  echo "|---|---:|"
  echo "| \`Link\` (state, channel table, counters) | $LINK |"
  echo "| workspace (receive window 4096, frame buffers, upward channel buffers) | $WS |"
  echo "| **total** | **$((LINK + WS))** (goal <= 8192) |"
  echo
  echo "The client's link RAM is static: the \`Link\` object and the workspace \`Link::init\` carves"
  echo "(\`link_workspace_size(device_config(...))\`, a compile-time constant), no heap. The receive"
  echo "window is 4096 bytes (4 frames of 1 KiB); the rest is the receive frame buffer (1037 bytes:"
  echo "one COBS-encoded 1 KiB frame, decoded in place), the transmit frame buffer, the upward channels'"
  echo "buffers (control 256 + 256, checksums 256, pose 32, stats 64), 16 out-of-order ranges per"
  echo "reliable receive channel, 8 in-flight frame records per reliable send channel and the log of"
  echo "frames on the line (two entries per in-flight frame record, 12 bytes each)."
  echo
  echo "Largest stack frames of the core (\`-fstack-usage\`, bytes):"
  echo
  echo '```'
  echo "$STACK" | sed "s|$ROOT/||"
  echo '```'
  echo
  cat "$TMP/boards.md"
} > "$OUT"
echo "wrote $OUT"
exit $BOARDS_OK
