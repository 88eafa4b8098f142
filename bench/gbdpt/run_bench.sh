#!/usr/bin/env bash
# G-BDPT against BDPT (gradient-domain-bdpt.md Sec. 5, issue "G-BDPT: the same image
# as BDPT, at full speed"), through the bench harness (bench/run):
#  1. equal wall time, several budgets: relMSE and image mean of BDPT and of G-BDPT's
#     default (hybrid) reconstruction, L1, L2 and its primal, against the shared
#     pbrt-v3 references and the reference of scenes/glass-env.pbrt (made by reference
#     mode, see below); every row of a budget uses the scene's pixel filter;
#  2. overhead at equal base samples (Table 1), light tracing on.
#
# usage: bench/gbdpt/run_bench.sh [--times 10,20,40] [--seeds 2] [--spp 8]
#                                 [--refdir DIR] [--out DIR] [--bin-dir DIR]
# The glass-env reference (not in the repository):
#   bench/run --make-reference --scenes local-glass-env --ref-spp 8192 --ref-runs 4 --refdir DIR
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
TIMES=10,20,40
SEEDS=2
SPP=8
REFDIR=$ROOT/bench/refs
OUT=${TMPDIR:-/tmp}/gbdpt-bench
BIN=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --times) TIMES=$2; shift 2;;
    --seeds) SEEDS=$2; shift 2;;
    --spp) SPP=$2; shift 2;;
    --refdir) REFDIR=$2; shift 2;;
    --out) OUT=$2; shift 2;;
    --bin-dir) BIN=(--bin-dir "$2"); shift 2;;
    *) echo "unknown argument $1" >&2; exit 2;;
  esac
done
SCENES=veach-ajar,veach-bidir,cornell-box,local-glass-env
"$ROOT/bench/run" "${BIN[@]}" --scenes "$SCENES" --refdir "$REFDIR" --times "$TIMES" --seeds "$SEEDS" \
  --nthreads 2 --integrators 'bdpt,gbdpt,gbdpt/reconstructed_l1,gbdpt/reconstructed_l2,gbdpt/primal' \
  --out "$OUT/equal-time"
"$ROOT/bench/run" "${BIN[@]}" --scenes "$SCENES" --refdir "$REFDIR" --overhead gbdpt:bdpt --spp "$SPP" \
  --seeds "$SEEDS" --nthreads 2 --out "$OUT/overhead"
