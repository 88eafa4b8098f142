#!/usr/bin/env bash
# The G-MLT paper's conditions (issue 58, item 4): pmlt and gmlt at ~230 000 pixels, equal wall
# time, 2 threads, seeds 0..SEEDS-1; gbdpt (GBDPT_SEEDS seeds on GBDPT_SCENES) for the comparison of
# Table 1's kind; mlt (MLT_SEEDS seeds, last) for its image mean. One run at a
# time (each takes both cores), seeds interleaved so that a cut-short session keeps whole seeds.
#
#   python3 bench/gmlt/make_paper_scenes.py
#   bench/gmlt/paper_bench.sh OUTDIR            # TIME=300 SEEDS=3 by default
#   bench/gmlt/paper_analyze.py OUTDIR          # relMSE, means, seed-pair variance (numpy)
#
# Every run writes OUTDIR/<scene>-<integrator>-s<seed>.exr and .log (gradus --stats).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
OUT="${1:?usage: paper_bench.sh OUTDIR}"
BIN="${GRADUS_BIN:-$ROOT/build/bin}"
TIME="${TIME:-300}"
SEEDS="${SEEDS:-3}"
GBDPT_SEEDS="${GBDPT_SEEDS:-1}"
GBDPT_SCENES="${GBDPT_SCENES:-door-560 torus-560}"
SCENES="${SCENES:-door-560 torus-560 veach-ajar-640}"
INTEGRATORS="${INTEGRATORS:-pmlt gmlt}"
mkdir -p "$OUT"

run() {  # scene integrator seed
    local base="$OUT/$1-$2-s$3"
    [ -f "$base.exr" ] && return 0
    echo "$(date +%T) $1 $2 seed $3 (load $(cut -d' ' -f1 /proc/loadavg))"
    "$BIN/gradus" "$ROOT/bench/gmlt/paper/$1.pbrt" --integrator "$2" --time "$TIME" --nthreads 2 \
        --seed "$3" --stats --quiet --outfile "$base.exr" > "$base.log" 2>&1
}

MLT_SEEDS="${MLT_SEEDS:-1}"
for ((s = 0; s < SEEDS; ++s)); do
    for scene in $SCENES; do
        for integ in $INTEGRATORS; do run "$scene" "$integ" "$s"; done
        if ((s < GBDPT_SEEDS)) && [[ " $GBDPT_SCENES " == *" $scene "* ]]; then run "$scene" gbdpt "$s"; fi
    done
done
# mlt (pbrt-v3's; its image mean is in the issue's goal too).
for ((m = 0; m < MLT_SEEDS; ++m)); do for scene in $SCENES; do run "$scene" mlt "$m"; done; done
