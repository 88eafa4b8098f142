#!/bin/sh
# gbdpt against bdpt at equal time on fog-spotlight (issue 56, item 2): one
# render per integrator at TIME seconds (default 60), 2 threads, seed SEED
# (default 1), each under the shared bench lock; then imgtool diff against the
# pbrt-v3 reference (the unprefixed image: gbdpt's hybrid reconstruction; and
# gbdpt's primal, L1 and L2 layers). Results in OUT (default
# /tmp/gradus-gbdpt-media-<date>); figures in bench/media/RESULTS.md.
set -e
cd "$(dirname "$0")/../.."
TIME=${TIME:-60}
SEED=${SEED:-1}
SCENES=${SCENES:-fog-spotlight}
OUT=${OUT:-/tmp/gradus-gbdpt-media-$(date +%Y%m%d-%H%M)}
mkdir -p "$OUT"
for scene in $SCENES; do
  for i in gbdpt bdpt; do
    f="$OUT/${scene}_${i}_t${TIME}_s${SEED}.exr"
    echo "$scene $i ${TIME}s seed $SEED: load before $(cut -d' ' -f1-3 /proc/loadavg)"
    flock /work/bench.lock build/bin/gradus ../shared/scenes/$scene/scene.pbrt --integrator $i --time "$TIME" \
      --spp 1048576 --nthreads 2 --seed "$SEED" --outfile "$f" --quiet
    echo "  load after $(cut -d' ' -f1-3 /proc/loadavg)"
    build/bin/imgtool info "$f" | grep -E "^  (spp|cpu_seconds|render_seconds|stop_reason) "
    build/bin/imgtool diff "$f" ../shared/references/$scene/ref.exr | grep -E "relMSE|mean"
    if [ $i = gbdpt ]; then
      for l in primal reconstructed_l1 reconstructed_l2; do
        echo "  layer $l: $(build/bin/imgtool diff "$f" ../shared/references/$scene/ref.exr --layer $l | grep relMSE)"
      done
    fi
  done
done
echo "results in $OUT"
