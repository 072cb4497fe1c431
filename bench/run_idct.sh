#!/usr/bin/env bash
# Accuracy and cost of the client IDCT (decoder/src/idct.cpp), written to
# bench/results/idct.md:
#   - IEEE 1180-1990 figures of all six runs, from the GoogleTest procedure
#     (tests/conformance/ieee1180_test.cpp) run by vds_tests;
#   - x86-64 instructions per call from callgrind on bench_idct;
#   - Cortex-M4: .text of idct.cpp (arm-none-eabi-g++ -O2) and, when
#     qemu-system-arm is present, instructions per call under QEMU mps2-an386
#     with -icount (firmware_sim/app/bench_idct.cpp on the QEMU board), plus a
#     bit-exactness check of every case's output checksum against the host.
#
# Usage: bench/run_idct.sh [BUILD_DIR]        (default build/host-release)
#   The build dir must already hold bench_idct, vds_tests and the Cortex-M4
#   sub-build (cm4/firmware_sim/vds_fw_bench_idct.elf):
#     cmake --preset host-release && cmake --build --preset host-release
#   VDS_TESTS=path/to/vds_tests takes the IEEE 1180 figures from another build
#   (e.g. a sanitizer build). The script configures and builds nothing in the
#   tree; the Cortex-M4 objects are compiled into a temporary directory.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
BENCH="$BUILD/bench/bench_idct"
TESTS=${VDS_TESTS:-$BUILD/tests/vds_tests}
OUT="$ROOT/bench/results/idct.md"
N=4000  # blocks per case (same sets on host and Cortex-M4)

for f in "$BENCH" "$TESTS"; do
  if [[ ! -x "$f" ]]; then
    echo "run_idct.sh: $f not found; build it first (see the header of this script)" >&2
    exit 1
  fi
done
command -v valgrind >/dev/null || { echo "run_idct.sh: valgrind is required" >&2; exit 1; }

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# 1. IEEE 1180-1990.
echo "== IEEE 1180 ($TESTS)"
set +e
"$TESTS" --gtest_filter='Ieee1180.*' >"$WORK/ieee.txt" 2>&1
IEEE_RC=$?
set -e
grep '^IEEE1180 ' "$WORK/ieee.txt" | tee "$WORK/ieee_lines.txt"
[[ $(wc -l <"$WORK/ieee_lines.txt") -eq 6 ]] || { echo "run_idct.sh: expected 6 IEEE1180 lines" >&2; cat "$WORK/ieee.txt" >&2; exit 1; }

# 2. x86-64 instructions per call (callgrind, only inside vds::idct8x8*).
echo "== callgrind ($BENCH, $N blocks per case)"
"$BENCH" --list >"$WORK/cases.txt"
while read -r name entry set; do
  valgrind --tool=callgrind --callgrind-out-file="$WORK/cg.$name" --toggle-collect='vds::idct8x8*' \
    "$BENCH" "$name" "$N" >"$WORK/host.$name" 2>"$WORK/vg.$name"
  ir=$(awk '/^totals:/ {print $2}' "$WORK/cg.$name")
  echo "$name $entry $set $ir $(cat "$WORK/host.$name")" | tee -a "$WORK/host.txt"
done <"$WORK/cases.txt"

# 3. Cortex-M4: .text of the client object, then the QEMU run.
ARM_FLAGS=(-std=c++20 -mcpu=cortex-m4 -mthumb -mfloat-abi=soft -O2 -ffreestanding -fno-exceptions -fno-rtti
  -fno-threadsafe-statics -ffunction-sections -fdata-sections -I"$ROOT/decoder/include")
HAVE_ARM=0
HAVE_QEMU=0
if command -v arm-none-eabi-g++ >/dev/null; then
  HAVE_ARM=1
  echo "== arm-none-eabi-g++ -O2 idct.cpp"
  arm-none-eabi-g++ "${ARM_FLAGS[@]}" -c "$ROOT/decoder/src/idct.cpp" -o "$WORK/idct.o"
  (cd "$WORK" && arm-none-eabi-size idct.o) | tee "$WORK/size.txt"
  arm-none-eabi-nm -S --size-sort -C "$WORK/idct.o" | tee "$WORK/nm.txt"
  arm-none-eabi-nm -u "$WORK/idct.o" >"$WORK/undef.txt"
  ELF="$BUILD/cm4/firmware_sim/vds_fw_bench_idct.elf"
  if command -v qemu-system-arm >/dev/null && [[ -f "$ELF" ]]; then
    HAVE_QEMU=1
    echo "== QEMU mps2-an386 -icount shift=0 ($ELF)"
    for s in dense sparse dc; do "$BENCH" --dump "$s" "$N" "$WORK/idct_$s.bin"; done
    # The firmware reads the dumps from its working directory through
    # semihosting; its console output arrives on QEMU's stderr.
    (cd "$WORK" && timeout 600 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
      -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF") 2>&1 | tee "$WORK/m4.txt"
  else
    echo "run_idct.sh: no QEMU or no $ELF (build with the host-release preset): Cortex-M4 counts skipped" >&2
  fi
fi

# 4. The report.
export WORK OUT N IEEE_RC HAVE_ARM HAVE_QEMU TESTS BENCH
export CPU="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
export HOSTCXX="$(clang++ --version | head -1)"
export ARMCXX="$( (arm-none-eabi-g++ --version 2>/dev/null || echo none) | head -1)"
export VG="$(valgrind --version)"
export QEMU="$( (qemu-system-arm --version 2>/dev/null || echo none) | head -1)"
export BUILD_TYPE="$(grep -m1 '^CMAKE_BUILD_TYPE:' "$BUILD/CMakeCache.txt" 2>/dev/null | cut -d= -f2 || true)"
export SANITIZE="$(grep -m1 '^VDS_SANITIZE:' "$(dirname "$(dirname "$TESTS")")/CMakeCache.txt" 2>/dev/null | cut -d= -f2 || true)"
python3 - <<'EOF'
import os, re, datetime, platform

work = os.environ["WORK"]
N = int(os.environ["N"])
def read(name):
    p = os.path.join(work, name)
    return open(p).read() if os.path.exists(p) else ""

limits = dict(peak=1, pmse=0.06, omse=0.02, pme=0.015, ome=0.0015)
runs = []
for line in read("ieee_lines.txt").splitlines():
    kv = dict(re.findall(r"(\w+)=([-+0-9.]+)", line))
    runs.append(kv)

def ok(kv):
    return (int(kv["peak"]) <= limits["peak"] and float(kv["pmse"]) <= limits["pmse"]
            and float(kv["omse"]) <= limits["omse"] and float(kv["pme"]) <= limits["pme"]
            and abs(float(kv["ome"])) <= limits["ome"])

host = {}
for line in read("host.txt").splitlines():
    name, entry, bset, ir, rest = line.split(" ", 4)
    kv = dict(re.findall(r"(\w+)=([^ ]+)", rest))
    host[name] = dict(entry=entry, set=bset, ir=int(ir), nz=kv["nonzero_per_block"], checksum=kv["checksum"])

m4 = {}
calib = ""
for line in read("m4.txt").splitlines():
    kv = dict(re.findall(r"(\w+)=([^ ]+)", line))
    if "case" in kv:
        m4[kv["case"]] = kv
    elif "resolution" in kv:
        calib = f"board counter from the 25 MHz timer, {kv['resolution']} instructions per tick"

o = []
o.append("# Client IDCT: IEEE 1180-1990 accuracy and cost\n")
o.append(f"Produced by `bench/run_idct.sh` on {datetime.date.today().isoformat()}. "
         "Algorithm and fixed-point design: `docs/idct.md`.\n")
o.append("## Machine and tools\n")
o.append(f"- host: {os.environ['CPU']}, {platform.machine()}, Linux {platform.release()}")
o.append(f"- host compiler: {os.environ['HOSTCXX']}, build type {os.environ['BUILD_TYPE'] or '?'}")
o.append(f"- IEEE 1180 figures from `{os.path.relpath(os.environ['TESTS'])}` "
         f"(VDS_SANITIZE={os.environ['SANITIZE'] or '?'})")
o.append(f"- {os.environ['VG']} (callgrind, `--toggle-collect='vds::idct8x8*'`)")
o.append(f"- Cortex-M4 compiler: {os.environ['ARMCXX']}")
o.append(f"- QEMU: {os.environ['QEMU']}\n")

o.append("## IEEE 1180-1990 (10,000 blocks per run)\n")
o.append("Input block from the standard's generator → double forward DCT → round → clip to "
         "[-2048, 2047] → (a) double IDCT, rounded, clipped to [-256, 255]; (b) `vds::idct8x8`, "
         "clipped to [-256, 255]. Figures are (b) − (a).\n")
o.append("| range | sign | peak error | worst pixel MSE | overall MSE | worst pixel \\|mean error\\| | overall mean error | result |")
o.append("|---|---|---|---|---|---|---|---|")
o.append(f"| **limit** | | ≤ {limits['peak']} | ≤ {limits['pmse']} | ≤ {limits['omse']} | ≤ {limits['pme']} | "
         f"\\|·\\| ≤ {limits['ome']} | |")
for kv in runs:
    rng = f"L={kv['L']}, H={kv['H']}"
    sign = "+" if kv["sign"].startswith("+") else "− (negated)"
    o.append(f"| {rng} | {sign} | {kv['peak']} | {float(kv['pmse']):.4f} | {float(kv['omse']):.4f} | "
             f"{float(kv['pme']):.4f} | {float(kv['ome']):+.5f} | {'pass' if ok(kv) else '**FAIL**'} |")
o.append("")
o.append(f"All-zero input gives all-zero output: checked by `Ieee1180.ZeroInZeroOut`. "
         f"GoogleTest exit status of the Ieee1180 suite: {os.environ['IEEE_RC']} "
         f"({'all passed' if os.environ['IEEE_RC'] == '0' else 'FAILURES'}).\n")

o.append(f"## Instructions per 8×8 block ({N} blocks per case)\n")
o.append("Block sets (`bench/src/idct.cpp`): *dense* = textured intra blocks quantised at about JPEG "
         "quality 90; *sparse* = smooth inter residuals at about quality 50 with 1–8 AC coefficients; "
         "*dc* = DC only. x86-64 counts are callgrind's Ir inside the entry point (host clang -O3). "
         "Cortex-M4 counts are executed instructions (not cycles) of the arm-none-eabi-g++ -O2 build "
         "on the QEMU board (`firmware_sim/app/bench_idct.cpp`), timer reads and call overhead "
         "of the driver loop subtracted"
         + (f" (calibration: {calib})" if calib else "") + ". The checksum column compares every "
         "byte each case wrote on x86-64 and on Cortex-M4.\n")
o.append("| case | entry point | nonzero coef/block | x86-64 instr/block | Cortex-M4 instr/block | M4 = x86-64 output |")
o.append("|---|---|---|---|---|---|")
all_match = True
for name, h in host.items():
    per = h["ir"] / N
    m = m4.get(name)
    m4s = m["instr_per_call"] if m else "n/a"
    if m:
        match = "yes" if m["checksum"] == h["checksum"] else "**NO**"
        all_match &= m["checksum"] == h["checksum"]
    else:
        match = "n/a"
    o.append(f"| {name} | `{h['entry']}` | {float(h['nz']):.2f} | {per:.1f} | {m4s} | {match} |")
o.append("")
if m4:
    o.append(f"Bit-exact across targets: {'yes, every case' if all_match else '**NO**'}.\n")

if os.environ["HAVE_ARM"] == "1":
    o.append("## Cortex-M4 code size (`arm-none-eabi-g++ -O2`, idct.cpp alone)\n")
    o.append("```")
    o.append(read("size.txt").rstrip())
    o.append("```\n")
    o.append("| symbol | bytes |")
    o.append("|---|---|")
    for line in read("nm.txt").splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in "tTrR":
            o.append(f"| `{parts[3]}` | {int(parts[1], 16)} |")
    undef = read("undef.txt").split()
    o.append("")
    o.append("Undefined symbols of the object: " + (", ".join(u for u in undef if u != "U") or "none") +
             ". Stack: 256 bytes of workspace (64 × int32) per call.\n")

o.append("## Reproduce\n")
o.append("```sh")
o.append("cmake --preset host-release && cmake --build --preset host-release")
o.append("bench/run_idct.sh build/host-release")
o.append("# pieces by hand:")
o.append("build/host-release/tests/vds_tests --gtest_filter='Ieee1180.*'")
o.append(f"valgrind --tool=callgrind --toggle-collect='vds::idct8x8*' build/host-release/bench/bench_idct store-dense {N}")
o.append("build/host-release/bench/bench_idct            # wall-clock ns/block table")
o.append("```")
o.append("The QEMU command line is in `bench/run_idct.sh`, step 3.")
open(os.environ["OUT"], "w").write("\n".join(o) + "\n")
print("wrote", os.environ["OUT"])
EOF
[[ $IEEE_RC -eq 0 ]] || { echo "run_idct.sh: IEEE 1180 tests failed" >&2; exit 1; }
