#!/usr/bin/env bash
# Link benchmark: goodput and framing overhead in simulated time
# (bench_link), and the client's link RAM from the Cortex-M4 build.
# Writes bench/results/link.md. Usage: bench/run_link.sh [MiB per row, default 8]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build/host-release}
MIB=${1:-8}
OUT=$ROOT/bench/results/link.md
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=Release -DVDS_BUILD_FIRMWARE=OFF >/dev/null
cmake --build "$BUILD" -j1 --target bench_link >/dev/null

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

{
  echo "# Link benchmark"
  echo
  REL=${BUILD#"$ROOT"/}
  echo "Produced by \`BUILD=$REL bench/run_link.sh $MIB\` (build: \`cmake -S . -B $REL -G Ninja"
  echo "-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release -DVDS_BUILD_FIRMWARE=OFF\`,"
  echo "then \`$REL/bench/bench_link $MIB\`; RAM from \`arm-none-eabi-g++ $ARMFLAGS\`"
  echo "on \`bench/m4/link_ram.cpp\`, sizes read with \`arm-none-eabi-nm -S\`). Date: $(date -u +%Y-%m-%d)."
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
  echo "reliable receive channel and 8 in-flight frame records per reliable send channel."
  echo
  echo "Largest stack frames of the core (\`-fstack-usage\`, bytes):"
  echo
  echo '```'
  echo "$STACK" | sed "s|$ROOT/||"
  echo '```'
} > "$OUT"
echo "wrote $OUT"
