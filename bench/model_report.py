#!/usr/bin/env python3
"""bench/results/model.md and model_rd.png from bench/run_model.sh's work
folder: per model, the thesis's measure (PSNR of Y', Cb, Cr per MIP level
against compression ratio) and the rendered-view PSNR against bytes of the
mesh colors codec and of the texture anchors, with BD-rates.

Usage: model_report.py WORK RESULTS COMMAND NAME=MODEL...
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def bd_rate(anchor, test):
    """Bjontegaard delta rate (percent) of `test` against `anchor`, each a
    list of (bytes, psnr): log-rate fitted as a cubic in PSNR over the PSNR
    range both cover. None when they do not overlap or have too few points."""
    def prep(pts):
        pts = sorted(set(pts), key=lambda p: p[1])
        return np.array([p[1] for p in pts]), np.array([math.log10(p[0]) for p in pts])
    if len(anchor) < 4 or len(test) < 4:
        return None
    da, ra = prep(anchor)
    dt, rt = prep(test)
    lo, hi = max(da.min(), dt.min()), min(da.max(), dt.max())
    if hi <= lo:
        return None
    pa, pt = np.polyfit(da, ra, 3), np.polyfit(dt, rt, 3)
    ia, it = np.polyint(pa), np.polyint(pt)
    avg = ((np.polyval(it, hi) - np.polyval(it, lo)) - (np.polyval(ia, hi) - np.polyval(ia, lo))) / (hi - lo)
    return (10 ** avg - 1) * 100


def main():
    work, results, command = sys.argv[1], sys.argv[2], sys.argv[3]
    models = [a.split("=", 1) for a in sys.argv[4:]]
    out = ["# Model mode: the mesh colors codec on textured models", "",
           "Produced by `%s` (docs/model-mode.md, \"Figures\")." % command, ""]
    fig, axes = plt.subplots(1, len(models), figsize=(5.5 * len(models), 4.2), squeeze=False)
    summary = []
    for (name, path), ax in zip(models, axes[0]):
        d = os.path.join(work, name)
        thesis = open(os.path.join(d, "thesis.txt")).read().strip()
        rows = list(csv.DictReader(open(os.path.join(d, "rendered.csv"))))
        curves = {}
        uncoded = None
        for r in rows:
            if r["codec"] == "mesh colors":
                uncoded = float(r["psnr"])
                continue
            curves.setdefault(r["codec"], []).append((int(r["bytes"]), float(r["psnr"])))
        out += ["## %s" % name, "", "`%s`" % path, "", "```", thesis, "```", ""]
        out += ["Rendered views (%s): mesh colors uncoded %.2f dB (what resampling the texture onto the mesh loses)." %
                (open(os.path.join(d, "rendered.txt")).read().split("rendered views: ")[1].split("\n")[0], uncoded), ""]
        out += ["| codec | parameter | bytes | rendered PSNR (dB) |", "|---|---:|---:|---:|"]
        for r in rows:
            if r["codec"] != "mesh colors":
                out.append("| %s | %s | %s | %.2f |" % (r["codec"], r["parameter"], r["bytes"], float(r["psnr"])))
        out.append("")
        for codec in ("mcc-vds", "mcc-paper"):
            test = curves.get(codec, [])
            for anchor in ("jpeg", "webp", "avif"):
                if anchor in curves:
                    bd = bd_rate(curves[anchor], test)
                    summary.append((name, codec, anchor, bd))
                    out.append("BD-rate of %s against %s: %s" % (codec, anchor, "no overlap" if bd is None else "%+.1f %%" % bd))
        out.append("")
        for codec, pts in curves.items():
            pts.sort()
            ax.plot([p[0] / 1024 for p in pts], [p[1] for p in pts], "o-", label=codec, markersize=3)
        ax.axhline(uncoded, color="grey", linestyle=":", label="mesh colors uncoded")
        ax.set_xscale("log")
        ax.set_xlabel("KiB")
        ax.set_ylabel("rendered PSNR (dB)")
        ax.set_title(name)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(results, "model_rd.png"), dpi=90)
    head = ["## Summary: BD-rate of the mesh colors codecs on rendered-view PSNR", "",
            "mcc-vds is the improved codec (vds mode; its sample density follows the quality, "
            "`density_for_quality`, and no finer than the views show, 2 samples per pixel side where they come "
            "nearest, `--samples-per-pixel`; its vertex samples in steps of half the quality, "
            "`vertex_step_for_quality`; at each quality the encoder draws its four choices of chroma lattice and face "
            "resolutions from 5 views of its own and keeps the best, `choose_colours`: the choice is printed in "
            "`rendered.txt`), mcc-paper the thesis's (one sample per texel side, chroma on each level's own "
            "lattice). Bytes: the header and "
            "level 0, what a client needs to show level 0; the anchors: the texture file(s). Negative: fewer bytes "
            "than the anchor for the same rendered PSNR, over the PSNR range both reach.", "",
            "| model | codec | against | BD-rate |", "|---|---|---|---:|"]
    head += ["| %s | %s | %s | %s |" % (n, c, a, "no overlap" if b is None else "%+.1f %%" % b) for n, c, a, b in summary]
    head += ["", "Goal (issue): the improved codec at <= -25 % against JPEG and <= 0 % against WebP.", "",
             "![rendered PSNR against bytes](model_rd.png)", ""]
    open(os.path.join(results, "model.md"), "w").write("\n".join(out[:4] + head + out[4:]) + "\n")


if __name__ == "__main__":
    main()
