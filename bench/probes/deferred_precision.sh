#!/usr/bin/env bash
# Probe: would sending coarse-level vertices on a coarser grid, and their
# low bits later from a denser ring, make the positions cheaper?
#
# Copies the committed tree to a scratch directory, applies
# deferred_precision.patch to its encoder (the patch is kept beside this
# script; it applies to the tree it was committed with), builds the `vds`
# tool there (preset host-release) and encodes glmark2's bunny at 10 bits
# under each step policy. A policy lists the grid step exponent s per level
# from the finest backwards: "0,1,2" codes the finest level exactly, the
# level before it on a grid of 2, all coarser ones on a grid of 4, and
# refines every vertex to a level's step at that level's start.
# deferred_precision_cost.py estimates the position bits of each log.
# The encoder's own connectivity bits are printed beside them (the split
# ranking reads the rounded positions).
#
# Usage: bench/probes/deferred_precision.sh [POLICY ...]
#   (default: 0  0,1  0,1,2  0,2  0,1,2,3  0,1,1,2,2,3,3,4)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
MODEL=/usr/share/glmark2/models/bunny.obj
[[ -e "$MODEL" ]] || { echo "deferred_precision.sh: $MODEL not found (scripts/fetch-data.sh)" >&2; exit 1; }
POLICIES=("$@")
[[ ${#POLICIES[@]} -gt 0 ]] || POLICIES=(0 0,1 0,1,2 0,2 0,1,2,3 0,1,1,2,2,3,3,4)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
git -C "$ROOT" archive HEAD | tar -x -C "$WORK"
patch -s -d "$WORK" -p1 < "$ROOT/bench/probes/deferred_precision.patch"
echo "building the patched encoder in $WORK (a few minutes) ..." >&2
cmake --preset host-release -S "$WORK" > /dev/null
cmake --build "$WORK/build/host-release" --target vds > /dev/null
for policy in "${POLICIES[@]}"; do
  out=$(VDS_PROBE_STEPS=$policy VDS_PROBE_LOG="$WORK/log" \
        "$WORK/build/host-release/encoder/vds" encode-mesh "$MODEL" --bits 10 -o "$WORK/bunny.vds")
  conn=$(sed -n 's/^bits\/vertex: split flags \([0-9.]*\), arc \([0-9.]*\), rotation \([0-9.]*\).*/\1 + \2 + \3/p' <<< "$out")
  printf '%-18s connectivity %s b/V   %s\n' "$policy" "$conn" \
    "$(python3 "$ROOT/bench/probes/deferred_precision_cost.py" "$WORK/log" 34835)"
done
