#!/usr/bin/env bash
# Seconds per iteration (one sample per pixel) of vcm, bdpt, gbdpt and gvcm on
# water-caustic (the scene's merging radius 0.01) at 256^2, 512^2 and 1024^2:
# `seconds_passes` of the EXR divided by its spp, 2 threads. Run on a quiet machine.
#   bench/gvcm/iteration_cost.sh [BIN_DIR] > iteration_cost.csv
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/build/bin}
scene=${GRADUS_SHARED:-$root/../shared}/references/water-caustic/ref.pbrt
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "resolution,integrator,spp,seconds_passes,seconds_per_iteration,peak_rss_mb"
run() {  # resolution spp label gradus-args...
    local res=$1 spp=$2 label=$3
    shift 3
    "$bin/gradus" "$scene" --resolution "${res}x${res}" --spp "$spp" --nthreads 2 --quiet \
        --outfile "$tmp/out.exr" "$@" 2>/dev/null
    local info secs rss
    info=$("$bin/imgtool" info "$tmp/out.exr")
    secs=$(sed -n 's/^ *seconds_passes = //p' <<<"$info")
    rss=$(sed -n 's/^ *peak_rss_mb = //p' <<<"$info")
    python3 -c "print('%s,%s,%s,%.3f,%.3f,%s' % ('$res', '$label', $spp, $secs, $secs / $spp, '$rss'))"
}
for res in ${RESOLUTIONS:-256 512 1024}; do
    spp=$((res == 256 ? 8 : res == 512 ? 2 : 1))
    run $res $spp vcm --integrator vcm
    run $res $spp bdpt --integrator bdpt
    run $res $spp gbdpt --integrator gbdpt
    run $res $spp "gvcm" --integrator gvcm
    # Every photon shifted through case 2 (case2budget 0): 1024^2 takes > 14 min per iteration.
    [ "$res" -le 512 ] && run $res 1 "gvcm case2budget 0" --integrator gvcm --param case2budget=0
done
