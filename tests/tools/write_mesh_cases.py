#!/usr/bin/env python3
"""Writes the mesh firmware benchmark's test cases into DIR: mesh_case0.vds,
the golden stream of mesh format v1 (vertex-centroid predictor), and
mesh_case1.vds, a torus encoded now by `vds encode-mesh` with the default
options (area predictor), so the boards compare both predictors; and
model_prefix.vds, a finer torus (4,608 vertices, about 14 KB) for a client too
small to hold all of it, long enough that stopping the stream shows.

Usage: write_mesh_cases.py --vds VDS --golden GOLDEN.vds --out DIR"""
import argparse
import math
import os
import shutil
import subprocess
import sys


def torus_obj(path, rings=24, sides=12, big=1.0, small=0.35):
    """A torus with a bump, rings x sides vertices, as an OBJ file."""
    lines = []
    for i in range(rings):
        a = 2 * math.pi * i / rings
        for j in range(sides):
            b = 2 * math.pi * j / sides
            r = small * (1 + 0.3 * math.cos(3 * a) * (j % 2 == 0))
            x = (big + r * math.cos(b)) * math.cos(a)
            y = r * math.sin(b)
            z = (big + r * math.cos(b)) * math.sin(a)
            lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
    for i in range(rings):
        for j in range(sides):
            v00 = i * sides + j + 1
            v10 = ((i + 1) % rings) * sides + j + 1
            v01 = i * sides + (j + 1) % sides + 1
            v11 = ((i + 1) % rings) * sides + (j + 1) % sides + 1
            lines.append(f"f {v00} {v01} {v11}")
            lines.append(f"f {v00} {v11} {v10}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vds", required=True)
    ap.add_argument("--golden", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    shutil.copyfile(a.golden, os.path.join(a.out, "mesh_case0.vds"))
    obj = os.path.join(a.out, "torus.obj")
    torus_obj(obj)
    enc = subprocess.run([a.vds, "encode-mesh", obj, "-o", os.path.join(a.out, "mesh_case1.vds"), "--max-chunk", "1024"],
                         capture_output=True, text=True)
    print(enc.stdout + enc.stderr)
    if enc.returncode != 0 or "area predictor" not in enc.stdout:
        print("write_mesh_cases: the torus was not encoded with the area predictor")
        return 1
    fine = os.path.join(a.out, "torus_fine.obj")
    torus_obj(fine, rings=96, sides=48)
    enc = subprocess.run([a.vds, "encode-mesh", fine, "-o", os.path.join(a.out, "model_prefix.vds"), "--max-chunk", "1024"],
                         capture_output=True, text=True)
    print(enc.stdout + enc.stderr)
    if enc.returncode != 0:
        print("write_mesh_cases: the fine torus was not encoded")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
