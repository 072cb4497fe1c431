#!/usr/bin/python3
"""bench/run_model_stream.sh's report: bench/results/model_stream.md, a plot of
rendered PSNR against time per model (2 KB/s and 115,200 baud) and a contact
sheet of the client's frames of one stream.

Usage: model_stream_report.py WORK RESULTS COMMAND "QUALITIES" NAME...
"""
import csv
import glob
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

RATES = [("2 KB/s", 2048.0), ("115,200 baud", 11520.0)]
FIRST_DB = 25.0


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def first_at(points, db):
    """Bytes at the first point at or above db, or None."""
    for b, p in points:
        if p >= db:
            return b
    return None


def main():
    work, results, command, qualities = sys.argv[1:5]
    names = sys.argv[5:]
    qualities = qualities.split()
    lines = ["# Textured model streams against a download", "",
             f"Command: `{command}` (the encoder's own timeline: `vds encode-model --timeline`).", "",
             "vds: the stream as it arrives, at each quality factor: after every chunk that completes a client frame, "
             "the client's picture (its mesh and the colours it holds, drawn by the client library's model view) "
             "from 8 orbit angles, PSNR against the model with its own texture (double, 3x3 supersampled) over the "
             "pixels inside the model's silhouette. The download: Draco (draco_encoder's defaults) and the texture as "
             "WebP (cwebp default, q 75) or JPEG (cjpeg -optimize, q 75), shown once whole, on the model's own geometry "
             "(Draco's quantisation not applied, no glTF JSON counted: both in its favour), drawn as a client draws a "
             "textured mesh (the client library's renderer, RGB565, bilinear); with the texture uncoded (PNG) that "
             "is the client renderer's ceiling. Time = bytes / rate "
             "(2 KB/s = 2,048 B/s; 115,200 baud = 11,520 B/s), link framing not counted for either.", "",
             "| model | first frame >= 25 dB (vds) | at 2 KB/s (goal <= 2 s) | download (WebP) | its PSNR | "
             "vds bytes to reach it | ratio (goal <= 0.5) | download (JPEG) | its PSNR | vds bytes to reach it | ratio | "
             "ceiling (PNG texture) | vds final (best) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    ws_lines = ["", "## Client workspace", "",
                "The finest colours a client shows in 128 KiB and 192 KiB of workspace (the player from byte 7,320, "
                "as the host board's link leaves it), quality factor " + qualities[1] + ":", "",
                "| model | 128 KiB | 192 KiB |", "|---|---|---|"]
    for name in names:
        d = os.path.join(work, name)
        vds = {}
        anchors = []
        for q in qualities:
            for r in rows(os.path.join(d, f"q{q}.csv")):
                if r["kind"] == "vds":
                    vds.setdefault(q, []).append((int(r["bytes"]), float(r["psnr"])))
                else:
                    anchors.append((r["kind"], int(r["bytes"]), float(r["psnr"])))
        first = [first_at(p, FIRST_DB) for p in vds.values()]
        first = min([b for b in first if b is not None], default=None)
        cells = [name, f"{first:,} B" if first else "never",
                 f"{first / 2048:.2f} s" if first else "-"]
        for kind in ("draco+webp", "draco+jpeg"):
            a = [x for x in anchors if x[0] == kind]
            if not a:
                cells += ["-"] * 4
                continue
            _, ab, ap = a[0]
            reach = [first_at(p, ap) for p in vds.values()]
            reach = min([b for b in reach if b is not None], default=None)
            cells += [f"{ab:,} B", f"{ap:.2f} dB", f"{reach:,} B" if reach else "not reached",
                      f"{reach / ab:.2f}" if reach else "-"]
        png = [x for x in anchors if x[0] == "draco+png"]
        cells.append(f"{png[0][2]:.2f} dB" if png else "-")
        best = max(((p[-1][1], b) for p in vds.values() for b in [p[-1][0]]), default=None)
        cells.append(f"{best[0]:.2f} dB in {best[1]:,} B" if best else "-")
        lines.append("| " + " | ".join(cells) + " |")

        fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
        for ax, (label, rate) in zip(axes, RATES):
            for q, pts in sorted(vds.items(), key=lambda x: float(x[0])):
                t = [0] + [b / rate for b, _ in pts]
                p = [0] + [p for _, p in pts]
                ax.step(t, p, where="post", label=f"vds q {q}")
            for kind, ab, ap in anchors:
                ax.step([0, ab / rate, ab / rate * 1.6], [0, ap, ap], where="post", linestyle="--",
                        label=f"{kind} download")
            ax.axhline(FIRST_DB, color="grey", linewidth=0.5)
            ax.set_xlabel(f"seconds at {label}")
            ax.set_ylabel("rendered PSNR (dB)")
            ax.set_title(f"{name} at {label}")
            ax.set_ylim(0, 45)
            ax.grid(alpha=0.3)
        webp = [ab for kind, ab, _ in anchors if kind == "draco+webp"]
        last = max((p[-1][0] for p in vds.values()), default=0)
        axes[0].set_xlim(0, 1.15 * max([last] + webp) / RATES[0][1])
        axes[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(results, f"model_stream_{name}.png"), dpi=80)
        plt.close(fig)

        frames = sorted(glob.glob(os.path.join(d, "frames", "frame*.png")))
        if frames:
            pick = [frames[round(i * (len(frames) - 1) / 7)] for i in range(8)] if len(frames) > 8 else frames
            fig, axes = plt.subplots(2, 4, figsize=(12, 4.6))
            for ax in axes.flat:
                ax.axis("off")
            for ax, f in zip(axes.flat, pick):
                ax.imshow(mpimg.imread(f))
                ax.set_title(os.path.basename(f), fontsize=8)
            fig.tight_layout()
            fig.savefig(os.path.join(results, f"model_stream_{name}_frames.png"), dpi=70)
            plt.close(fig)

        views = sorted(glob.glob(os.path.join(d, "img", "view*_reference.png")))[:3]
        if views:
            kinds = ["reference", "vds", "draco+webp", "draco+jpeg", "draco+png"]
            fig, axes = plt.subplots(len(views), len(kinds), figsize=(3 * len(kinds), 2.4 * len(views)), squeeze=False)
            for row, ref in zip(axes, views):
                base = ref[: -len("_reference.png")]
                for ax, kind in zip(row, kinds):
                    ax.axis("off")
                    f = f"{base}_{kind}.png"
                    if os.path.exists(f):
                        ax.imshow(mpimg.imread(f))
                        ax.set_title(f"{os.path.basename(base)} {kind}", fontsize=8)
            fig.tight_layout()
            fig.savefig(os.path.join(results, f"model_stream_{name}_views.png"), dpi=70)
            plt.close(fig)

        ws = []
        for kib in (128, 192):
            path = os.path.join(d, f"ws{kib}.txt")
            text = open(path).read() if os.path.exists(path) else ""
            m = re.search(r"colours down to MIP level (\d+) of (\d+)", text)
            if "no room for the colours" in text:
                ws.append("vertex colours only (no room for the faces' samples)")
            elif "not whole" in text or "workspace holds" in text or "base mesh needs" in text:
                ws.append("part of the mesh, no colours")
            elif m:
                ws.append(f"MIP level {m.group(1)} (of {m.group(2)})")
            elif re.search(r"^[0-9a-f]{8}$", text, re.M):
                ws.append("every level")
            else:
                ws.append("the base mesh does not fit")
        ws_lines.append(f"| {name} | {ws[0]} | {ws[1]} |")
    lines += ws_lines
    lines += ["", "Plots: `model_stream_<model>.png` (PSNR against time at both rates); the client's frames of the "
              f"quality {qualities[1]} stream: `model_stream_<model>_frames.png`; its last picture from the first "
              "views beside the reference and each download as the client draws it: `model_stream_<model>_views.png`."]
    with open(os.path.join(results, "model_stream.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
