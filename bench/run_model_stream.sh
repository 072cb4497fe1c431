#!/usr/bin/env bash
# The textured model stream against what a user would ship (docs/model-mode.md,
# "The model stream"), written to bench/results/model_stream.md and
# model_stream_<name>.png:
#   vds: `vds encode-model` at a range of qualities, each measured as it
#   arrives (--timeline: after every chunk that completes a client frame,
#   the client's picture from VIEWS orbit angles of the client's own model
#   view against the model with its own texture);
#   the download: the model's geometry and texture coordinates as Draco
#   (draco_encoder's defaults) with its texture as WebP (cwebp's default
#   quality, 75) or JPEG (cjpeg -optimize, quality 75), shown once whole,
#   measured at the same cameras on the model's own geometry (Draco's
#   quantisation not applied, no glTF JSON counted: both in its favour);
#   every picture drawn by the client library (the download as a client
#   draws a textured mesh: the same renderer, RGB565); the uncoded texture
#   so drawn (PNG) is the client renderer's ceiling;
#   both over 2 KB/s and 115,200 baud (11,520 bytes/s), link framing not
#   counted for either.
# Also the client's frames of one stream as a contact sheet
# (model_stream_<name>_frames.png), and the largest MIP level each model
# plays at in 128 KiB and 192 KiB of client workspace.
#
# Usage: bench/run_model_stream.sh [BUILD_DIR]   (default build/host-release)
#   MODELS, PLAYER, Z_UP as bench/run_model.sh; QUALITIES; VIEWS=8.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
WORK=${WORK:-$BUILD/model_stream}
RESULTS=${RESULTS:-$ROOT/bench/results}
A=/usr/share/assimp/models
PLAYER=${PLAYER:-major}
mkdir -p "$WORK" "$RESULTS"
/usr/bin/python3 "$ROOT/bench/extract_oa_player.py" "$WORK/oa" "$PLAYER"
MODELS=${MODELS:-"duck:$A/Collada/duck_triangulate.dae truck:$A/glTF/CesiumMilkTruck/CesiumMilkTruck.gltf mrfixit:$A/IQM/mrfixit.iqm $PLAYER:$WORK/oa/models/players/$PLAYER"}
Z_UP=${Z_UP:-}
QUALITIES=${QUALITIES:-0.5 1 2 4}
VIEWS=${VIEWS:-8}
for tool in cjpeg djpeg cwebp dwebp draco_encoder; do
  command -v $tool >/dev/null || { echo "run_model_stream: $tool missing (scripts/setup.sh installs it)" >&2; exit 1; }
done
[ -x "$VDS" ] || { echo "run_model_stream: $VDS missing (make build-release)" >&2; exit 1; }

for entry in $MODELS; do
  name=${entry%%:*}
  model=${entry#*:}
  dir="$WORK/$name"
  rm -rf "$dir"; mkdir -p "$dir/tex"
  up=+y; case " $Z_UP " in *" $name "*) up=+z ;; esac
  echo "run_model_stream: $name: the download (Draco + WebP or JPEG)"
  "$VDS" mesh-colors "$model" --max-res 0 --codec vds --quality 1 --dump-textures "$dir/tex" > /dev/null
  "$VDS" encode-model "$model" -o "$dir/probe.vds" --up $up --dump-obj "$dir/model.obj" -q
  draco_encoder -i "$dir/model.obj" -o "$dir/model.drc" > /dev/null
  drc=$(stat -c %s "$dir/model.drc")
  textures=$(ls "$dir"/tex/texture*.png | wc -l)
  : > "$dir/anchors.csv"
  bytes=$drc; files=""
  for ((i = 0; i < textures; i++)); do
    cwebp -quiet "$dir/tex/texture$i.png" -o "$dir/tex/w.$i.webp"
    dwebp -quiet "$dir/tex/w.$i.webp" -o "$dir/tex/w.$i.png"
    bytes=$((bytes + $(stat -c %s "$dir/tex/w.$i.webp"))); files="$files${files:+;}$dir/tex/w.$i.png"
  done
  echo "draco+webp,75,$bytes,$files" >> "$dir/anchors.csv"
  bytes=$drc; files=""
  for ((i = 0; i < textures; i++)); do
    cjpeg -optimize -quality 75 "$dir/tex/texture$i.ppm" > "$dir/tex/j.$i.jpg"
    djpeg -outfile "$dir/tex/j.$i.ppm" "$dir/tex/j.$i.jpg"
    bytes=$((bytes + $(stat -c %s "$dir/tex/j.$i.jpg"))); files="$files${files:+;}$dir/tex/j.$i.ppm"
  done
  echo "draco+jpeg,75,$bytes,$files" >> "$dir/anchors.csv"
  # The texture uncoded (as the PNG files the benchmark wrote): the client renderer's ceiling.
  bytes=$drc; files=""
  for ((i = 0; i < textures; i++)); do
    bytes=$((bytes + $(stat -c %s "$dir/tex/texture$i.png"))); files="$files${files:+;}$dir/tex/texture$i.png"
  done
  echo "draco+png,lossless,$bytes,$files" >> "$dir/anchors.csv"
  mid=$(echo $QUALITIES | awk '{print $2}')
  for q in $QUALITIES; do
    echo "run_model_stream: $name: vds encode-model --quality $q, as it arrives"
    extra=()
    if [ "$q" = "$mid" ]; then extra=(--anchors "$dir/anchors.csv" --timeline-images "$dir/img"); fi
    "$VDS" encode-model "$model" -o "$dir/q$q.vds" --up $up --quality $q --orbit 0 --timeline "$dir/q$q.csv" --views "$VIEWS" \
      "${extra[@]}" > "$dir/q$q.txt"
  done
  rm -rf "$dir/frames"
  "$VDS" frames "$dir/q$mid.vds" --png "$dir/frames" > "$dir/frames.txt"
  # The finest colours a board of 128 KiB and of 192 KiB shows (the player
  # from byte 7,320, as the host board's link leaves it).
  for kib in 128 192; do
    "$VDS" frames "$dir/q$mid.vds" --workspace $((kib * 1024)) --player-from 7320 --notices > "$dir/ws$kib.txt" 2>&1 || true
  done
done

/usr/bin/python3 "$ROOT/bench/model_stream_report.py" "$WORK" "$RESULTS" "bench/run_model_stream.sh $*" \
  "$QUALITIES" $(for e in $MODELS; do echo "${e%%:*}"; done)
echo "run_model_stream: wrote $RESULTS/model_stream.md"
