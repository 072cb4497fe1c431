#!/usr/bin/env bash
# The textured model client on the Cortex-M4 board (QEMU, -icount: counts
# are instructions, repeatable), written to bench/results/model_client.md:
# per frame the instructions decoding its chunk and drawing it, the pixels
# the model covers (from the host board's identical frames), and per
# mesh colors level the instructions per decoded sample; the board's
# workspace high-water mark.
#
# Usage: bench/run_model_client.sh [BUILD_DIR]   (default build/host-release,
#   built whole: its cm4/firmware_sim/vds_fw_client.elf and the host board)
#   MODELS (default: glTF's textured box at R <= 64, an OpenArena player).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
WORK=${WORK:-$BUILD/model_client}
RESULTS=${RESULTS:-$ROOT/bench/results}
A=/usr/share/assimp/models
PLAYER=${PLAYER:-major}
mkdir -p "$WORK" "$RESULTS"
/usr/bin/python3 "$ROOT/bench/extract_oa_player.py" "$WORK/oa" "$PLAYER"
MODELS=${MODELS:-"box:$A/glTF2/BoxTextured-glTF/BoxTextured.gltf:--max-res=6 $PLAYER:$WORK/oa/models/players/$PLAYER:--up=+y"}
ELF="$BUILD/cm4/firmware_sim/vds_fw_client.elf"
HOSTFW="$BUILD/firmware_sim/vds_fw_client_host"
for f in "$VDS" "$ELF" "$HOSTFW"; do
  [ -e "$f" ] || { echo "run_model_client: $f missing (cmake --preset host-release && cmake --build build/host-release)" >&2; exit 1; }
done
for entry in $MODELS; do
  IFS=: read -r name model args <<< "$entry"
  dir="$WORK/$name"
  rm -rf "$dir"; mkdir -p "$dir"
  echo "run_model_client: $name: encode, then both boards"
  "$VDS" encode-model "$model" -o "$dir/model.vds" --orbit 0 ${args//=/ } > "$dir/encode.txt"
  "$VDS" play "$dir/model.vds" --board qemu --firmware "$ELF" --out "$dir/qemu" > "$dir/qemu.txt" 2>&1
  "$VDS" play "$dir/model.vds" --board host --firmware "$HOSTFW" --out "$dir/host" > "$dir/host.txt" 2>&1
done
/usr/bin/python3 - "$WORK" "$RESULTS" "bench/run_model_client.sh $*" $(for e in $MODELS; do echo "${e%%:*}"; done) <<'PY'
import glob, os, re, sys
import matplotlib.image as mpimg
import numpy as np
work, results, command = sys.argv[1:4]
out = ["# Textured model client on the Cortex-M4 board", "",
       f"Command: `{command}`. Instructions counted by QEMU (-icount) on the mps2-an386 board; "
       "pixels: the model's, in the host board's frames (equal CRCs).", ""]
for name in sys.argv[4:]:
    d = os.path.join(work, name)
    enc = open(os.path.join(d, "encode.txt")).read()
    q = open(os.path.join(d, "qemu.txt")).read()
    samples = {int(m.group(1)): int(m.group(2)) for m in re.finditer(r"colour level (\d+): (\d+) samples, \d+ bytes", enc)}
    frames = [(int(m.group(1)), int(m.group(2)), int(m.group(3))) for m in
              re.finditer(r"frame\s+(\d+) crc \w+ parse \d+ decode (\d+) .*? display (\d+)", q)]
    ws = re.search(r"workspace (\d+) of (\d+) B", q)
    pngs = sorted(glob.glob(os.path.join(d, "host", "frames", "*.png")))
    pix = []
    for f in pngs:
        im = (mpimg.imread(f)[:, :, :3] * 255).round().astype(int)
        pix.append(int((np.abs(im - im[0, 0]).sum(axis=2) > 0).sum()))
    out += [f"## {name}", "", "```", enc.strip(), "```", "",
            f"Workspace high-water on the board: {ws.group(1)} of {ws.group(2)} bytes." if ws else "", "",
            "| frame | decode (instructions) | display (instructions) | model pixels | display per model pixel |",
            "|---:|---:|---:|---:|---:|"]
    for i, dec, disp in frames:
        p = pix[i] if i < len(pix) else 0
        out.append(f"| {i} | {dec:,} | {disp:,} | {p:,} | {disp / p:.0f} |" if p else f"| {i} | {dec:,} | {disp:,} | - | - |")
    # The last frames are the levels the board showed (those sent, no finer
    # than its workspace holds), finest last: decode per sample.
    logs = q + "".join(open(f).read() for f in glob.glob(os.path.join(d, "qemu", "*.log")))
    held = re.search(r"colours down to MIP level (\d+)", logs)
    finest = int(held.group(1)) if held else 0
    sent = [m for m in sorted(samples, reverse=True) if m >= finest]
    if "no room for the colours" in logs:
        sent = []
    tail = frames[-len(sent):] if sent and len(frames) >= len(sent) else []
    if held:
        out.append(f"The board's workspace holds MIP level {finest} and coarser; finer levels are skipped.")
    if tail:
        out += ["", "| mesh colors level | samples | decode (instructions) | per sample |", "|---:|---:|---:|---:|"]
        for m, (_, dec, _) in zip(sent, tail):
            out.append(f"| {m} | {samples[m]:,} | {dec:,} | {dec / samples[m]:.0f} |")
    out.append("")
open(os.path.join(results, "model_client.md"), "w").write("\n".join(out) + "\n")
PY
echo "run_model_client: wrote $RESULTS/model_client.md"
