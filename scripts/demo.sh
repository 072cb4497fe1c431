#!/usr/bin/env bash
# The demo: builds are done by `make demo`; this encodes a small stream from
# the sample data, reads it back with the client's parser (`vds info`), and
# writes a short report to out/demo/report.md.
set -euo pipefail
BUILD=${1:-build/host-release}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT="$ROOT/out/demo"
VDS="$ROOT/$BUILD/encoder/vds"
mkdir -p "$OUT"

TEX=$(ls /usr/share/glmark2/textures/*.jpg 2>/dev/null | head -n 1 || true)
if [ -z "$TEX" ]; then
  echo "demo: no glmark2 texture found; run scripts/fetch-data.sh" >&2
  exit 1
fi

echo "demo: packing $TEX into a stream"
"$VDS" pack -o "$OUT/demo.vds" --mode images --size 240x180 --max-chunk 262144 \
  --chunk "JPEG=$TEX" --meta "source=$(basename "$TEX") (glmark2-data)" --meta "title=vds demo stream"
"$VDS" info "$OUT/demo.vds" | tee "$OUT/info.txt"

echo "demo: Cortex-M4 size of the client parts"
SIZE_TABLE=$(python3 "$ROOT/tests/tools/check_freestanding.py" \
  --cxx arm-none-eabi-g++ --nm arm-none-eabi-nm --size arm-none-eabi-size --out "$OUT/linkcheck" \
  --lib "decoder=$ROOT/$BUILD/cm4/decoder/libvds_decoder.a" \
  --lib "transport_core=$ROOT/$BUILD/cm4/transport/libvds_transport_core.a")
echo "$SIZE_TABLE"

echo "demo: client self-test on the host board and on the Cortex-M4 board (QEMU mps2-an386)"
BOARDS=$(python3 "$ROOT/tests/tools/compare_boards.py" --host "$ROOT/$BUILD/firmware_sim/vds_fw_selftest_host" \
  --qemu qemu-system-arm --elf "$ROOT/$BUILD/cm4/firmware_sim/vds_fw_selftest.elf")
echo "$BOARDS" | grep -E '^(check|count|info|boards)' | sort -u

{
  echo "# vds demo report"
  echo
  echo "Stream: \`out/demo/demo.vds\`, $(stat -c %s "$OUT/demo.vds") bytes, from \`$TEX\`."
  echo
  echo '```'
  cat "$OUT/info.txt"
  echo '```'
  echo
  echo '```'
  echo "$SIZE_TABLE"
  echo '```'
  echo
  echo "Client self-test, host board vs Cortex-M4 board under QEMU (\`-icount shift=0\`):"
  echo
  echo '```'
  echo "$BOARDS" | grep -E '^(check|count|info|boards)' | sort -u
  echo '```'
} > "$OUT/report.md"
echo "demo: report written to out/demo/report.md"
