#!/usr/bin/env bash
# The walkthrough client on the Cortex-M4 board: each map's 600-frame tour
# (bench/run_walk_video.sh's tours) encoded at 16 kbit/s by `vds encode-walk`,
# played through vds::Player by the firmware vds_fw_bench_walk in QEMU
# mps2-an386 (-icount shift=0: the player's frame records count
# instructions) and by the same firmware on the host board; every frame's
# CRC must be identical on both. Writes bench/results/walkthrough_m4.md:
# instructions per frame (mean, worst, by stage) and the frames/s they mean
# at 100 MHz, the workspace, and the flash and RAM of the client firmware.
#
# Usage: bench/run_walkthrough_m4.sh [BUILD_DIR]   (default build/host-release: it
#   must hold encoder/vds, firmware_sim/vds_fw_bench_walk_host,
#   cm4/firmware_sim/vds_fw_bench_walk.elf and cm4/firmware_sim/vds_fw_client.elf)
#   MAPS="oa_dm4 oa_dm5 oa_rpg3dm2"; RATE=16; WORK (default BUILD_DIR/walk).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
HOSTFW="$BUILD/firmware_sim/vds_fw_bench_walk_host"
ELF="$BUILD/cm4/firmware_sim/vds_fw_bench_walk.elf"
CLIENT="$BUILD/cm4/firmware_sim/vds_fw_client.elf"
WORK=${WORK:-$BUILD/walk}
RATE=${RATE:-16}
OUT="$ROOT/bench/results/walkthrough_m4.md"
for f in "$VDS" "$HOSTFW" "$ELF" "$CLIENT"; do
  [[ -e "$f" ]] || { echo "run_walkthrough_m4.sh: $f not found (cmake --preset host-release && cmake --build build/host-release)" >&2; exit 1; }
done
for t in qemu-system-arm arm-none-eabi-size arm-none-eabi-nm; do command -v $t >/dev/null || { echo "run_walkthrough_m4.sh: $t is required" >&2; exit 1; }; done
RUN=$(mktemp -d)
trap 'rm -rf "$RUN"' EXIT

i=0
: >"$RUN/names.txt"
for map in ${MAPS:-oa_dm4 oa_dm5 oa_rpg3dm2}; do
  [[ -f "$WORK/$map/tour.txt" ]] || { echo "run_walkthrough_m4.sh: $WORK/$map/tour.txt missing (bench/run_walk_video.sh)" >&2; exit 1; }
  echo "== $map: vds encode-walk at $RATE kbit/s"
  "$VDS" encode-walk "$map" --path "$WORK/$map/tour.txt" --rate "$RATE" -o "$RUN/walk_case$i.vds" 2>/dev/null | tee "$RUN/enc$i.txt"
  echo "walk_case$i.vds $map" >>"$RUN/names.txt"
  i=$((i + 1))
done
echo "== Cortex-M4 board (QEMU -icount shift=0) and host board"
(cd "$RUN" && qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial null \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF" >"$RUN/m4.txt" 2>&1) ||
  { tail -n 20 "$RUN/m4.txt"; echo "run_walkthrough_m4.sh: the Cortex-M4 run failed" >&2; exit 1; }
(cd "$RUN" && "$HOSTFW" >"$RUN/host.txt" 2>&1) || { tail -n 20 "$RUN/host.txt"; exit 1; }
crcs() { grep -E '^frame |^m4 walk stream=' "$1" | sed -E 's/ parse=.*//; s/ instructions=.*//'; }
if ! diff <(crcs "$RUN/host.txt") <(crcs "$RUN/m4.txt") >/dev/null; then
  echo "run_walkthrough_m4.sh: the boards showed different frames" >&2
  exit 1
fi
echo "   $(grep -c '^frame ' "$RUN/m4.txt") frame CRCs identical on both boards"
arm-none-eabi-size -A "$CLIENT" >"$RUN/size.txt"
arm-none-eabi-nm -S -C "$CLIENT" >"$RUN/nm.txt"

/usr/bin/python3 - "$RUN" "$OUT" "$(qemu-system-arm --version | head -n 1)" "$RATE" <<'PY'
import datetime, os, re, sys
run, out, qemu, rate = sys.argv[1:5]
names = dict(l.split() for l in open(os.path.join(run, "names.txt")))
frames, summ, parts = {}, {}, {}
cur = None
stream = sorted(names)
k = 0
for l in open(os.path.join(run, "m4.txt")):
    if l.startswith("frame "):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        frames.setdefault(stream[k], []).append(sum(int(kv[s]) for s in ("parse", "decode", "display")))
    elif l.startswith("m4 walk stream="):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        summ[kv["stream"]] = kv
    elif l.startswith("m4 walk_parts stream="):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        parts[kv["stream"]] = kv
        k += 1
enc = {}
for i, s in enumerate(stream):
    t = open(os.path.join(run, f"enc{i}.txt")).read()
    enc[s] = {"kbps": re.search(r"= ([\d.]+) kbit/s", t).group(1),
              "psnr": re.search(r"PSNR R,G,B ([\d.]+) dB", t).group(1),
              "declared": int(re.search(r"(\d+) bytes of workspace", t).group(1))}
sec = {}
for l in open(os.path.join(run, "size.txt")):
    f = l.split()
    if len(f) >= 2 and f[0].startswith("."):
        sec[f[0]] = int(f[1])
flash = sec.get(".text", 0) + sec.get(".rodata", 0) + sec.get(".data", 0) + sec.get(".ARM.exidx", 0)
ram = sec.get(".data", 0) + sec.get(".bss", 0) + sec.get(".stack", 0)
client_ws = next(int(l.split()[1], 16) for l in open(os.path.join(run, "nm.txt")) if l.rstrip().endswith("g_workspace"))
fits = [names[s] for s in sorted(names) if enc[s]["declared"] <= client_ws]
L = ["# The walkthrough client on the Cortex-M4 board", "",
     f"Produced by `bench/run_walkthrough_m4.sh build/host-release` on {datetime.date.today()}. {qemu}, "
     "`-M mps2-an386 -cpu cortex-m4 -icount shift=0`; firmware `vds_fw_bench_walk` (arm-none-eabi-g++ -O2, the "
     "Release Cortex-M4 sub-build, 4 MiB RAM linker script) plays each stream through `vds::Player` as the client "
     f"does; streams by `vds encode-walk MAP --path TOUR --rate {rate}` on the 600-frame tours of `walk_anchors.md`, "
     "240x180. The same firmware on the host board showed the same CRC for every frame.", "",
     "| map | kbit/s | PSNR R,G,B dB | frames | instructions/frame mean | worst | frames/s at 100 MHz (mean) | (worst) | "
     "parse | decode | display (draw) | workspace high-water B | of which the 32 KiB chunk buffer | HEAD declares |",
     "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
for s in stream:
    kv, pv, fr = summ[s], parts[s], frames[s]
    n = int(kv["frames"])
    mean = int(kv["instructions"]) / n
    worst = int(kv["worst"])
    L.append(f"| {names[s]} | {enc[s]['kbps']} | {enc[s]['psnr']} | {n} | {mean / 1e6:.2f} M | {worst / 1e6:.2f} M | "
             f"{1e8 / mean:.1f} | {1e8 / worst:.1f} | {int(pv['parse']) / n / 1e3:.1f} k | {int(pv['decode']) / n / 1e3:.0f} k | "
             f"{int(pv['display']) / n / 1e6:.2f} M | {int(pv['workspace']):,} | {int(pv['chunk_buffer']):,} | {enc[s]['declared']:,} |")
L += ["", "Per stage (the player's frame records): parse is the container (chunk framing and CRC-32C), decode the "
      "records' geometry, poses and view choices and the view images (counted in the frame after them), display "
      "the drawing of the frame (every hot triangle mapped from its view: homography, set-up, spans) and the "
      "player's band CRC. Workspace: the arena's high-water mark, the player's chunk buffer included.", "",
      f"Client firmware `vds_fw_client` (the image, model and walkthrough modes and the link): flash {flash:,} bytes "
      f"(.text + .rodata + .data), RAM {ram:,} bytes (.data + .bss + .stack, its {client_ws:,}-byte workspace "
      "included): a stream whose workspace high-water, less the 32 KiB chunk buffer above, with the client's own chunk "
      "buffer and link buffers fits that workspace plays on this firmware.", "",
      f"**Goals: >= 20 frames/s at 240x180 at 100 MHz — "
      f"{'reached' if all(1e8 * int(summ[s]['frames']) / int(summ[s]['instructions']) >= 20 for s in stream) else 'not reached'}; "
      f"RAM <= 192 KiB — the firmware's RAM is {'within' if ram <= 192 * 1024 else 'over'} it (the build links the client "
      f"into 192 KiB), and of these maps {', '.join(fits) if fits else 'none'} "
      f"{'declares' if len(fits) == 1 else 'declare'} no more workspace than the firmware's.** docs/walkthrough.md says "
      "where the instructions and the bytes go."]
open(out, "w").write("\n".join(L) + "\n")
print("\n".join(L))
PY
