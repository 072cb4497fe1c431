#!/usr/bin/env bash
# The terrain client on the Cortex-M4 board: each benchmark map's 300-frame
# flyover written by `vds encode-terrain` (poses arriving 2 frames late, 5 a
# second) at 2 KB/s and at 115,200 baud, played through vds::Player by the
# firmware vds_fw_bench_walk in QEMU mps2-an386 (-icount shift=0: the
# player's frame records count instructions) and by the same firmware on
# the host board; every frame's CRC must be identical on both. Writes
# bench/results/terrain_m4.md: instructions per frame (mean, worst, by
# stage) and the frames/s they mean at 100 MHz, the workspace the stream
# needed, and what the client showed against the ground truth.
#
# Usage: bench/run_terrain_m4.sh [BUILD_DIR]   (default build/host-release: it
#   must hold encoder/vds, firmware_sim/vds_fw_bench_walk_host and
#   cm4/firmware_sim/vds_fw_bench_walk.elf)
#   MAPS="arizonachase crooked tropic"; RATES="2000 11520"; STORE=24576 (units
#   of 2 bytes); FRAMES=300.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
HOSTFW="$BUILD/firmware_sim/vds_fw_bench_walk_host"
ELF="$BUILD/cm4/firmware_sim/vds_fw_bench_walk.elf"
OUT="$ROOT/bench/results/terrain_m4.md"
STORE=${STORE:-24576}
FRAMES=${FRAMES:-300}
for f in "$VDS" "$HOSTFW" "$ELF"; do
  [[ -e "$f" ]] || { echo "run_terrain_m4.sh: $f not found (cmake --preset host-release && cmake --build build/host-release)" >&2; exit 1; }
done
command -v qemu-system-arm >/dev/null || { echo "run_terrain_m4.sh: qemu-system-arm is required" >&2; exit 1; }
RUN=$(mktemp -d)
trap 'rm -rf "$RUN"' EXIT

i=0
: >"$RUN/names.txt"
for map in ${MAPS:-arizonachase crooked tropic}; do
  for rate in ${RATES:-2000 11520}; do
    echo "== $map at $rate bytes/s: vds encode-terrain --store $STORE --psnr"
    "$VDS" encode-terrain "$map" --frames "$FRAMES" --rate "$rate" --store "$STORE" --psnr -o "$RUN/terrain_case$i.vds" \
      2>/dev/null | tee "$RUN/enc$i.txt"
    "$VDS" info "$RUN/terrain_case$i.vds" >"$RUN/info$i.txt"
    echo "terrain_case$i.vds $map $rate" >>"$RUN/names.txt"
    i=$((i + 1))
  done
done
echo "== Cortex-M4 board (QEMU -icount shift=0) and host board"
(cd "$RUN" && qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial null \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF" >"$RUN/m4.txt" 2>&1) ||
  { tail -n 20 "$RUN/m4.txt"; echo "run_terrain_m4.sh: the Cortex-M4 run failed" >&2; exit 1; }
(cd "$RUN" && "$HOSTFW" >"$RUN/host.txt" 2>&1) || { tail -n 20 "$RUN/host.txt"; exit 1; }
crcs() { grep -E '^frame |^m4 terrain stream=' "$1" | sed -E 's/ parse=.*//; s/ instructions=.*//'; }
if ! diff <(crcs "$RUN/host.txt") <(crcs "$RUN/m4.txt") >/dev/null; then
  echo "run_terrain_m4.sh: the boards showed different frames" >&2
  exit 1
fi
echo "   $(grep -c '^frame ' "$RUN/m4.txt") frame CRCs identical on both boards"

/usr/bin/python3 - "$RUN" "$OUT" "$(qemu-system-arm --version | head -n 1)" "$STORE" "$FRAMES" <<'PY'
import datetime, os, re, sys
run, out, qemu, store, frames_n = sys.argv[1:6]
names = [l.split() for l in open(os.path.join(run, "names.txt"))]
per = {}
order = []
for l in open(os.path.join(run, "m4.txt")):
    if l.startswith("frame "):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        per.setdefault(len(order), []).append([int(kv[s]) for s in ("parse", "decode", "display")])
    elif l.startswith("m4 terrain_parts stream="):
        order.append(dict(re.findall(r"(\w+)=(\S+)", l)))
rows = []
for k, (name, m, rate) in enumerate(names):
    enc = open(os.path.join(run, f"enc{k}.txt")).read()
    info = open(os.path.join(run, f"info{k}.txt")).read()
    f = per.get(k, [])
    tot = [sum(x) for x in f]
    mean = sum(tot) / len(tot)
    worst = max(tot)
    disp = sum(x[2] for x in f) / len(f)
    dec = sum(x[1] for x in f) / len(f)
    psnr = re.search(r"ground truth: mean ([\d.]+) dB", enc).group(1)
    size = re.search(r"(\d+) bytes \(", enc).group(1)
    needs = re.search(r"client needs\s+(\d+) B", info).group(1)
    rows.append((m, int(rate), len(f), mean, worst, dec, disp, int(order[k]["workspace"]), int(needs), psnr, int(size)))
with open(out, "w") as o:
    o.write("# Terrain client on the Cortex-M4 board\n\n")
    o.write(f"Made by `bench/run_terrain_m4.sh` on {datetime.date.today()} ({qemu}, `-icount shift=0`: one "
            "instruction a nanosecond, so instruction counts are exact and repeatable). Each map's scripted "
            f"{frames_n}-frame flyover, 240x180 at 20 frames/s, written by `vds encode-terrain MAP --rate R --store {store} "
            "--psnr` (poses 5 a second, arriving 2 frames late) and played by `vds_fw_bench_walk` through "
            "`vds::Player`; the host board played the same streams and every frame's CRC was identical.\n\n")
    o.write("| map | link (bytes/s) | frames | instructions a frame, mean | worst | of which decode (mean) | display (mean) "
            "| frames/s at 100 MHz (mean, worst) | workspace used | declared | client frames vs ground truth |\n")
    o.write("|---|---|---|---|---|---|---|---|---|---|---|\n")
    for m, rate, n, mean, worst, dec, disp, ws, needs, psnr, size in rows:
        o.write(f"| {m} | {rate:,} | {n} | {mean/1e6:.2f} M | {worst/1e6:.2f} M | {dec/1e6:.2f} M | {disp/1e6:.2f} M "
                f"| {1e8/mean:.1f}, {1e8/worst:.1f} | {ws/1024:.0f} KiB | {needs/1024:.0f} KiB | {psnr} dB |\n")
    o.write("\nThe goals: at least 20 frames/s at 100 MHz and at most 192 KiB of RAM with the store. "
            "Workspace is the player's arena high-water mark (the link's buffers, about 8 KiB, and the stack come on top "
            "on the client firmware). 'Declared' is what the stream's header asks of a client beyond its chunk buffer.\n")
print(open(out).read())
PY
