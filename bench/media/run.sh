#!/bin/sh
# Equal-time comparison on the shared media and subsurface scenes (issue 42):
# path, bdpt and vcm on fog-spotlight and smoke-grid, path on subsurface-trio
# (the bidirectional integrators refuse BSSRDFs), at TIMES seconds (default
# 30,120) with SEEDS seeds (default 1). Results (renders included) in OUT
# (default /tmp/gradus-media-bench-<date>); the CSVs of a measured run and
# their reading are in bench/media/RESULTS.md.
set -e
cd "$(dirname "$0")/../.."
TIMES=${TIMES:-30,120}
SEEDS=${SEEDS:-1}
OUT=${OUT:-/tmp/gradus-media-bench-$(date +%Y%m%d-%H%M)}
bench/run --scenes fog-spotlight,smoke-grid --integrators path,bdpt,vcm --times "$TIMES" --seeds "$SEEDS" \
  --nthreads 2 --out "$OUT/volumes" "$@"
bench/run --scenes subsurface-trio --integrators path --times "$TIMES" --seeds "$SEEDS" \
  --nthreads 2 --out "$OUT/subsurface" "$@"
echo "results in $OUT"
