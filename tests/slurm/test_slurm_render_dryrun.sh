#!/usr/bin/env bash
# scripts/slurm-render --dry-run (no Slurm, no renderer): the pass ranges and the commands for
# K=4 tasks and N=10 passes, and the errors on bad arguments.
# usage: test_slurm_render_dryrun.sh SOURCE_DIR
set -uo pipefail
src=${1:?usage: $0 SOURCE_DIR}
script=$src/scripts/slurm-render
scene=$src/scenes/cornell-box.pbrt
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# Stand-in binaries: the dry run only checks that they are executable files.
printf '#!/bin/sh\nexit 0\n' >"$tmp/gradus"
cp "$tmp/gradus" "$tmp/imgtool"
chmod +x "$tmp/gradus" "$tmp/imgtool"
bins=(--gradus "$tmp/gradus" --imgtool "$tmp/imgtool")
failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}
expect_line() { # expect_line OUTPUT LINE: OUTPUT has exactly LINE among its lines
  grep -qxF -- "$2" <<<"$1" || fail "missing line: $2"
}

out=$("$script" --dry-run --tasks 4 --outdir "$tmp/run" --partition fast "${bins[@]}" \
  --sbatch-args "--time=5 --mem=1G" "$scene" -- --spp 10 --integrator gpt --seed 7 2>&1)
rc=$?
[ $rc = 0 ] || fail "dry run exited $rc: $out"
# floor(k*10/4) for k = 0..4: 0 2 5 7 10.
ranges=(0:2 2:5 5:7 7:10)
for k in 0 1 2 3; do
  expect_line "$out" "# task $k: $tmp/gradus $scene --spp 10 --integrator gpt --seed 7 --passes ${ranges[$k]} --checkpoint $tmp/run/part_$k.ckpt --quiet"
done
[ "$(grep -c '^# task ' <<<"$out")" = 4 ] || fail "expected 4 tasks"
expect_line "$out" "# finish: $tmp/imgtool merge $tmp/run/merged.ckpt $tmp/run/part_0.ckpt $tmp/run/part_1.ckpt $tmp/run/part_2.ckpt $tmp/run/part_3.ckpt"
expect_line "$out" "# finish: $tmp/gradus $scene --spp 10 --integrator gpt --seed 7 --resume $tmp/run/merged.ckpt --outfile $tmp/run/final.exr --quiet"
expect_line "$out" "sbatch --parsable --array=0-3 --job-name=gradus-part --output=$tmp/run/logs/part_%a.out --partition=fast --time=5 --mem=1G $tmp/run/task.sh"
expect_line "$out" "sbatch --parsable --dependency=afterok:ARRAYID --kill-on-invalid-dep=yes --job-name=gradus-finish --output=$tmp/run/logs/finish.out --partition=fast --time=5 --mem=1G $tmp/run/finish.sh"
[ ! -e "$tmp/run" ] || fail "the dry run created the output directory"

# A relative scene and outdir become absolute (the nodes see the same paths); spaces are quoted.
out=$(cd "$src" && "$script" --dry-run --tasks 2 --outdir "rel dir" "${bins[@]}" \
  scenes/cornell-box.pbrt -- --spp 3 --param 'a=b c' 2>&1)
expect_line "$out" "# task 0: $tmp/gradus $scene --spp 3 --param a=b\\ c --passes 0:1 --checkpoint $src/rel\\ dir/part_0.ckpt --quiet"
expect_line "$out" "# task 1: $tmp/gradus $scene --spp 3 --param a=b\\ c --passes 1:3 --checkpoint $src/rel\\ dir/part_1.ckpt --quiet"

# --cpus-per-task reserves CPUs and sets --nthreads unless the options have it.
out=$("$script" --dry-run --tasks 2 --cpus-per-task 3 --outdir "$tmp/c" "${bins[@]}" "$scene" -- --spp 2 2>&1)
expect_line "$out" "# task 1: $tmp/gradus $scene --spp 2 --nthreads 3 --passes 1:2 --checkpoint $tmp/c/part_1.ckpt --quiet"
grep -q -- "--array=0-1 --job-name=gradus-part --output=$tmp/c/logs/part_%a.out --cpus-per-task=3 " <<<"$out" ||
  fail "--cpus-per-task not passed to sbatch: $out"
out=$("$script" --dry-run --tasks 2 --cpus-per-task 3 --outdir "$tmp/c" "${bins[@]}" "$scene" -- --nthreads 1 --spp 2 2>&1)
expect_line "$out" "# task 0: $tmp/gradus $scene --nthreads 1 --spp 2 --passes 0:1 --checkpoint $tmp/c/part_0.ckpt --quiet"

# More tasks than passes: one task per pass.
out=$("$script" --dry-run --tasks 8 --outdir "$tmp/m" "${bins[@]}" "$scene" -- --spp 3 2>&1)
[ "$(grep -c '^# task ' <<<"$out")" = 3 ] || fail "8 tasks for 3 passes should give 3 tasks: $out"

# Errors: exit 1 with a message naming the problem.
expect_error() { # expect_error PATTERN ARGS...: slurm-render ARGS exits 1 and prints PATTERN
  local pattern=$1 out rc
  shift
  out=$("$script" "$@" 2>&1)
  rc=$?
  [ $rc = 1 ] || fail "exit $rc (expected 1) for: $* -> $out"
  grep -q -- "$pattern" <<<"$out" || fail "no \"$pattern\" in the error for: $* -> $out"
}
expect_error "give the render's sample count" --dry-run "${bins[@]}" "$scene" -- --integrator path
expect_error "give the render's sample count" --dry-run "${bins[@]}" "$scene"
expect_error "--spp expects a positive integer" --dry-run "${bins[@]}" "$scene" -- --spp 0
expect_error "--spp needs a value" --dry-run "${bins[@]}" "$scene" -- --spp
expect_error "--tasks expects a positive integer" --dry-run --tasks x "${bins[@]}" "$scene" -- --spp 4
expect_error "--tasks needs a value" --dry-run "${bins[@]}" "$scene" --tasks
expect_error "no scene given" --dry-run "${bins[@]}" -- --spp 4
expect_error "is not a file" --dry-run "${bins[@]}" "$tmp/missing.pbrt" -- --spp 4
expect_error "one scene only" --dry-run "${bins[@]}" "$scene" "$scene" -- --spp 4
expect_error "unknown option" --dry-run --bogus "${bins[@]}" "$scene" -- --spp 4
expect_error "gradus binary" --dry-run --gradus "$tmp/none" --imgtool "$tmp/imgtool" "$scene" -- --spp 4
expect_error "mlt cannot be split" --dry-run "${bins[@]}" "$scene" -- --spp 4 --integrator mlt
expect_error "--outfile is set by" --dry-run "${bins[@]}" "$scene" -- --spp 4 --outfile x.exr
expect_error "--passes is set by" --dry-run "${bins[@]}" "$scene" -- --spp 4 --passes 0:2
expect_error "--time cannot be split" --dry-run "${bins[@]}" "$scene" -- --spp 4 --time 10
expect_error "--quick changes" --dry-run "${bins[@]}" "$scene" -- --spp 4 --quick
mkdir -p "$tmp/used" && touch "$tmp/used/part_0.ckpt"
expect_error "already holds a render" --dry-run --outdir "$tmp/used" "${bins[@]}" "$scene" -- --spp 4
# Without --dry-run and without sbatch on the PATH: a clear message, nothing submitted.
mkdir -p "$tmp/bin" && ln -s "$(command -v dirname)" "$tmp/bin/dirname"
out=$(PATH=$tmp/bin /bin/bash "$script" --outdir "$tmp/nos" "${bins[@]}" "$scene" -- --spp 4 2>&1)
rc=$?
[ $rc = 1 ] && grep -q "sbatch not found" <<<"$out" || fail "no sbatch: exit $rc, $out"
[ ! -e "$tmp/nos" ] || fail "the output directory was created without sbatch"

if [ $failures -gt 0 ]; then
  echo "$failures failure(s)"
  exit 1
fi
echo "slurm-render dry run: all checks passed"
