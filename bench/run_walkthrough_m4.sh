#!/usr/bin/env bash
# The walkthrough client on the Cortex-M4 board: each map's 600-frame tour
# (bench/run_walk_video.sh's tours) encoded at 16 kbit/s by `vds encode-walk`,
# played through vds::Player by the firmware vds_fw_bench_walk in QEMU
# mps2-an386 (-icount shift=0: the player's frame records count
# instructions) and by the same firmware on the host board, each stream
# twice: in the client firmware's workspace (after its link's buffers, with
# its chunk buffer) and in the board's 4 MiB; every frame's CRC must be
# identical on both boards and in both workspaces. Writes
# bench/results/walkthrough_m4.md: instructions per frame (mean, worst, by
# stage) and the frames/s they mean at 100 MHz in each workspace, the
# workspace, and the flash and RAM of the client firmware.
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
crcs() { grep -E '^frame |^m4 walk stream=' "$1" | sed -E 's/ parse=.*//; s/ needs=.*//'; }
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
cur = []
for l in open(os.path.join(run, "m4.txt")):
    if l.startswith("frame "):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        cur.append((kv["crc"], sum(int(kv[s]) for s in ("parse", "decode", "display"))))
    elif l.startswith("m4 walk stream="):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        summ[kv["stream"], kv["budget"]] = kv
    elif l.startswith("m4 walk_parts stream="):
        kv = dict(re.findall(r"(\w+)=(\S+)", l))
        parts[kv["stream"], kv["budget"]] = kv
        frames[kv["stream"], kv["budget"]] = cur
        cur = []
stream = sorted(names)
for s in stream:
    c, b = frames.get((s, "client"), []), frames[s, "board"]
    if c and [x[0] for x in c] != [x[0] for x in b]:
        sys.exit(f"run_walkthrough_m4.sh: {names[s]} showed other frames in the client's workspace than in the board's")
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
fits = [names[s] for s in stream if summ[s, "client"]["status"] == "ok"]
def speed(s, b):
    kv = summ[s, b]
    if kv["status"] != "ok":
        return None
    n = int(kv["frames"])
    return int(kv["instructions"]) / n, int(kv["worst"])
L = ["# The walkthrough client on the Cortex-M4 board", "",
     f"Produced by `bench/run_walkthrough_m4.sh build/host-release` on {datetime.date.today()}. {qemu}, "
     "`-M mps2-an386 -cpu cortex-m4 -icount shift=0`; firmware `vds_fw_bench_walk` (arm-none-eabi-g++ -O2, the "
     "Release Cortex-M4 sub-build) plays each stream through `vds::Player` twice: in the client firmware's "
     f"workspace ({client_ws:,} bytes, after the buffers its link takes, with its chunk buffer: what the client "
     "does) and in the board's 4 MiB (every cache the player keeps). Streams by "
     f"`vds encode-walk MAP --path TOUR --rate {rate}` on the 600-frame tours of `walk_anchors.md`, 240x180. The "
     "same firmware on the host board showed the same CRC for every frame, and so did both workspaces.", "",
     "| map | kbit/s | PSNR R,G,B dB | frames | in the client's workspace: instructions/frame mean | worst | "
     "frames/s at 100 MHz (mean) | (worst) | with every cache: mean | worst | frames/s (mean) | parse | decode | "
     "display (draw) | the least workspace it plays in B | with every cache B | HEAD declares (host) |",
     "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
for s in stream:
    kv, pv = summ[s, "board"], parts[s, "board"]
    n = int(kv["frames"])
    cl, bd = speed(s, "client"), speed(s, "board")
    cpart = (f"{cl[0] / 1e6:.2f} M | {cl[1] / 1e6:.2f} M | {1e8 / cl[0]:.1f} | {1e8 / cl[1]:.1f}" if cl
             else "does not fit | - | - | -")
    least = int(summ[s, "board"]["needs"]) + int(parts[s, "client"]["chunk_buffer"]) + int(parts[s, "client"]["link"])
    L.append(f"| {names[s]} | {enc[s]['kbps']} | {enc[s]['psnr']} | {n} | {cpart} | {bd[0] / 1e6:.2f} M | "
             f"{bd[1] / 1e6:.2f} M | {1e8 / bd[0]:.1f} | {int(pv['parse']) / n / 1e3:.1f} k | "
             f"{int(pv['decode']) / n / 1e3:.0f} k | {int(pv['display']) / n / 1e6:.2f} M | {least:,} | "
             f"{int(pv['workspace']) - int(pv['chunk_buffer']):,} | {enc[s]['declared']:,} |")
L += ["", "Per stage (the player's frame records, with every cache): parse is the container (chunk framing and "
      "CRC-32C), decode the records' geometry, poses and view choices and the view images (counted in the frame "
      "after them), display the drawing of the frame (every hot triangle mapped from its view: homography, set-up, "
      "spans) and the player's band CRC. The least workspace: what the player needs on this board (its plan) with "
      "the client's link buffers and chunk buffer; with every cache: the arena's high-water mark less the "
      "benchmark's 32 KiB chunk buffer; HEAD declares what the encoder computes on the host (64-bit pointers).", "",
      f"Client firmware `vds_fw_client` (the image, model and walkthrough modes and the link): flash {flash:,} bytes "
      f"(.text + .rodata + .data), RAM {ram:,} bytes (.data + .bss + .stack, its {client_ws:,}-byte workspace "
      "included).", "",
      f"**Goals: >= 20 frames/s at 240x180 at 100 MHz — "
      f"{'reached' if all(speed(s, 'client') and 1e8 / speed(s, 'client')[0] >= 20 for s in stream) else 'not reached'}"
      f" in the client's workspace (reached on: {', '.join(names[s] for s in stream if speed(s, 'client') and 1e8 / speed(s, 'client')[0] >= 20) or 'none'}); "
      f"RAM <= 192 KiB — the firmware's RAM is {'within' if ram <= 192 * 1024 else 'over'} it (the build links the client "
      f"into 192 KiB), and {', '.join(fits) if fits else 'none'} of these maps "
      f"{'plays' if len(fits) == 1 else 'play'} in it.** docs/walkthrough.md says "
      "where the instructions and the bytes go."]
open(out, "w").write("\n".join(L) + "\n")
print("\n".join(L))
PY
