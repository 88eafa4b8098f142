#!/bin/bash
# The equal-time table of bench/mbdpt/RESULTS.md ("The paper's configuration and the equal-time
# table"): the two paper scenes (made by make_ajar_hidden.py and make_multiroom.py) and the
# Cornell box, budgets 20, 40 and 120 s, 4 seeds, two renders at a time with one thread each
# (a 2-core machine; nothing else may run meanwhile).
#   bench/mbdpt/paper_table.sh SCENEDIR REFDIR OUTDIR
# SCENEDIR: veach-ajar-hidden.pbrt, multiroom-ajar.pbrt; REFDIR: their references
# veach-ajar-hidden-ref.exr, multiroom-ajar-ref.exr (bdpt, see RESULTS.md).
# Environment: GRADUS_BIN (a private copy of gradus and imgtool), SHARED (../shared),
# TIMES (default "20 40 120"), SEEDS (default 4).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
scenes=$1 refs=$2 out=$3
shared=${SHARED:-$here/../../../shared}
times=${TIMES:-20 40 120}
seeds=${SEEDS:-4}
mkdir -p "$out"
paper="bdpt bdpt:rrdepth=-1 mbdpt mbdpt:rrdepth=-1 mbdpt:configuration=paper"
for t in $times; do
    "$here/equal_spp.py" "$scenes/veach-ajar-hidden.pbrt" "$refs/veach-ajar-hidden-ref.exr" --time "$t" \
        --seeds "$seeds" --jobs 2 --ref-noise 0.52 --args "--resolution 320x180 --nthreads 1" \
        --outdir "$out/renders" $paper > "$out/hidden-$t.md"
    "$here/equal_spp.py" "$scenes/multiroom-ajar.pbrt" "$refs/multiroom-ajar-ref.exr" --time "$t" \
        --seeds "$seeds" --jobs 2 --ref-noise 0.62 --args "--nthreads 1" \
        --outdir "$out/renders" $paper > "$out/multiroom-$t.md"
    # The Cornell box (maxdepth 65): every configuration at 20 and 40 s, the defaults at 120 s.
    configs=$paper
    [ "$t" -gt 40 ] && configs="bdpt mbdpt"
    "$here/equal_spp.py" "$shared/references/cornell-box/ref.pbrt" "$shared/references/cornell-box/ref.exr" \
        --time "$t" --seeds "$seeds" --jobs 2 --ref-noise "$(cut -d' ' -f1 "$shared/references/cornell-box/ref.noise")" \
        --args "--nthreads 1" --outdir "$out/renders" $configs > "$out/cornell-$t.md"
done
cat "$out"/*.md
