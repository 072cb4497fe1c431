#!/usr/bin/env bash
# Installs the sample content from Debian packages (never committed):
#   glmark2-data            Stanford bunny, horse, cat (OBJ) and textures
#   openarena-081-maps      Quake III BSP maps (oa_dm4, ...)
#   openarena-081-textures  1,600+ JPG/TGA textures and lightmapped surfaces
#   openarena-081-misc      further textures the maps use
#   openarena-data          the game's shader scripts (pak0), later maps and
#                           fixes (pak6-patch085), player models
#   trigger-rally-data      96 terrain maps (heightmap, colour map, scales)
#                           in data.zip, read in place
#   assimp-testmodels       textured models in many formats (the duck, the
#                           milk truck, mrfixit, ...) for the model mode
# and prints where each lives. Idempotent.
set -euo pipefail

PACKAGES=(glmark2-data openarena-081-maps openarena-081-textures openarena-081-misc openarena-data trigger-rally-data assimp-testmodels)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "fetch-data: installing ${missing[*]} (about 480 MB download)"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

GLMARK2=/usr/share/glmark2
OPENARENA=/usr/share/games/openarena/baseoa
TRIGGER=/usr/share/games/trigger-rally/data.zip
ASSIMP_MODELS=/usr/share/assimp/models
for f in "$TRIGGER" "$GLMARK2/models/bunny.obj" "$GLMARK2/models/horse.3ds" "$OPENARENA/pak1-maps.pk3" "$OPENARENA/pak4-textures.pk3" "$OPENARENA/pak0.pk3" "$ASSIMP_MODELS/Collada/duck_triangulate.dae"; do
  [ -e "$f" ] || echo "fetch-data: note: $f not found" >&2
done
echo "fetch-data: glmark2 models:   $GLMARK2/models ($(ls "$GLMARK2/models" 2>/dev/null | wc -l) files)"
echo "fetch-data: glmark2 textures: $GLMARK2/textures ($(ls "$GLMARK2/textures" 2>/dev/null | wc -l) files)"
echo "fetch-data: OpenArena data:   $OPENARENA ($(ls "$OPENARENA" 2>/dev/null | wc -l) entries)"
echo "fetch-data: Trigger Rally maps: $TRIGGER"
