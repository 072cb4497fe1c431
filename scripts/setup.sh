#!/usr/bin/env bash
# Installs every Debian package vds needs to build, test and run its demo.
# Idempotent: packages already present are not touched, and apt is only
# consulted when something is missing.
set -euo pipefail

PACKAGES=(
  # host build
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev
  # client build: Cortex-M toolchain, C library and the emulated board
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  qemu-system-arm
  # host libraries
  libgtest-dev libgmock-dev libbenchmark-dev libusb-1.0-0-dev
  libdraco-dev draco libmeshoptimizer-dev libcli11-dev libpng-dev libassimp-dev libzip-dev libtinyxml2-dev libstb-dev
  libsdl2-dev
  # anchors the benchmarks and conformance tests compare against
  libjpeg-turbo-progs libturbojpeg0-dev libwebp-dev
  # the model mode's texture anchors: cwebp, dwebp, avifenc, avifdec
  webp libavif-bin
  # the video codecs the walkthrough is measured against (x264, x265, SVT-AV1, libaom)
  ffmpeg
  # measurement and plots
  valgrind python3 python3-matplotlib python3-numpy python3-pil
)

if [ "${1:-}" = "--print" ]; then printf '%s\n' "${PACKAGES[@]}"; exit 0; fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
