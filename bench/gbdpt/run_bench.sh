#!/usr/bin/env bash
# G-BDPT benchmark (gradient-domain-bdpt.md Sec. 5):
#  1. equal-time relMSE of G-BDPT (L1 and L2 reconstruction, and its primal)
#     against BDPT on the shared pbrt-v3 references (papers' metric, imgtool diff);
#  2. overhead at equal base samples per pixel (Table 1): time(G-BDPT) /
#     time(BDPT) with light-tracing paths shifted, without (lighttracing false),
#     and with the half-vector shift instead of the manifold shift.
#
# usage: bench/gbdpt/run_bench.sh [--gradus BIN] [--imgtool BIN] [--time S] [--spp N]
#                                 [--threads N] [--seed S] [--out DIR] [scene ...]
# scenes: names under ../shared/references (beside the repository) (default: veach-ajar veach-bidir cornell-box).
# Both integrators render the same scene file with the same light-selection
# strategy ("power": position-free, which G-BDPT's MIS requires). veach-bidir's
# relMSE ignores the 0.01% highest pixel errors, as the G-BDPT paper does.
# Times are the render seconds gradus stores in the image (wall clock); the
# machine is shared, so CPU seconds (user+sys of the process) are printed too.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
GRADUS=$ROOT/build/bin/gradus
IMGTOOL=""
TIME=30
SPP=8
THREADS=2
SEED=1
OUT=${TMPDIR:-/tmp}/gbdpt-bench
REFS=$(cd "$ROOT/.." && pwd)/shared/references
SCENES=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --gradus) GRADUS=$2; shift 2;;
    --imgtool) IMGTOOL=$2; shift 2;;
    --time) TIME=$2; shift 2;;
    --spp) SPP=$2; shift 2;;
    --threads) THREADS=$2; shift 2;;
    --seed) SEED=$2; shift 2;;
    --out) OUT=$2; shift 2;;
    *) SCENES+=("$1"); shift;;
  esac
done
[[ ${#SCENES[@]} -eq 0 ]] && SCENES=(veach-ajar veach-bidir cornell-box)
[[ -z $IMGTOOL ]] && IMGTOOL=$(dirname "$GRADUS")/imgtool
mkdir -p "$OUT"

relmse() {  # image layer reference discard-fraction
  local args=()
  [[ -n $2 ]] && args+=(--layer "$2")
  [[ $4 != 0 ]] && args+=(--discard-fraction "$4")
  "$IMGTOOL" diff "$1" "$3" "${args[@]}" | awk '/relMSE/ {print $2}'
}
seconds() { "$IMGTOOL" info "$1" | awk '/render_seconds/ {print $3}'; }
spp_of() { "$IMGTOOL" info "$1" | awk '/ spp = / {print $3}'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN{ if (b > 0) printf "%.2f", a/b; else print "-" }'; }
# Runs gradus and prints its CPU seconds (user + sys).
run() {
  /usr/bin/time -f "%U %S" -o "$OUT/.cpu" "$GRADUS" "$@" > /dev/null 2>> "$OUT/gradus.log"
  awk '{printf "%.1f", $1+$2}' "$OUT/.cpu"
}

{
echo "# G-BDPT vs BDPT ($(date -u +%F), commit $(git -C "$ROOT" rev-parse --short HEAD), ${THREADS} threads, shared machine)"
echo
for s in "${SCENES[@]}"; do
  ref=$REFS/$s/ref.exr
  noise=$(cat "$REFS/$s/ref.noise" 2>/dev/null || echo "?")
  src=$REFS/$s/ref.pbrt
  work=$OUT/$s; mkdir -p "$work"
  disc=0
  [[ $s == veach-bidir ]] && disc=0.0001
  # Variants in $work (the references' folder is read-only), asset paths made absolute.
  mk() {  # name integrator-line
    sed -e "s#\"\\.\\./\\.\\./scenes/#\"$REFS/../scenes/#g" \
        -e "s#^Integrator \"[a-z]*\"#$2#" "$src" > "$work/$1.pbrt"
  }
  depth=$(grep -o '^Integrator.*maxdepth" *\[ *[0-9]*' "$src" | grep -o '[0-9]*$' || echo 5)
  md="\"integer maxdepth\" [$depth] \"string lightsamplestrategy\" \"power\""
  mk bdpt "Integrator \"bdpt\" $md #"
  mk gbdpt "Integrator \"gbdpt\" $md #"
  mk gbdpt_nolt "Integrator \"gbdpt\" $md \"bool lighttracing\" \"false\" #"
  mk gbdpt_hv "Integrator \"gbdpt\" $md \"string shift\" \"halfvector\" #"

  echo "## $s (maxdepth $depth; reference noise floor relMSE $noise; trimmed fraction $disc)"
  echo
  echo "Equal time, ${TIME}s:"
  echo
  echo "| method | spp | CPU s | relMSE | BDPT relMSE / relMSE |"
  echo "|---|---|---|---|---|"
  cb=$(run "$work/bdpt.pbrt" --time "$TIME" --nthreads "$THREADS" --seed "$SEED" --quiet --outfile "$work/bdpt_t.exr")
  eb=$(relmse "$work/bdpt_t.exr" "" "$ref" $disc)
  echo "| bdpt | $(spp_of "$work/bdpt_t.exr") | $cb | $eb | 1.00 |"
  for v in gbdpt gbdpt_hv; do
    cg=$(run "$work/$v.pbrt" --time "$TIME" --nthreads "$THREADS" --seed "$SEED" --quiet --outfile "$work/${v}_t.exr")
    for layer in primal reconstructed_l1 reconstructed_l2; do
      e=$(relmse "$work/${v}_t.exr" "$layer" "$ref" $disc)
      echo "| $v $layer | $(spp_of "$work/${v}_t.exr") | $cg | $e | $(ratio "$eb" "$e") |"
    done
  done
  echo
  echo "Overhead at $SPP spp (render seconds, wall clock; CPU seconds in brackets):"
  echo
  echo "| configuration | BDPT | G-BDPT | factor (wall) | factor (CPU) |"
  echo "|---|---|---|---|---|"
  cb=$(run "$work/bdpt.pbrt" --spp "$SPP" --nthreads "$THREADS" --seed 2 --quiet --outfile "$work/bdpt_s.exr")
  tb=$(seconds "$work/bdpt_s.exr")
  for v in gbdpt_nolt gbdpt gbdpt_hv; do
    cg=$(run "$work/$v.pbrt" --spp "$SPP" --nthreads "$THREADS" --seed 2 --quiet --outfile "$work/${v}_s.exr")
    tg=$(seconds "$work/${v}_s.exr")
    echo "| $v | ${tb}s [${cb}] | ${tg}s [${cg}] | $(ratio "$tg" "$tb") | $(ratio "$cg" "$cb") |"
  done
  echo
  echo '```'
  "$GRADUS" "$work/gbdpt.pbrt" --spp 1 --nthreads "$THREADS" --seed 3 --outfile "$work/stats.exr" 2>&1 \
    | sed -n '/G-BDPT shifts/,/^Reconstruction/p'
  echo '```'
  echo
done
} | tee "$OUT/results.md"
