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
#   MAPS="arizonachase crooked tropic"; RATES="2000 11520"; FRAMES=300;
#   CLIENTS: name=options pairs for vds encode-terrain, one run each (default:
#   "default=--store 24576" and "small=--store 16384 --half-log2 5 --cache-log2 3",
#   the second sized for 192 KiB).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
HOSTFW="$BUILD/firmware_sim/vds_fw_bench_walk_host"
ELF="$BUILD/cm4/firmware_sim/vds_fw_bench_walk.elf"
OUT="$ROOT/bench/results/terrain_m4.md"
FRAMES=${FRAMES:-300}
CLIENTS=${CLIENTS:-"default=--store 24576;small=--store 16384 --half-log2 5 --cache-log2 3"}
for f in "$VDS" "$HOSTFW" "$ELF"; do
  [[ -e "$f" ]] || { echo "run_terrain_m4.sh: $f not found (cmake --preset host-release && cmake --build build/host-release)" >&2; exit 1; }
done
command -v qemu-system-arm >/dev/null || { echo "run_terrain_m4.sh: qemu-system-arm is required" >&2; exit 1; }
RUN=$(mktemp -d)
trap 'rm -rf "$RUN"' EXIT

IFS=';' read -ra CLIENT_LIST <<<"$CLIENTS"
: >"$RUN/clients.txt"
for client in "${CLIENT_LIST[@]}"; do
  cname=${client%%=*}
  copts=${client#*=}
  DIR="$RUN/$cname"
  mkdir -p "$DIR"
  echo "$cname $copts" >>"$RUN/clients.txt"
  i=0
  : >"$DIR/names.txt"
  for map in ${MAPS:-arizonachase crooked tropic}; do
    for rate in ${RATES:-2000 11520}; do
      echo "== $cname client: $map at $rate bytes/s: vds encode-terrain $copts --psnr"
      # shellcheck disable=SC2086
      "$VDS" encode-terrain "$map" --frames "$FRAMES" --rate "$rate" $copts --psnr -o "$DIR/terrain_case$i.vds" \
        2>/dev/null | tee "$DIR/enc$i.txt"
      "$VDS" info "$DIR/terrain_case$i.vds" >"$DIR/info$i.txt"
      echo "terrain_case$i.vds $map $rate" >>"$DIR/names.txt"
      i=$((i + 1))
    done
  done
  echo "== $cname client: Cortex-M4 board (QEMU -icount shift=0) and host board"
  (cd "$DIR" && qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial null \
    -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF" >"$DIR/m4.txt" 2>&1) ||
    { tail -n 20 "$DIR/m4.txt"; echo "run_terrain_m4.sh: the Cortex-M4 run failed" >&2; exit 1; }
  (cd "$DIR" && "$HOSTFW" >"$DIR/host.txt" 2>&1) || { tail -n 20 "$DIR/host.txt"; exit 1; }
  crcs() { grep -E '^frame |^m4 terrain stream=' "$1" | sed -E 's/ parse=.*//; s/ needs=.*//'; }
  if ! diff <(crcs "$DIR/host.txt") <(crcs "$DIR/m4.txt") >/dev/null; then
    echo "run_terrain_m4.sh: the boards showed different frames" >&2
    exit 1
  fi
  echo "   $(grep -c '^frame ' "$DIR/m4.txt") frame CRCs identical on both boards"
done

/usr/bin/python3 - "$RUN" "$OUT" "$(qemu-system-arm --version | head -n 1)" "$FRAMES" <<'PY'
import datetime, os, re, sys
run, out, qemu, frames_n = sys.argv[1:5]
clients = [l.rstrip("\n").split(" ", 1) for l in open(os.path.join(run, "clients.txt"))]
rows = []
for cname, copts in clients:
    d = os.path.join(run, cname)
    names = [l.split() for l in open(os.path.join(d, "names.txt"))]
    per, order = {}, []
    for l in open(os.path.join(d, "m4.txt")):
        if l.startswith("frame "):
            kv = dict(re.findall(r"(\w+)=(\S+)", l))
            per.setdefault(len(order), []).append([int(kv[s]) for s in ("parse", "decode", "display")])
        elif l.startswith("m4 terrain_parts stream="):
            order.append(dict(re.findall(r"(\w+)=(\S+)", l)))
    for k, (name, m, rate) in enumerate(names):
        enc = open(os.path.join(d, f"enc{k}.txt")).read()
        info = open(os.path.join(d, f"info{k}.txt")).read()
        f = per[k]
        tot = [sum(x) for x in f]
        rows.append(dict(client=cname, opts=copts, map=m, rate=int(rate), n=len(f), mean=sum(tot) / len(tot), worst=max(tot),
                         dec=sum(x[1] for x in f) / len(f), disp=sum(x[2] for x in f) / len(f),
                         ws=int(order[k]["workspace"]) - int(order[k]["chunk_buffer"]),
                         needs=int(re.search(r"client needs\s+(\d+) B", info).group(1)),
                         psnr=re.search(r"ground truth: mean ([\d.]+) dB", enc).group(1)))
with open(out, "w") as o:
    o.write("# Terrain client on the Cortex-M4 board\n\n")
    o.write(f"Made by `bench/run_terrain_m4.sh` on {datetime.date.today()} ({qemu}, `-icount shift=0`: one "
            "instruction a nanosecond, so instruction counts are exact and repeatable). Each map's scripted "
            f"{frames_n}-frame flyover, 240x180 at 20 frames/s, written by `vds encode-terrain MAP --rate R OPTIONS "
            "--psnr` (poses 5 a second, arriving 2 frames late) and played by `vds_fw_bench_walk` through "
            "`vds::Player`; the host board played the same streams and every frame's CRC was identical.\n\n")
    o.write("Clients: " + "; ".join(f"**{c}** `{opts}`" for c, opts in clients) + ".\n\n")
    o.write("| client | map | link (bytes/s) | instructions a frame, mean | worst | decode (mean) | display (mean) "
            "| frames/s at 100 MHz (mean, worst) | workspace used | client needs | client's frames vs ground truth |\n")
    o.write("|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        o.write(f"| {r['client']} | {r['map']} | {r['rate']:,} | {r['mean']/1e6:.2f} M | {r['worst']/1e6:.2f} M | "
                f"{r['dec']/1e6:.2f} M | {r['disp']/1e6:.2f} M | {1e8/r['mean']:.1f}, {1e8/r['worst']:.1f} | "
                f"{r['ws']/1024:.0f} KiB | {r['needs']/1024:.0f} KiB | {r['psnr']} dB |\n")
    o.write("\nThe goals: at least 20 frames/s at 100 MHz and at most 192 KiB of RAM with the store. 'Workspace used' is "
            "the player's arena high-water mark less the benchmark's 32 KiB chunk buffer; 'client needs' is what the "
            "stream's header asks of a client with the boards' 4 KiB chunk buffer (the link's buffers, about 8 KiB, and "
            "the stack come on top on the client firmware). 'Client's frames vs ground truth' is the mean PSNR of the "
            "frames the client library draws against the reference renderer with the whole colour map.\n")
print(open(out).read())
PY
