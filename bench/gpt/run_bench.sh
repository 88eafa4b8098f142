#!/usr/bin/env bash
# Equal-time comparison of G-PT (L1 and L2 reconstruction) with the path
# tracer, and the overhead factor of G-PT at equal base samples per pixel
# (the G-PT papers' Table 1 metric: time(G-PT) / time(PT) at equal spp).
#
# usage: bench/gpt/run_bench.sh [--gradus BIN] [--imgtool BIN] [--time S] [--spp N]
#                               [--threads N] [--out DIR] [scene ...]
# scenes: names under ../shared/references (beside the repository) (default: cornell-box veach-mis).
# G-PT runs twice: "box" (gradients with box-filter semantics, the default)
# and "film" (primal and gradients splatted with the scene's pixel filter,
# which the pbrt-v3 references use). relMSE is imgtool's (the papers' metric,
# epsilon 0.001); the reference's own noise (ref.noise) is printed beside it.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
GRADUS=$ROOT/build/bin/gradus
IMGTOOL=""
TIME=15
SPP=16
THREADS=2
OUT=${TMPDIR:-/tmp}/gpt-bench
REFS=$(cd "$ROOT/.." && pwd)/shared/references
SCENES=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --gradus) GRADUS=$2; shift 2;;
    --imgtool) IMGTOOL=$2; shift 2;;
    --time) TIME=$2; shift 2;;
    --spp) SPP=$2; shift 2;;
    --threads) THREADS=$2; shift 2;;
    --out) OUT=$2; shift 2;;
    *) SCENES+=("$1"); shift;;
  esac
done
[[ ${#SCENES[@]} -eq 0 ]] && SCENES=(cornell-box veach-mis)
[[ -z $IMGTOOL ]] && IMGTOOL=$(dirname "$GRADUS")/imgtool
[[ -x $IMGTOOL ]] || IMGTOOL=$ROOT/build/bin/imgtool
mkdir -p "$OUT"

relmse() {  # image layer reference
  local layer=()
  [[ -n $2 ]] && layer=(--layer "$2")
  "$IMGTOOL" diff "$1" "$3" "${layer[@]}" | awk '/relMSE/ {print $2}'
}
seconds() { "$IMGTOOL" info "$1" | awk '/render_seconds/ {print $3}'; }
spp_of() { "$IMGTOOL" info "$1" | awk '/ spp = / {print $3}'; }

{
echo "# G-PT vs path tracing ($(date -u +%F), ${THREADS} threads, ${TIME}s per equal-time run, machine shared)"
echo
for s in "${SCENES[@]}"; do
  ref=$REFS/$s/ref.exr
  noise=$(cat "$REFS/$s/ref.noise" 2>/dev/null || echo "?")
  src=$REFS/$s/ref.pbrt
  work=$OUT/$s; mkdir -p "$work"
  # The references' folder is read-only: variants go to $work with asset paths made absolute.
  fix() { sed -e "s#\"\\.\\./\\.\\./scenes/#\"$REFS/../scenes/#g" "$src"; }
  # One light (cornell-box): "power" is the same distribution as "spatial" without
  # the per-voxel precomputation, which would dominate short runs of both integrators.
  ls=""
  [[ $s == cornell-box ]] && ls=' "string lightsamplestrategy" "power"'
  fix | sed -e "s/^Integrator \"path\"/Integrator \"path\"$ls/" > "$work/pt.pbrt"
  fix | sed -e "s/^Integrator \"path\"/Integrator \"gpt\" \"string pixelfilter\" \"box\"$ls/" > "$work/gpt_box.pbrt"
  fix | sed -e "s/^Integrator \"path\"/Integrator \"gpt\" \"string pixelfilter\" \"film\"$ls/" > "$work/gpt_film.pbrt"

  echo "## $s (reference noise floor relMSE $noise)"
  echo
  echo "| method | spp in ${TIME}s | relMSE | vs PT |"
  echo "|---|---|---|---|"
  "$GRADUS" "$work/pt.pbrt" --time "$TIME" --nthreads "$THREADS" --seed 1 --quiet --outfile "$work/pt_t.exr"
  pt=$(relmse "$work/pt_t.exr" "" "$ref")
  echo "| path | $(spp_of "$work/pt_t.exr") | $pt | 1.00 |"
  for v in box film; do
    "$GRADUS" "$work/gpt_$v.pbrt" --time "$TIME" --nthreads "$THREADS" --seed 1 --quiet --outfile "$work/gpt_${v}_t.exr"
    n=$(spp_of "$work/gpt_${v}_t.exr")
    for layer in primal reconstructed_l1 reconstructed_l2; do
      e=$(relmse "$work/gpt_${v}_t.exr" "$layer" "$ref")
      echo "| gpt-$v $layer | $n | $e | $(awk -v a="$pt" -v b="$e" 'BEGIN{printf "%.2f", a/b}') |"
    done
  done
  echo
  # Overhead at equal base samples (render time only; reconstruction printed separately).
  "$GRADUS" "$work/pt.pbrt" --spp "$SPP" --nthreads "$THREADS" --seed 2 --quiet --outfile "$work/pt_s.exr"
  "$GRADUS" "$work/gpt_box.pbrt" --spp "$SPP" --nthreads "$THREADS" --seed 2 --outfile "$work/gpt_s.exr" \
    2> "$work/gpt_s.log"
  tp=$(seconds "$work/pt_s.exr"); tg=$(seconds "$work/gpt_s.exr")
  echo "Overhead at $SPP spp: path ${tp}s, gpt ${tg}s, factor $(awk -v a="$tg" -v b="$tp" 'BEGIN{printf "%.2f", a/b}')"
  grep -E "Reconstruction:" "$work/gpt_s.log" || true
  echo
  echo '```'
  sed -n '/G-PT shifts/,/failed: escaped/p' "$work/gpt_s.log"
  echo '```'
  echo
done
} | tee "$OUT/results.md"
