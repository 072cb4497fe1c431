#!/usr/bin/env bash
# Accuracy and cost of the client renderer (decoder/src/render*.cpp), written
# to bench/results/render.md and bench/results/render_*.png:
#   - PSNR of the fixed-point renderer against the double-precision reference
#     (encoder/src/ref_render.cpp) on the shared scenes, every texture, depth
#     and output format, and side-by-side PNGs (reference | client | |diff| x 16);
#   - x86-64 instructions per frame and per pixel from callgrind (a proxy);
#   - Cortex-M4: .text of the renderer (arm-none-eabi-g++ -O2), stack use, and,
#     when qemu-system-arm is present, instructions per frame on the QEMU board
#     (mps2-an386, -icount) from the firmware vds_fw_bench_render
#     (firmware_sim/app/bench_render.cpp), plus a bit-exactness check of every
#     frame's CRC-32C against the host;
#   - workspace bytes of typical configurations.
#
# Usage: bench/run_render.sh [BUILD_DIR [CM4_BUILD_DIR]]
#   BUILD_DIR (default build/host-release) must hold bench_render:
#     cmake -S . -B build/host-release -G Ninja -DCMAKE_C_COMPILER=clang \
#       -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release -DVDS_BUILD_FIRMWARE=OFF
#     cmake --build build/host-release -j1 --target bench_render
#   CM4_BUILD_DIR holds the firmware (firmware_sim/vds_fw_bench_render.elf);
#   default BUILD_DIR/cm4 when it has one (host presets build it), else
#   build/cortex-m4:
#     cmake --preset cortex-m4 && cmake --build --preset cortex-m4 --target vds_fw_bench_render
#   The script configures and builds nothing in the tree; the Cortex-M4
#   objects for the size and stack figures are compiled into a temporary
#   directory.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
BENCH="$BUILD/bench/bench_render"
CM4=${2:-}
if [[ -z "$CM4" ]]; then
  if [[ -f "$BUILD/cm4/firmware_sim/vds_fw_bench_render.elf" ]]; then CM4="$BUILD/cm4"; else CM4="$ROOT/build/cortex-m4"; fi
fi
case "$CM4" in /*) ;; *) CM4="$ROOT/$CM4" ;; esac
ELF="$CM4/firmware_sim/vds_fw_bench_render.elf"
OUT="$ROOT/bench/results/render.md"
FRAMES=4  # frames per callgrind run
M4_FRAMES=3

[[ -x "$BENCH" ]] || { echo "run_render.sh: $BENCH not found; build it first (see the header of this script)" >&2; exit 1; }
command -v valgrind >/dev/null || { echo "run_render.sh: valgrind is required" >&2; exit 1; }

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# 1. Accuracy and the PNGs.
echo "== accuracy"
"$BENCH" accuracy "$ROOT/bench/results" | tee "$WORK/accuracy.md"

# 2. The cases measured on both targets (the list: kCases in bench/src/render.cpp),
# as $WORK/render_case<i>.bin; cases.txt: label scene texture output depth band cache filter.
"$BENCH" cases "$WORK" "$M4_FRAMES" | tee "$WORK/case_list.txt" | cut -d' ' -f2- >"$WORK/cases.txt"

# 3. x86-64: callgrind counts inside the measured render calls.
echo "== callgrind ($FRAMES frames per case)"
i=0
while read -r label scene tex out depth band cache filter; do
  valgrind --tool=callgrind --callgrind-out-file="$WORK/cg.$i" --toggle-collect='*measured_render*' \
    "$BENCH" frames "$WORK/render_case$i.bin" "$FRAMES" >"$WORK/host.$i" 2>"$WORK/vg.$i"
  ir=$(awk '/^totals:/ {print $2}' "$WORK/cg.$i")
  echo "$label $ir $FRAMES $(cat "$WORK/host.$i")" | tee -a "$WORK/host.txt"
  i=$((i + 1))
done <"$WORK/cases.txt"

# 4. Cortex-M4: code size, stack, and the QEMU run of the same case files.
ARM_FLAGS=(-std=c++20 -mcpu=cortex-m4 -mthumb -mfloat-abi=soft -O2 -ffreestanding -fno-exceptions -fno-rtti
  -fno-threadsafe-statics -ffunction-sections -fdata-sections -fstack-usage -I"$ROOT/decoder/include")
HAVE_ARM=0
HAVE_QEMU=0
if command -v arm-none-eabi-g++ >/dev/null; then
  HAVE_ARM=1
  echo "== arm-none-eabi-g++ -O2"
  mkdir -p "$WORK/m4" "$WORK/m4min"
  for f in render render_setup render_span render_clip render_camera homography fixed crc32c status; do
    arm-none-eabi-g++ "${ARM_FLAGS[@]}" -c "$ROOT/decoder/src/$f.cpp" -o "$WORK/m4/$f.o"
  done
  for f in render render_setup render_span render_clip render_camera; do
    arm-none-eabi-g++ "${ARM_FLAGS[@]}" -DVDS_CONFIG_RENDER_TEXTURE_FORMATS=1 -DVDS_CONFIG_RENDER_OUTPUT_FORMATS=1 \
      -DVDS_CONFIG_RENDER_DEPTH_FORMATS=1 -c "$ROOT/decoder/src/$f.cpp" -o "$WORK/m4min/$f.o"
  done
  (cd "$WORK/m4" && arm-none-eabi-size render.o render_setup.o render_span.o render_clip.o render_camera.o homography.o) | tee "$WORK/size.txt"
  (cd "$WORK/m4min" && arm-none-eabi-size render.o render_setup.o render_span.o render_clip.o render_camera.o) | tee "$WORK/size_min.txt"
  cat "$WORK"/m4/render*.su "$WORK"/m4/homography.su >"$WORK/stack.txt"
  # Symbols the renderer objects take from outside themselves.
  arm-none-eabi-nm -u "$WORK"/m4/render*.o "$WORK/m4/homography.o" | awk 'NF {print $NF}' | grep -v ':$' | sort -u >"$WORK/undef_all.txt"
  arm-none-eabi-nm --defined-only "$WORK"/m4/render*.o "$WORK/m4/homography.o" | awk 'NF == 3 {print $3}' | sort -u >"$WORK/defined.txt"
  comm -23 "$WORK/undef_all.txt" "$WORK/defined.txt" | arm-none-eabi-c++filt >"$WORK/undef.txt"
  if command -v qemu-system-arm >/dev/null && [[ -f "$ELF" ]]; then
    HAVE_QEMU=1
    echo "== QEMU mps2-an386 -icount shift=0 ($ELF)"
    # The firmware reads render_case<i>.bin from its working directory
    # through semihosting; its console output arrives on QEMU's stderr.
    (cd "$WORK" && timeout 1200 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial null \
      -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF") 2>&1 | tee "$WORK/m4.txt"
  else
    echo "run_render.sh: no QEMU or no $ELF (see the header of this script): Cortex-M4 counts skipped" >&2
  fi
fi

# 5. Workspace sizes.
"$BENCH" ram >"$WORK/ram.txt"

# 6. The report.
BUILD_ARG="${1:-build/host-release}${2:+ $2}"
ELF_REL=$(realpath --relative-to="$ROOT" "$ELF")
export WORK OUT FRAMES HAVE_ARM HAVE_QEMU BENCH BUILD_ARG ELF_REL
export CPU="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
export HOSTCXX="$(clang++ --version | head -1)"
export ARMCXX="$( (arm-none-eabi-g++ --version 2>/dev/null || echo none) | head -1)"
export VG="$(valgrind --version)"
export QEMU="$( (qemu-system-arm --version 2>/dev/null || echo none) | head -1)"
export BUILD_TYPE="$(grep -m1 '^CMAKE_BUILD_TYPE:' "$BUILD/CMakeCache.txt" 2>/dev/null | cut -d= -f2 || true)"
python3 "$ROOT/bench/render_report.py"
echo "wrote $OUT"
