#!/usr/bin/env python3
"""Estimates the position bits of a deferred-precision probe log.

Reads the log the patched encoder writes (bench/probes/deferred_precision.sh)
and codes every value with adaptive binary contexts much like the codec's:

- "N" lines, a new vertex's correction on its level's step: zero flag,
  sign, unary magnitude up to 12 then Exp-Golomb, contexts by (normal axis
  or not, ring scale class, step);
- "R" lines, a refinement from step 2^a to 2^s: the sub-cell index bit by
  bit, most significant first, each bit with a context of (normal axis or
  not, ring scale class, first bit or not, where the prediction lies in the
  current interval in quarters, clamped to -5..4).

Prints bytes and bits per vertex for each kind. With every step 0 the
estimate is within 2 % of the codec's own position bits, so it compares
policies; it is not the codec's coder.

Usage: deferred_precision_cost.py LOG VERTICES
"""
import collections
import math
import sys


class Bin:
    __slots__ = ("c0", "c1")

    def __init__(self):
        self.c0 = self.c1 = 0.4

    def cost(self, bit):
        p = (self.c1 if bit else self.c0) / (self.c0 + self.c1)
        if bit:
            self.c1 += 1
        else:
            self.c0 += 1
        return -math.log2(p)


def exp_golomb_bits(v, k):
    n = 0
    while v >= (1 << k):
        v -= 1 << k
        k += 1
        n += 1
    return n + 1 + k


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    path, vertices = sys.argv[1], int(sys.argv[2])
    bins = collections.defaultdict(Bin)

    def signed(ctx, r, cutoff=12, k=1):
        c = bins[ctx + ("zero",)].cost(r != 0)
        if r == 0:
            return c
        c += 1.0  # sign
        m = abs(r) - 1
        for i in range(min(m, cutoff)):
            c += bins[ctx + ("mag", min(i, 7))].cost(1)
        if m < cutoff:
            c += bins[ctx + ("mag", min(m, 7))].cost(0)
        else:
            c += exp_golomb_bits(m - cutoff, k)
        return c

    total = collections.Counter()
    with open(path) as f:
        for line in f:
            fields = line.split()
            if fields[0] == "N":
                _, scale, role, r, s = map(int, fields[1:])
                total["N"] += signed(("N", role, scale, s), r)
            elif fields[0] == "R":
                _, scale, role, a, s, offset, predicted = map(int, fields[1:])
                low, width = 0, 1 << a  # the interval, grid units from the cell's low corner
                for b in range(a - s - 1, -1, -1):
                    mid = low + width // 2
                    where = max(-5, min(4, (predicted - mid) * 4 // width))
                    bit = (offset >> b) & 1
                    total["R"] += bins[("R", role, scale, b == a - s - 1, where)].cost(bit)
                    if bit:
                        low = mid
                    width //= 2
            else:
                sys.exit(f"{path}: not a probe log line: {line.strip()}")
    n, r = total["N"], total["R"]
    print(f"new vertices {n / 8:8.0f} B {n / vertices:5.2f} b/V   refinements {r / 8:8.0f} B {r / vertices:5.2f} b/V"
          f"   positions {(n + r) / 8:8.0f} B {(n + r) / vertices:5.2f} b/V")


if __name__ == "__main__":
    main()
