#!/bin/sh
# Progressive mesh codec against Draco: sizes, per-level tables and
# rate-distortion (bench_mesh, which runs the real draco_encoder), client
# instructions per vertex split (callgrind on the host), plots. Writes
# bench/results/mesh.md, mesh_rd.csv, mesh_rd.png and mesh_sizes.png.
#
#   bench/run_mesh.sh            (from the repository root; needs glmark2-data,
#                                 the draco tools, valgrind, python3-matplotlib)
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build/h-mesh-rel}
TMP=${TMPDIR:-/tmp}/vds-bench-mesh
OUT=bench/results
PY=/usr/bin/python3

cmake -S . -B "$BUILD" -G Ninja -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=Release -DVDS_BUILD_FIRMWARE=OFF > /dev/null
cmake --build "$BUILD" -j1 --target bench_mesh vds > /dev/null
mkdir -p "$TMP" "$OUT"

BENCH_CMD="$BUILD/bench/bench_mesh --out $OUT --tmp $TMP"
$BENCH_CMD

# Instructions per vertex: the mesh decoder only (MeshDecoder::consume and
# everything it calls), one decode of each stream under callgrind.
CG="$TMP/callgrind.md"
{
  echo "| stream | vertices | vertices after the base | instructions | per vertex after the base |"
  echo "|---|---:|---:|---:|---:|"
  for f in "$TMP"/*_1[02].vds "$TMP"/*_1[02]_splits.vds "$TMP"/*_1[02]_paper.vds; do
    [ -f "$f" ] || continue
    valgrind --tool=callgrind --callgrind-out-file="$TMP/cg.out" \
      --toggle-collect='vds::MeshDecoder::consume*' \
      "$BUILD/bench/bench_mesh" --decode-once "$f" > "$TMP/cg.txt" 2>&1
    ir=$(callgrind_annotate "$TMP/cg.out" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1}')
    line=$(grep "splits" "$TMP/cg.txt")
    verts=$(echo "$line" | sed 's/.* \([0-9]*\) vertices.*/\1/')
    splits=$(echo "$line" | sed 's/.* \([0-9]*\) splits.*/\1/')
    echo "| $(basename "$f") | $verts | $splits | $ir | $(( ir / splits )) |"
  done
} > "$CG"

$PY - "$OUT" <<'EOF'
import csv, sys, collections
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
out = sys.argv[1]
rows = list(csv.DictReader(open(out + "/mesh_rd.csv")))
models = list(dict.fromkeys(r["model"] for r in rows))
bits = sorted(set(int(r["bits"]) for r in rows))
colors = {10: "tab:blue", 12: "tab:orange", 11: "tab:green", 14: "tab:red"}
fig, axes = plt.subplots(1, len(models), figsize=(5.2 * len(models), 4.4), squeeze=False)
for ax, m in zip(axes[0], models):
    for b in bits:
        v = [r for r in rows if r["model"] == m and int(r["bits"]) == b and r["codec"] == "vds"]
        s = [r for r in rows if r["model"] == m and int(r["bits"]) == b and r["codec"] == "vds-splits"]
        d = [r for r in rows if r["model"] == m and int(r["bits"]) == b and r["codec"] == "draco"]
        x = [int(r["bytes"]) / 1024 for r in v]
        c = colors.get(b, None)
        # Steps: what the client shows stays until the next level is in (the
        # last step of vds is the single-rate tail).
        ax.plot(x, [100 * float(r["hausdorff"]) for r in v], "-o", ms=3, color=c, drawstyle="steps-post",
                label=f"vds {b} bits: Hausdorff")
        ax.plot(x, [100 * float(r["rms"]) for r in v], "--s", ms=3, color=c, drawstyle="steps-post",
                label=f"vds {b} bits: RMS")
        xs_ = [int(r["bytes"]) / 1024 for r in s]
        ax.plot(xs_, [100 * float(r["rms"]) for r in s], ":", lw=1, color=c, alpha=0.7, drawstyle="steps-post",
                label=f"vds splits only {b} bits: RMS")
        for r in d:
            ax.plot([int(r["bytes"]) / 1024], [100 * float(r["hausdorff"])], "*", ms=13, color=c,
                    markeredgecolor="black", label=f"Draco {b} bits: Hausdorff")
            ax.plot([int(r["bytes"]) / 1024], [100 * float(r["rms"])], "P", ms=10, color=c,
                    markeredgecolor="black", label=f"Draco {b} bits: RMS")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("bytes received (KiB, log)")
    ax.set_ylabel("distance to the original (% of bbox diagonal, log)")
    ax.set_title(f"{m}: progressive decoding, level by level")
    ax.grid(True, which="both", alpha=0.3)
    ax.axvline(2.0, color="grey", lw=0.8, ls=":")
    ax.text(2.05, ax.get_ylim()[1] * 0.7, "1 s at 2 KB/s", fontsize=7, color="grey")
axes[0][0].legend(fontsize=7, loc="lower left")
fig.tight_layout()
fig.savefig(out + "/mesh_rd.png", dpi=110)

# Sizes: bits per triangle, vds vs the paper's coding vs Draco.
sizes = collections.OrderedDict()
for line in open(out + "/mesh_body.md"):
    p = [x.strip() for x in line.split("|")]
    if len(p) > 16 and p[1] in models and p[2].isdigit() and p[9].startswith("**"):
        sizes[(p[1], int(p[2]))] = (float(p[6]), float(p[8]), float(p[15]), float(p[11]))
fig, ax = plt.subplots(figsize=(9, 4))
labels = [f"{m}\n{b} bits" for (m, b) in sizes]
import numpy as np
xs = np.arange(len(sizes))
w = 0.21
ax.bar(xs - 1.5 * w, [v[0] for v in sizes.values()], w, label="Draco -cl 10 (single rate)", color="tab:gray")
ax.bar(xs - 0.5 * w, [v[1] for v in sizes.values()], w, label="vds: split levels + single-rate tail", color="tab:blue")
ax.bar(xs + 0.5 * w, [v[2] for v in sizes.values()], w, label="vds splits only", color="tab:cyan")
ax.bar(xs + 1.5 * w, [v[3] for v in sizes.values()], w, label="paper's coding (Huffman)", color="tab:orange")
ax.bar(xs - 0.5 * w, [1.25 * v[0] for v in sizes.values()], w, fill=False, edgecolor="black", ls="--",
       label="goal: 1.25 x Draco")
ax.set_xticks(xs)
ax.set_xticklabels(labels, fontsize=8)
ax.set_ylabel("bits per triangle (whole stream)")
ax.legend(fontsize=8)
ax.grid(True, axis="y", alpha=0.3)
fig.tight_layout()
fig.savefig(out + "/mesh_sizes.png", dpi=110)
EOF

{
  echo "# Progressive mesh codec against Draco"
  echo
  echo "Produced by \`bench/run_mesh.sh\` on $(date -u +%Y-%m-%d) ($(uname -m), $(nproc) cores),"
  echo "which ran \`$BENCH_CMD\` (release build: \`cmake -S . -B $BUILD -G Ninja -DCMAKE_C_COMPILER=clang"
  echo "-DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release -DVDS_BUILD_FIRMWARE=OFF\`),"
  echo "the real \`$(command -v draco_encoder)\` ($(dpkg-query -W -f='draco ${Version}' draco 2>/dev/null || echo draco)) as"
  echo "\`draco_encoder -i MODEL.ply -o MODEL.drc -qp Q -cl 10\` on the same welded positions-only PLY that vds"
  echo "encodes, and callgrind for the client's instruction counts. Inputs: glmark2-data"
  echo "($(dpkg-query -W -f='${Version}' glmark2-data 2>/dev/null || echo '?')). Plots: \`mesh_rd.png\`, \`mesh_sizes.png\`;"
  echo "raw numbers: \`mesh_rd.csv\`. The codec is described in \`docs/mesh-codec.md\`."
  echo
  cat "$OUT/mesh_body.md"
  echo "## Client instructions per vertex (host, callgrind)"
  echo
  echo "One decode of each stream under \`valgrind --tool=callgrind --toggle-collect='vds::MeshDecoder::consume*'\`"
  echo "(the mesh decoder and everything it calls; container parsing and file reading excluded), x86-64"
  echo "release build. The Cortex-M4 figures (QEMU board) come from \`bench/run_mesh_m4.sh\`:"
  echo "[mesh_m4.md](mesh_m4.md)."
  echo
  cat "$CG"
} > "$OUT/mesh.md"
rm -f "$OUT/mesh_body.md"
echo "wrote $OUT/mesh.md"
