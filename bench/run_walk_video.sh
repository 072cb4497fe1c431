#!/usr/bin/env bash
# The video codecs a user would otherwise pick for a walkthrough, on the
# ground truth `vds render` draws, written to bench/results/walk_anchors.md
# (tables, commands), walk_anchors.json (every point), walk_anchors_rd.png
# (rate-distortion) and walk_<map>_tour.jpg (each path's contact sheet):
#   1. per map: `vds path MAP` (a 600-frame tour through its spawn points) and
#      `vds render` (240x180, 20 frames/s, 2x2 supersampling): scene
#      statistics and render time;
#   2. x264 (-preset veryslow -tune animation, 2-pass), x265 (-preset
#      veryslow, 2-pass), SVT-AV1 (libsvtav1 preset SVT_PRESET, one pass:
#      ffmpeg 5.1's wrapper offers no second), libaom-av1 (-cpu-used
#      AOM_CPU, 2-pass) at 8, 16 and 32 kbit/s and a CRF sweep, all through
#      Debian's ffmpeg; Motion-JPEG (cjpeg -optimize -baseline, 4:2:0) down
#      to quality 1, its floor;
#   3. bitrate = bytes of the elementary stream (H.264/HEVC Annex B with the
#      encoders' SEI banners removed, AV1 OBUs, JPEGs without their JFIF
#      APP0) x 8 / duration; distortion = PSNR over R, G, B pooled over all
#      frames against the ground truth, luma PSNR and SSIM (BT.601 luma,
#      11x11 Gaussian window) as second measures; each codec's PSNR at 8, 16
#      and 32 kbit/s read off its points (linear in log-rate between the two
#      nearest, never extrapolated);
#   4. what a client must hold (walk_visibility.md, bench/walk_visibility.py):
#      triangles visible per frame, first seen, and hot within a window,
#      from the ground truth's visibility buffers.
#
# Usage: bench/run_walk_video.sh [BUILD_DIR]     (default build/host-release)
#   MAPS="oa_dm4 oa_dm5 oa_rpg3dm2"  the maps;  FRAMES=600  the tour's length;
#   SVT_PRESET=1, AOM_CPU=2  the AV1 encoders' speed;  QUICK=1  one rate and
#   one CRF per codec (for trying changes). Ground truth and encodes are
#   kept in WORK (default BUILD_DIR/walk); results go to RESULTS (default
#   bench/results).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
[ -x "$VDS" ] || { echo "run_walk_video: $VDS not built (cmake --build --preset host-release)" >&2; exit 1; }
# Debian's Python: numpy, matplotlib and PIL come from its packages (scripts/setup.sh).
PY=/usr/bin/python3
for tool in ffmpeg cjpeg djpeg $PY; do
  command -v "$tool" >/dev/null || { echo "run_walk_video: $tool missing (scripts/setup.sh installs it)" >&2; exit 1; }
done
WORK=${WORK:-$BUILD/walk}
RESULTS=${RESULTS:-$ROOT/bench/results}
mkdir -p "$WORK" "$RESULTS"
$PY "$ROOT/bench/walk_anchors.py" --vds "$VDS" --work "$WORK" --results "$RESULTS" \
  --maps ${MAPS:-oa_dm4 oa_dm5 oa_rpg3dm2} --frames "${FRAMES:-600}" --svt-preset "${SVT_PRESET:-1}" \
  --aom-cpu "${AOM_CPU:-2}" ${QUICK:+--quick}
MAPS_LIST=${MAPS:-oa_dm4 oa_dm5 oa_rpg3dm2}
$PY "$ROOT/bench/walk_visibility.py" --work "$WORK" --results "$RESULTS" --vds "$VDS" --maps $MAPS_LIST
