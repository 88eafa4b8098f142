#!/usr/bin/env bash
# Seconds per iteration (one sample per pixel) of vcm, bdpt, gbdpt and gvcm on
# water-caustic (the scene's merging radius 0.01) at 256^2, 512^2 and 1024^2:
# `seconds_passes` of the EXR divided by its spp, 2 threads. Run on a quiet machine; on a
# loaded one compare cpu_per_iteration (`cpu_seconds_passes` / spp: processor seconds of the
# passes alone, which the machine's load changes far less than the wall time).
# cpu_seconds (the whole process) and cores = cpu_seconds / (preprocess + passes + finish)
# say how much of the machine the run got;
# lane_occupancy and the passes' serial share (1 - seconds_parallel / seconds_passes) how
# much the scheduling left idle, whatever the load.
#   bench/gvcm/iteration_cost.sh [BIN_DIR] > iteration_cost.csv
# RESOLUTIONS="256 512" and LABELS="vcm gvcm" (of vcm bdpt gbdpt gvcm gvcm-k0) select runs.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/build/bin}
scene=${GRADUS_SHARED:-$root/../shared}/references/water-caustic/ref.pbrt
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "resolution,integrator,spp,seconds_passes,seconds_per_iteration,peak_rss_mb,cpu_seconds,cores,cpu_per_iteration,lane_occupancy,serial_share,loadavg"
labels=" ${LABELS:-vcm bdpt gbdpt gvcm gvcm-k0} "
run() {  # resolution spp label key gradus-args...
    local res=$1 spp=$2 label=$3 key=$4
    shift 4
    [[ "$labels" == *" $key "* ]] || return 0
    "$bin/gradus" "$scene" --resolution "${res}x${res}" --spp "$spp" --nthreads 2 --quiet \
        --outfile "$tmp/out.exr" "$@" 2>/dev/null
    local info secs rss cpu wall load occ par cpup
    load=$(cut -d' ' -f1 /proc/loadavg)
    info=$("$bin/imgtool" info "$tmp/out.exr")
    secs=$(sed -n 's/^ *seconds_passes = //p' <<<"$info")
    rss=$(sed -n 's/^ *peak_rss_mb = //p' <<<"$info")
    cpu=$(sed -n 's/^ *cpu_seconds = //p' <<<"$info")
    occ=$(sed -n 's/^ *lane_occupancy = //p' <<<"$info")
    cpup=$(sed -n 's/^ *cpu_seconds_passes = //p' <<<"$info")
    par=$(sed -n 's/^ *seconds_parallel = //p' <<<"$info")
    wall=$(sed -n 's/^ *seconds_\(preprocess\|passes\|finish\) = //p' <<<"$info" | paste -sd+)
    python3 -c "print('%s,%s,%s,%.3f,%.3f,%s,%.2f,%.2f,%.3f,%.4f,%.4f,%s' % ('$res', '$label', $spp, $secs, $secs / $spp, '$rss', $cpu, $cpu / ($wall), ${cpup:-0} / $spp, ${occ:-0}, 1 - ${par:-0} / $secs, '$load'))"
}
for res in ${RESOLUTIONS:-256 512 1024}; do
    spp=$((res == 256 ? 8 : res == 512 ? 2 : 1))
    run $res $spp vcm vcm --integrator vcm
    run $res $spp bdpt bdpt --integrator bdpt
    run $res $spp gbdpt gbdpt --integrator gbdpt
    run $res $spp "gvcm" gvcm --integrator gvcm
    # Every photon shifted through case 2 (case2budget 0): 1024^2 takes > 14 min per iteration.
    [ "$res" -le 512 ] && run $res 1 "gvcm case2budget 0" gvcm-k0 --integrator gvcm --param case2budget=0
done
