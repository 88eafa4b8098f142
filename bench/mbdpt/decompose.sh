#!/usr/bin/env bash
# Per-strategy variance decomposition of BDPT and M-BDPT at equal spp (issue
# "M-BDPT: make the matrix pay for itself"): every integrator renders the scene
# twice (seeds 1 and 2) with MIS-weighted strategy layers ("visualizeweights");
# for two independent renders X1, X2 of a layer, E[(X1 - X2)^2] = 2 Var, so
# imgtool's MSE between the seeds / 2 is the layer's mean per-pixel variance.
# The layers sum to the image, so the table says which (s, t) carries the
# variance and where M-BDPT gains or loses against BDPT.
#
# usage: bench/mbdpt/decompose.sh SCENE.pbrt [SPP] [INTEGRATOR[:PARAM=VALUE,...] ...]
#   default integrators: bdpt mbdpt mbdpt:matrixsampler=pixel
# environment: GRADUS_BIN (directory of gradus and imgtool), GRADUS_ARGS (more gradus
#   options for every render, e.g. "--resolution 640x360 --nthreads 2"), TMPDIR (images go
#   to $TMPDIR/mbdpt-decompose), STRATEGIES (only these strategies, e.g. "s1_t2 s2_t2": each
#   layer's diff reads both images again, ~120 layers at maxdepth 13), REUSE=1 (keep renders
#   already in the output directory)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BIN=${GRADUS_BIN:-$ROOT/build/bin}
SCENE=$1
SPP=${2:-16}
read -ra EXTRA <<< "${GRADUS_ARGS:-}"
shift $(( $# >= 2 ? 2 : $# ))
INTS=("$@")
[[ ${#INTS[@]} -gt 0 ]] || INTS=(bdpt mbdpt mbdpt:matrixsampler=pixel)
OUT=${TMPDIR:-/tmp}/mbdpt-decompose
mkdir -p "$OUT"
declare -A VAR
# The MSE from diff's JSON (its text output ends with RMSE as the last line ending in a
# number: reading that line gave RMSE / 2 instead of the variance before 2026-12-05).
mse_of() { python3 -c 'import json, sys; print(json.load(sys.stdin)["mse"])'; }
LAYERS=()
for spec in "${INTS[@]}"; do
  name=${spec%%:*}
  params=()
  if [[ $spec == *:* ]]; then
    IFS=, read -ra kv <<< "${spec#*:}"
    for p in "${kv[@]}"; do params+=(--param "$p"); done
  fi
  tag=$(echo "$spec" | tr ':=,' '___')
  for seed in 1 2; do
    [[ ${REUSE:-0} == 1 && -s $OUT/$tag-$seed.exr ]] && continue
    "$BIN/gradus" "$SCENE" --integrator "$name" "${params[@]}" --param visualizeweights=true \
      --spp "$SPP" --seed $seed "${EXTRA[@]}" --quiet --outfile "$OUT/$tag-$seed.exr"
  done
  # Layers: <integrator>_s<S>_t<T>
  mapfile -t ls < <("$BIN/imgtool" info "$OUT/$tag-1.exr" | grep -oE "${name}_s[0-9]+_t[0-9]+" | sort -u)
  for l in "${ls[@]}"; do
    st=${l#${name}_}
    [[ -z ${STRATEGIES:-} || " $STRATEGIES " == *" $st "* ]] || continue
    mse=$("$BIN/imgtool" diff "$OUT/$tag-1.exr" "$OUT/$tag-2.exr" --layer "$l" --metric mse --json | mse_of)
    VAR[$tag,$st]=$(python3 -c "print('%.3e' % ($mse / 2))")
    [[ " ${LAYERS[*]} " == *" $st "* ]] || LAYERS+=("$st")
  done
  mse=$("$BIN/imgtool" diff "$OUT/$tag-1.exr" "$OUT/$tag-2.exr" --metric mse --json | mse_of)
  VAR[$tag,image]=$(python3 -c "print('%.3e' % ($mse / 2))")
done
printf "mean per-pixel variance at %s spp, %s\n\n| strategy |" "$SPP" "$(basename "$SCENE")"
for spec in "${INTS[@]}"; do printf " %s |" "$spec"; done
printf "\n|---|"
for spec in "${INTS[@]}"; do printf -- "---|"; done
printf "\n"
for st in $(printf "%s\n" "${LAYERS[@]}" | sort -t_ -k1.2n -k2.2n) image; do
  printf "| %s |" "$st"
  for spec in "${INTS[@]}"; do
    tag=$(echo "$spec" | tr ':=,' '___')
    printf " %s |" "${VAR[$tag,$st]:--}"
  done
  printf "\n"
done
