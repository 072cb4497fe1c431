#!/usr/bin/env bash
# Runs every benchmark script (bench/run_*.sh) against the given build and
# leaves their results in bench/results/. Usage: bench/run_all.sh [BUILD_DIR]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
status=0
for script in "$ROOT"/bench/run_*.sh; do
  [ "$(basename "$script")" = run_all.sh ] && continue
  echo "== $(basename "$script")"
  bash "$script" "$BUILD" || { echo "bench: $(basename "$script") failed" >&2; status=1; }
done
exit $status
