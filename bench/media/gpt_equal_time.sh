#!/bin/sh
# gpt against path at equal time on the shared media scenes (issue 56): one
# render per scene and integrator at TIME seconds (default 60), 2 threads,
# seed 1, under the shared bench lock; then imgtool diff against the pbrt-v3
# references (the unprefixed image: gpt's hybrid reconstruction; and gpt's
# primal). Results in OUT (default /tmp/gradus-gpt-media-<date>); figures in
# bench/media/RESULTS.md.
set -e
cd "$(dirname "$0")/../.."
TIME=${TIME:-60}
OUT=${OUT:-/tmp/gradus-gpt-media-$(date +%Y%m%d-%H%M)}
mkdir -p "$OUT"
for scene in smoke-grid fog-spotlight; do
  for i in gpt path; do
    echo "$scene $i load $(cut -d' ' -f1-3 /proc/loadavg)"
    flock /work/bench.lock build/bin/gradus ../shared/scenes/$scene/scene.pbrt --integrator $i --time "$TIME" \
      --nthreads 2 --seed 1 --outfile "$OUT/${scene}_$i.exr" --quiet
    build/bin/imgtool info "$OUT/${scene}_$i.exr" | grep -E "^  (spp|cpu_seconds) "
    build/bin/imgtool diff "$OUT/${scene}_$i.exr" ../shared/references/$scene/ref.exr | grep -E "relMSE|mean"
    if [ $i = gpt ]; then
      build/bin/imgtool diff "$OUT/${scene}_$i.exr" ../shared/references/$scene/ref.exr --layer primal | grep relMSE
    fi
  done
done
echo "results in $OUT"
