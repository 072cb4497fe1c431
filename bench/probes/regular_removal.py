#!/usr/bin/env python3
"""Probe: does decimation that keeps the mesh regular make coarse levels cheap?

The codec's half-edge collapses leave degree-5 and degree-8 vertices behind,
and every level coarser than the finest costs 14-18 bits per vertex
(docs/mesh-codec.md). This probe decimates by vertex removal instead,
retriangulating each hole with the triangulation that changes the sum of
(degree - 6)^2 the least, and accepts a removal only if that sum does not
grow (and the hole's new faces keep their orientation and lie within 0.6
mean ring edge lengths of the vertex). Removed vertices of one level are
independent, as in the codec. It prints per level the vertices removed and
the share of degree-6 vertices left, then an estimate of the position bits
of every level: the vertex predicted at its ring's centroid (vertex or
area centroid, as the codec's predictors), the corrections coded per axis
with adaptive frequency counts per (normal axis or not, log2 ring edge
length) and level. The estimate is not the codec's coder; compare its
levels with each other and with the codec's finest level, not in bytes.

Usage: bench/probes/regular_removal.py MESH.ply [--bits 10]
(ASCII PLY with x y z and triangle lists, e.g. the welded bunny that
bench/run_mesh.sh writes to /tmp/vds-bench-mesh/bunny.ply). Takes a few
minutes: it is plain Python.
"""
import argparse
import collections
import functools
import math
import sys

import numpy as np


def load_ply(path, bits):
    with open(path) as f:
        if f.readline().strip() != "ply":
            sys.exit(f"{path}: not a PLY file")
        nv = nf = 0
        while True:
            line = f.readline()
            if not line:
                sys.exit(f"{path}: no end_header")
            line = line.strip()
            if line.startswith("format") and "ascii" not in line:
                sys.exit(f"{path}: only ASCII PLY is read")
            if line.startswith("element vertex"):
                nv = int(line.split()[-1])
            if line.startswith("element face"):
                nf = int(line.split()[-1])
            if line == "end_header":
                break
        p = np.array([list(map(float, f.readline().split()[:3])) for _ in range(nv)])
        faces = []
        for _ in range(nf):
            row = f.readline().split()
            if row[0] != "3":
                sys.exit(f"{path}: only triangles are read")
            faces.append(tuple(map(int, row[1:4])))
    lo = p.min(0)
    step = (p.max(0) - lo).max() / ((1 << bits) - 1)
    return np.floor((p - lo) / step + 0.5).astype(np.int64), faces


@functools.lru_cache(None)
def triangulations(d):
    """Every triangulation of the polygon 0..d-1, as (triangles, diagonals)."""
    @functools.lru_cache(None)
    def tri(i, j):
        if j - i < 2:
            return [()]
        return [((i, k, j),) + a + b for k in range(i + 1, j) for a in tri(i, k) for b in tri(k, j)]
    out = []
    for t in tri(0, d - 1):
        diags = {(x, y) for (i, k, j) in t for (x, y) in ((i, k), (k, j), (i, j))
                 if y - x != 1 and not (x == 0 and y == d - 1)}
        out.append((t, tuple(sorted(diags))))
    return out


class Mesh:
    def __init__(self, q, faces):
        self.p = q.astype(float)
        self.faces = {}
        self.vf = [set() for _ in range(len(q))]
        self.alive = [True] * len(q)
        self.next_face = 0
        for f in faces:
            self.add(f)

    def add(self, f):
        i = self.next_face
        self.next_face += 1
        self.faces[i] = f
        for x in f:
            self.vf[x].add(i)

    def remove(self, i):
        for x in self.faces.pop(i):
            self.vf[x].discard(i)

    def ring(self, v):
        """Counter-clockwise ring of an interior manifold vertex, else None."""
        nxt = {}
        for i in self.vf[v]:
            a, b, c = self.faces[i]
            if a == v:
                nxt[b] = c
            elif b == v:
                nxt[c] = a
            else:
                nxt[a] = b
        if len(nxt) != len(self.vf[v]) or set(nxt) != set(nxt.values()):
            return None
        s = min(nxt)
        r = [s]
        while nxt[r[-1]] != s:
            r.append(nxt[r[-1]])
            if len(r) > len(nxt):
                return None
        return r if len(r) == len(nxt) else None

    def degree(self, v):
        return len({x for i in self.vf[v] for x in self.faces[i]}) - 1

    def has_edge(self, a, b):
        return bool(self.vf[a] & self.vf[b])


def point_triangle_distance(p, a, b, c):
    n = np.cross(b - a, c - a)
    nn = float(np.dot(n, n))
    def seg(a, b):
        t = np.clip(np.dot(p - a, b - a) / max(np.dot(b - a, b - a), 1e-12), 0, 1)
        return float(np.linalg.norm(p - (a + t * (b - a))))
    if nn > 1e-12:
        q = p - np.dot(p - a, n) / nn * n
        v0, v1, v2 = b - a, c - a, q - a
        d00, d01, d11 = np.dot(v0, v0), np.dot(v0, v1), np.dot(v1, v1)
        d20, d21 = np.dot(v2, v0), np.dot(v2, v1)
        den = d00 * d11 - d01 * d01
        u, w = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
        if u >= 0 and w >= 0 and u + w <= 1:
            return float(np.linalg.norm(p - q))
    return min(seg(a, b), seg(b, c), seg(c, a))


def decimate_level(m, max_degree=8, min_cos=0.3, max_dist=0.6):
    """One level of independent removals that do not raise irregularity."""
    removed, locked = [], set()
    verts = [v for v in range(len(m.alive)) if m.alive[v]]
    deg = {v: m.degree(v) for v in verts}
    order, seen = [], set()
    for s in verts:  # breadth first, so removals pack like a conquest
        if s in seen:
            continue
        queue = collections.deque([s])
        seen.add(s)
        while queue:
            x = queue.popleft()
            order.append(x)
            for y in sorted({y for i in m.vf[x] for y in m.faces[i]}):
                if y not in seen:
                    seen.add(y)
                    queue.append(y)
    for v in order:
        if v in locked:
            continue
        r = m.ring(v)
        if r is None or not 3 <= len(r) <= max_degree:
            continue
        d, p, pv = len(r), m.p, m.p[v]
        normal = sum(np.cross(p[r[i]] - pv, p[r[(i + 1) % d]] - pv) for i in range(d))
        if np.linalg.norm(normal) == 0:
            continue
        normal = normal / np.linalg.norm(normal)
        edge = np.mean([np.linalg.norm(p[x] - pv) for x in r])
        cands = []
        for t, diags in triangulations(d):
            ends = collections.Counter(x for pair in diags for x in pair)
            cost = sum((deg[r[i]] - 1 + ends[i] - 6) ** 2 - (deg[r[i]] - 6) ** 2 for i in range(d)) - (d - 6) ** 2
            cands.append((cost, t, diags, ends))
        cands.sort(key=lambda c: c[0])
        best = None
        for cost, t, diags, ends in cands[:20]:
            if cost > 0 or (best is not None and cost > best[0][0]):
                break
            if any(m.has_edge(r[x], r[y]) for x, y in diags):
                continue
            cos = [np.dot(n, normal) / np.linalg.norm(n) if np.linalg.norm(n) > 0 else -1
                   for n in (np.cross(p[r[k]] - p[r[i]], p[r[j]] - p[r[i]]) for i, k, j in t)]
            if min(cos) < min_cos:
                continue
            dist = min(point_triangle_distance(pv, p[r[i]], p[r[k]], p[r[j]]) for i, k, j in t)
            if dist > max_dist * edge:
                continue
            if best is None or (cost, dist) < best[0]:
                best = ((cost, dist), t, ends)
        if best is None:
            continue
        _, t, ends = best
        for i in list(m.vf[v]):
            m.remove(i)
        for i, k, j in t:
            m.add((r[i], r[k], r[j]))
        m.alive[v] = False
        for i in range(d):
            deg[r[i]] += ends[i] - 1
        locked.update(r)
        removed.append((v, r))
    return removed


def zigzag(x):
    return 2 * x if x >= 0 else -2 * x - 1


class AdaptiveCost:
    """Bits of an adaptive frequency model per context, 40 symbols + escape."""
    def __init__(self):
        self.tables = {}

    def __call__(self, ctx, sym, k=40):
        cnt, n = self.tables.setdefault(ctx, [collections.Counter(), 0])
        key = sym if sym < k else "esc"
        bits = -math.log2((cnt[key] + 0.4) / (n + 0.4 * (k + 1)))
        if sym >= k:
            bits += 2 * math.log2(sym - k + 1) + 1
        cnt[key] += 1
        self.tables[ctx][1] += 1
        return bits


def predict(p, r, area):
    c = p[r].mean(0)
    if not area:
        return c
    s, w = np.zeros(3), 0.0
    for i in range(len(r)):
        a, b = p[r[i]], p[r[(i + 1) % len(r)]]
        weight = np.abs(np.cross(a - c, b - c)).max()
        s += weight * (a + b + c) / 3
        w += weight
    return s / w if w > 0 else c


def position_bits(q, levels, area):
    p = q.astype(float)
    rows = []
    for li in range(len(levels) - 1, -1, -1):  # coarse to fine, as decoded
        cost, bits = AdaptiveCost(), 0.0
        for v, r in levels[li]:
            ring = p[r]
            res = q[v] - np.floor(predict(p, r, area) + 0.5).astype(np.int64)
            n = sum(np.cross(ring[i] - ring[0], ring[(i + 1) % len(r)] - ring[0]) for i in range(len(r)))
            axis = int(np.argmax(np.abs(n)))
            scale = int(min(11, max(0, math.log2(max(np.mean(np.abs(ring - np.roll(ring, 1, 0)).sum(1)), 1)))))
            for k in range(3):
                x = int(res[k]) * (-1 if k == axis and n[axis] < 0 else 1)
                bits += cost((k == axis, scale), zigzag(x))
        rows.append((li + 1, len(levels[li]), bits / len(levels[li])))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("mesh")
    ap.add_argument("--bits", type=int, default=10)
    a = ap.parse_args()
    q, faces = load_ply(a.mesh, a.bits)
    m = Mesh(q, faces)
    levels = []
    print(f"{a.mesh}: {len(q)} vertices, {len(faces)} triangles, {a.bits}-bit grid")
    print("level (1 = finest)  removed  share of the level  vertices left  degree 6 left")
    while True:
        before = sum(m.alive)
        rem = decimate_level(m)
        if not rem:
            break
        levels.append(rem)
        left = [v for v in range(len(q)) if m.alive[v]]
        deg6 = sum(1 for v in left if m.degree(v) == 6) / len(left)
        print(f"{len(levels):5d}  {len(rem):7d}  {len(rem) / before:6.3f}  {len(left):7d}  {deg6:5.2f}", flush=True)
        if len(left) < 0.01 * len(q) or len(rem) < 0.02 * before:
            break
    for area in (False, True):
        rows = position_bits(q, levels, area)
        total = sum(n * b for _, n, b in rows)
        print(f"positions, {'area' if area else 'vertex'} centroid: {total / sum(n for _, n, _ in rows):.2f} "
              f"bits per removed vertex; per level (level, removed, bits/vertex):")
        for row in sorted(rows):
            print("  %3d %6d %6.2f" % row)


if __name__ == "__main__":
    main()
