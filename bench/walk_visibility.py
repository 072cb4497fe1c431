#!/usr/bin/env python3
"""What a walkthrough client must hold, measured on the ground truth's
visibility buffers (`vds render`'s OUT.vis): per frame the triangles seen,
the triangles seen for the first time, and the "hot" set (triangles seen
within W frames either side: what a polygon cache must hold to draw every
frame), for each map of bench/run_walk_video.sh. Writes walk_visibility.md.

Usage: walk_visibility.py --work WORK --results DIR --maps MAP... [--vds VDS]
"""
import argparse
import os
import re
import subprocess

import numpy as np

NONE = 0xFFFFFFFF


def read_vis(path):
    with open(path, "rb") as f:
        head = f.read(16)
        if head[:8] != b"VDSVIS01":
            raise SystemExit(f"{path}: not a visibility file")
        w, h = np.frombuffer(head[8:16], dtype="<u4")
        data = np.fromfile(f, dtype="<u4")
    n = data.size // (2 * w * h)
    frames = data.reshape(n, 2, h * w)[:, 0, :]
    return int(w), int(h), frames


def analyse(path, windows=(10, 20, 40)):
    w, h, ids = read_vis(path)
    n = ids.shape[0]
    seen = []
    for f in range(n):
        u = np.unique(ids[f])
        seen.append(u[u != NONE])
    first = set()
    new = []
    for s in seen:
        fresh = [t for t in s.tolist() if t not in first]
        first.update(fresh)
        new.append(len(fresh))
    hot = {}
    for wdw in windows:
        sizes = []
        for f in range(n):
            lo, hi = max(0, f - wdw), min(n, f + wdw + 1)
            sizes.append(len(np.unique(np.concatenate(seen[lo:hi]))))
        hot[wdw] = sizes
    counts = [len(s) for s in seen]
    void = float(np.mean(ids == NONE))
    return {"frames": n, "width": w, "height": h, "visible": counts, "new": new, "total_seen": len(first), "hot": hot,
            "void": void, "pixels_per_triangle": float(np.mean([w * h * (1 - np.mean(ids[f] == NONE)) / max(1, c)
                                                                  for f, c in enumerate(counts)]))}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--maps", nargs="+", required=True)
    ap.add_argument("--vds")
    a = ap.parse_args()
    L = ["# Walkthrough visibility: what a client must hold\n",
         "Produced by `bench/walk_visibility.py` (run by `bench/run_walk_video.sh`) from the visibility buffers of the "
         "ground truth (`vds render`'s `OUT.vis`, the triangle seen at each pixel centre) of each map's 600-frame tour "
         "at 240x180, 20 frames/s. *Visible*: triangles seen in a frame. *New*: seen for the first time (the geometry "
         "a stream must have delivered by then). *Hot W*: triangles seen within W frames either side (a polygon cache "
         "of that size draws every frame with geometry at most W frames old or early).\n",
         "| map | scene triangles | seen on the tour | visible per frame (mean / max) | new per frame (mean / max) | "
         "new in the first frame | hot 10 (mean / max) | hot 20 | hot 40 | pixels per visible triangle | pixels seeing nothing |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name in a.maps:
        r = analyse(os.path.join(a.work, name, "gt.vis"))
        total = "?"
        if a.vds:
            info = subprocess.run([a.vds, "info", name], stdout=subprocess.PIPE, text=True, check=True).stdout
            m = re.search(r"triangles\s+(\d+)", info)
            total = m.group(1) if m else "?"
        v, nw = np.array(r["visible"]), np.array(r["new"])
        hot = {k: np.array(s) for k, s in r["hot"].items()}
        L.append(f"| {name} | {total} | {r['total_seen']} | {v.mean():.0f} / {v.max()} | {nw[1:].mean():.1f} / {nw[1:].max()} | "
                 f"{nw[0]} | {hot[10].mean():.0f} / {hot[10].max()} | {hot[20].mean():.0f} / {hot[20].max()} | "
                 f"{hot[40].mean():.0f} / {hot[40].max()} | {r['pixels_per_triangle']:.0f} | {100 * r['void']:.2f} % |")
    L.append("")
    open(os.path.join(a.results, "walk_visibility.md"), "w").write("\n".join(L))
    print("\n".join(L))


if __name__ == "__main__":
    main()
