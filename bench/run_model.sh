#!/usr/bin/env bash
# The model mode's colour codec on textured models (docs/model-mode.md,
# "Figures"), written to bench/results/model.md, model_rd.png (rendered PSNR
# against bytes per model) and model_<name>_sheet.png (view 0: reference,
# mesh colors uncoded, the codec at each quality, then the anchors):
#   the thesis's measure: PSNR of Y', Cb, Cr of every MIP level against its
#   compression ratio (`vds mesh-colors --csv`);
#   rendered views: 24 cameras round the model, its own texture through its
#   UV map the reference; the mesh colors codecs, the improved one (vds
#   mode) and the thesis's (paper mode), each header + level 0, against
#   the model's texture coded by cjpeg -optimize, cwebp and avifenc at a
#   range of qualities, each drawn on the same geometry; BD-rate of the mesh
#   colors codec against each anchor.
#
# Usage: bench/run_model.sh [BUILD_DIR]   (default build/host-release)
#   MODELS (default: the duck, the milk truck, mrfixit, an OpenArena player: PLAYER=major; Sydney, the jeep);
#   WORK (default BUILD_DIR/model);
#   VIEWS=24 SIZE=256 SUPERSAMPLE=3; QUALITIES (mesh colors quality factors); MAX_RES (face resolution cap, 2^r);
#   MC_ARGS (more `vds mesh-colors` options for both passes, e.g. --full-chroma).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
WORK=${WORK:-$BUILD/model}
RESULTS=${RESULTS:-$ROOT/bench/results}
A=/usr/share/assimp/models
mkdir -p "$WORK"
# An OpenArena player (openarena-data's pak2-players.pk3), taken out of the
# archive with its skins and textures: its folder is the whole player, legs,
# torso and head joined at their tags (vds reads ARCHIVE.pk3:FOLDER as well).
PLAYER=${PLAYER:-major}
/usr/bin/python3 "$ROOT/bench/extract_oa_player.py" "$WORK/oa" "$PLAYER"
# Then two more of assimp-testmodels: Quake II's Sydney (MD2, a BMP skin) and
# MilkShape's jeep (MS3D, a texture reused across many faces).
MODELS=${MODELS:-"duck:$A/Collada/duck_triangulate.dae truck:$A/glTF/CesiumMilkTruck/CesiumMilkTruck.gltf mrfixit:$A/IQM/mrfixit.iqm $PLAYER:$WORK/oa/models/players/$PLAYER sydney:$A/MD2/sydney.md2 jeep:$A/MS3D/jeep1.ms3d"}
# Models whose up axis is +z; assimp gives most formats +y (an MD3's Z up too).
Z_UP=${Z_UP:-}
VIEWS=${VIEWS:-24}
SIZE=${SIZE:-256}
SS=${SUPERSAMPLE:-3}
QUALITIES=${QUALITIES:-0.125 0.25 0.5 1 2 4 8 16}
MC_ARGS=${MC_ARGS:-}
MAX_RES=${MAX_RES:-8}   # R <= 256: the truck's few larger faces change its figures by under 0.2 dB and double the time
for tool in cjpeg cwebp dwebp avifenc avifdec; do
  command -v $tool >/dev/null || { echo "run_model: $tool missing (scripts/setup.sh installs it)" >&2; exit 1; }
done
[ -x "$VDS" ] || { echo "run_model: $VDS missing (make build-release)" >&2; exit 1; }
mkdir -p "$WORK" "$RESULTS"

for entry in $MODELS; do
  name=${entry%%:*}
  model=${entry#*:}
  dir="$WORK/$name"
  rm -rf "$dir"; mkdir -p "$dir/tex"
  echo "run_model: $name: mesh colors and the thesis's measure"
  "$VDS" mesh-colors "$model" $MC_ARGS --max-res "$MAX_RES" --quality $QUALITIES --csv "$dir/thesis.csv" --dump-textures "$dir/tex" > "$dir/thesis.txt"
  textures=$(ls "$dir"/tex/texture*.png | wc -l)
  echo "run_model: $name: $textures texture(s) through cjpeg, cwebp, avifenc"
  : > "$dir/anchors.csv"
  for q in 10 20 30 40 50 60 70 80 90 95; do
    bytes=0; files=""
    for ((i = 0; i < textures; i++)); do
      cjpeg -optimize -quality $q "$dir/tex/texture$i.ppm" > "$dir/tex/j$q.$i.jpg"
      bytes=$((bytes + $(stat -c %s "$dir/tex/j$q.$i.jpg"))); files="$files${files:+;}$dir/tex/j$q.$i.jpg"
    done
    echo "jpeg,$q,$bytes,$files" >> "$dir/anchors.csv"
    bytes=0; files=""
    for ((i = 0; i < textures; i++)); do
      cwebp -quiet -q $q "$dir/tex/texture$i.png" -o "$dir/tex/w$q.$i.webp"
      dwebp -quiet "$dir/tex/w$q.$i.webp" -o "$dir/tex/w$q.$i.png"
      bytes=$((bytes + $(stat -c %s "$dir/tex/w$q.$i.webp"))); files="$files${files:+;}$dir/tex/w$q.$i.png"
    done
    echo "webp,$q,$bytes,$files" >> "$dir/anchors.csv"
  done
  for aq in 10 20 30 40 50; do
    bytes=0; files=""
    for ((i = 0; i < textures; i++)); do
      avifenc -s 6 --min $aq --max $aq "$dir/tex/texture$i.png" "$dir/tex/a$aq.$i.avif" > /dev/null
      avifdec "$dir/tex/a$aq.$i.avif" "$dir/tex/a$aq.$i.png" > /dev/null
      bytes=$((bytes + $(stat -c %s "$dir/tex/a$aq.$i.avif"))); files="$files${files:+;}$dir/tex/a$aq.$i.png"
    done
    echo "avif,$aq,$bytes,$files" >> "$dir/anchors.csv"
  done
  echo "run_model: $name: $VIEWS rendered views"
  up=y; case " $Z_UP " in *" $name "*) up=z ;; esac
  "$VDS" mesh-colors "$model" $MC_ARGS --max-res "$MAX_RES" --up $up --quality $QUALITIES --views "$VIEWS" --size "$SIZE" --supersample "$SS" \
    --anchors "$dir/anchors.csv" --rendered-csv "$dir/rendered.csv" --sheet "$RESULTS/model_${name}_sheet.png" > "$dir/rendered.txt"
done

/usr/bin/python3 "$ROOT/bench/model_report.py" "$WORK" "$RESULTS" "bench/run_model.sh $*" $(for e in $MODELS; do echo "${e%%:*}=${e#*:}"; done)
echo "run_model: wrote $RESULTS/model.md"
