#!/bin/sh
# gpt and path on smoke-grid side by side, one thread each, TIME seconds (default
# 300), seeds 1 and 2, under the shared bench lock (both renders get the same
# share of a loaded machine); then imgtool against the pbrt-v3 reference.
# Figures in bench/media/RESULTS.md.
set -e
cd "$(dirname "$0")/../.."
TIME=${TIME:-300}
OUT=${OUT:-/tmp/gradus-gpt-side-$(date +%Y%m%d-%H%M)}
mkdir -p "$OUT"
for seed in 1 2; do
  echo "seed $seed start $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
  flock /work/bench.lock sh -c "
    build/bin/gradus ../shared/scenes/smoke-grid/scene.pbrt --integrator gpt --time $TIME --nthreads 1 --seed $seed --outfile $OUT/smoke_gpt_s$seed.exr --quiet &
    build/bin/gradus ../shared/scenes/smoke-grid/scene.pbrt --integrator path --time $TIME --nthreads 1 --seed $seed --outfile $OUT/smoke_path_s$seed.exr --quiet &
    wait"
  echo "seed $seed end $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
  for i in gpt path; do
    build/bin/imgtool info "$OUT/smoke_${i}_s$seed.exr" | grep -E "^  (spp|cpu_seconds) "
    build/bin/imgtool diff "$OUT/smoke_${i}_s$seed.exr" ../shared/references/smoke-grid/ref.exr | grep -E "relMSE|mean"
  done
done
