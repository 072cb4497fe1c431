#!/usr/bin/env bash
# The shape a walkthrough client draws its views onto, against the scene:
# depth from every 10th camera of each map's tour at several decimation
# tolerances (bench/src/shape.cpp). Writes bench/results/walk_shape.md.
#
# Usage: bench/run_walk_shape.sh [BUILD_DIR]   (default build/host-release)
#   MAPS="oa_dm4 oa_dm5 oa_rpg3dm2"; WORK (default BUILD_DIR/walk): the tours of bench/run_walk_video.sh.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
WORK=${WORK:-$BUILD/walk}
BIN="$BUILD/bench/bench_shape"
OUT="$ROOT/bench/results/walk_shape.md"
TOLERANCES="0 0.03125 0.0625 0.125"
{
  echo "# The walkthrough's shape against the scene"
  echo
  echo "Produced by \`bench/run_walk_shape.sh\` (\`bench_shape MAP TOUR 10 $TOLERANCES\`) on $(date -u +%Y-%m-%d): each map's 600-frame tour (\`walk_anchors.md\`), every 10th camera, 240x180, one sample a pixel. Per pixel the scene covers: *empty* where the shape shows nothing, *through* where the shape's surface lies more than the tolerance plus 1 % of the depth behind the scene's (a crack or a collapsed part it sees past), *in front* as far the other way, else *within*. Tolerance 0: the merged shape alone (no decimation). The decimation takes curved patches and models only (docs/walkthrough.md, \"Fewer triangles\")."
  for map in ${MAPS:-oa_dm4 oa_dm5 oa_rpg3dm2}; do
    [[ -f "$WORK/$map/tour.txt" ]] || { echo "run_walk_shape.sh: $WORK/$map/tour.txt missing (bench/run_walk_video.sh)" >&2; exit 1; }
    echo
    echo "## $map"
    echo
    # shellcheck disable=SC2086
    "$BIN" "$map" "$WORK/$map/tour.txt" 10 $TOLERANCES
  done
} >"$OUT.tmp"
mv "$OUT.tmp" "$OUT"
echo "wrote $OUT"
