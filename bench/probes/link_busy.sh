#!/usr/bin/env bash
# A client that is slow to draw, on a slow line: glmark2's bunny as a
# progressive model (vds encode-mesh, 10 bits) served at 115,200 baud over a
# pty to the host-native client board with a 400,000-byte workspace (it
# holds and draws 22 levels, then reports its workspace full; 4,000,000
# bytes hold all 30, whose last levels are 4 KB chunks of about 2,000
# splits each, long to decode). Run from the
# sanitiser build (preset `host`) the board draws 10-30 times slower than
# natively: a stand-in for a microcontroller whose frames take longer than
# the link's retransmission timeout. Prints, per run, the host's link time,
# goodput, data frames, retransmissions and timeouts (from `vds serve`).
#
# Usage: bench/probes/link_busy.sh [BUILD_DIR] [RUNS] [WORKSPACE]
#   (default build/host, 3, 400000)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-build/host}
RUNS=${2:-3}
WORKSPACE=${3:-400000}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
MODEL=/usr/share/glmark2/models/bunny.obj
for f in "$BUILD/encoder/vds" "$BUILD/firmware_sim/vds_fw_client_host" "$MODEL"; do
  [[ -e "$f" ]] || { echo "link_busy.sh: $f not found (make test builds it; scripts/fetch-data.sh)" >&2; exit 1; }
done
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BUILD/encoder/vds" encode-mesh "$MODEL" --bits 10 -o "$WORK/bunny.vds" > /dev/null
echo "run | link time (s) | goodput | data frames | retransmitted | timeouts"
echo "---:|---:|---:|---:|---:|---:"
for i in $(seq 1 "$RUNS"); do
  echo "link_busy.sh: run $i of $RUNS" >&2
  python3 "$ROOT/scripts/sim.py" --board host --build "$BUILD" --baud 115200 --workspace "$WORKSPACE" \
    --out "$WORK/out" "$WORK/bunny.vds" 2> /dev/null |
    awk -v i="$i" '/^  time /{t=$2; g=$5}
                   /^  frames  /{d=$2; r=$4; to=$6; sub(/^\(/, "", to)}
                   END{printf "%d | %s | %s %% | %s | %s | %s\n", i, t, g, d, r, to}'
done
