#!/usr/bin/env bash
# scripts/slurm-render on a real, private one-node Slurm cluster (slow tier, as root).
#
# Installs Slurm and MUNGE from Debian when missing (exit 77, a skip, when apt cannot), starts
# munged, slurmctld and slurmd under a temporary directory, checks the cluster with a plain
# job array and a dependent job, then renders scenes/cornell-box.pbrt at a small resolution
# with the path and gpt integrators as 4 array tasks plus the merge/finish job, and compares
# each final.exr with the single-process render of the same options and seed. Both sum the same
# per-pass samples, only in another order (per part, then across parts), so the images must
# agree to floating-point summation order: relMSE <= 1e-12, i.e. about 1e-6 relative per pixel
# on every layer (gpt: primal, gradients, variances and reconstructions). Today's merge sums
# in pass order and the images come out bit-identical; the tolerance leaves room for a merge
# that sums in another order. Every wait has a timeout; on failure the daemons' and the
# jobs' logs are printed. The daemons it started are stopped and the directory removed.
#
# usage: test_slurm_render_cluster.sh SOURCE_DIR BINARY_DIR
set -uo pipefail
src=${1:?usage: $0 SOURCE_DIR BINARY_DIR}
bin=${2:?usage: $0 SOURCE_DIR BINARY_DIR}/bin
. "$src/tests/slurm/local_cluster.sh"

for b in gradus imgtool; do
  [ -x "$bin/$b" ] || { echo "FAIL: $bin/$b not built"; exit 1; }
done

[ "$(id -u)" = 0 ] || { echo "FAIL: runs slurmctld and slurmd as SlurmUser=root: run it as root"; exit 1; }
cluster_install
rc=$?
if [ $rc = 77 ]; then
  echo "SKIP: Slurm could not be installed from Debian"
  exit 77
fi
[ $rc = 0 ] || exit 1

# All waits end within 900 s of here (CTest's TIMEOUT is 1200 s).
deadline=$((SECONDS + 900))
# Under /tmp, not the build tree: MUNGE's and slurmd's Unix socket paths must stay short
# (108 bytes at most).
work=$(mktemp -d /tmp/gradus-slurm-test.XXXXXX)
chmod 755 "$work"  # munged's socket lives below it
status=1
finish() {
  if [ $status != 0 ]; then
    echo "===== FAILED: logs"
    cluster_logs
    local f
    for f in "$work"/jobs/*/logs/* "$work"/sanity/*; do
      [ -s "$f" ] || continue
      echo "----- $f"
      tail -n 40 "$f"
    done
  fi
  cluster_stop
  cd / && rm -rf "$work"
  exit $status
}
trap finish EXIT
trap 'exit 1' INT TERM

fail() {
  echo "FAIL: $*"
  exit 1
}

# job_state ID: the state of job ID (for an array: every task's state, space-separated).
job_state() {
  scontrol show job -o "$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2 | sort -u | tr '\n' ' '
}
# wait_job ID SECONDS: waits until job ID (every task of an array) completed; fails on any other end.
wait_job() {
  local id=$1 limit=$2 start=$SECONDS s
  # Never past the test's own deadline, so that the cleanup runs before CTest's TIMEOUT kills it.
  [ $((deadline - SECONDS)) -ge "$limit" ] || limit=$((deadline - SECONDS))
  while :; do
    s=$(job_state "$id")
    case " $s" in
      *" FAILED "*|*" CANCELLED "*|*" TIMEOUT "*|*" NODE_FAIL "*|*" OUT_OF_MEMORY "*|*" BOOT_FAIL "*|*" DEADLINE "*|*" PREEMPTED "*)
        scontrol show job "$id" | grep -E 'JobId=|JobState=|Reason|ExitCode'
        echo "job $id ended: $s"
        return 1 ;;
    esac
    [ "$s" = "COMPLETED " ] && return 0
    if [ $((SECONDS - start)) -ge "$limit" ]; then
      echo "job $id not done after ${limit}s (state: $s)"
      squeue
      return 1
    fi
    sleep 1
  done
}

mkdir -p "$work/cluster" "$work/sanity" "$work/jobs"
cluster_start "$work/cluster" || fail "the cluster did not start"

# Sanity: an array of 4 and a job that depends on it, as slurm-render uses them.
cd "$work/sanity" || exit 1
array=$(sbatch --parsable --array=0-3 --output="$work/sanity/task_%a.out" \
  --wrap 'echo "task $SLURM_ARRAY_TASK_ID on $(hostname)"') || fail "sbatch of a plain array failed"
array=${array%%;*}
dep=$(sbatch --parsable --dependency=afterok:"$array" --output="$work/sanity/dep.out" \
  --wrap "cat $work/sanity/task_*.out") || fail "sbatch of a dependent job failed"
dep=${dep%%;*}
wait_job "$dep" 120 || fail "the plain array $array and its dependent job $dep did not complete"
[ "$(grep -c '^task [0-3] on ' "$work/sanity/dep.out")" = 4 ] ||
  fail "the dependent job did not see the 4 tasks' outputs"
echo "cluster sanity: array $array and dependent job $dep completed"

"$bin/gradus" --help 2>&1 | grep -q -- '--passes' ||
  fail "$bin/gradus has no --passes/--checkpoint/--resume (render splitting)"

# The renders: 10 passes over 4 tasks (ranges 0:2 2:5 5:7 7:10), one thread per task.
scene=$src/scenes/cornell-box.pbrt
for integrator in path gpt; do
  opts=(--resolution 40x32 --spp 10 --integrator "$integrator" --seed 5)
  out=$work/jobs/$integrator
  echo "== $integrator: slurm-render --tasks 4 ${opts[*]}"
  msg=$("$src/scripts/slurm-render" --tasks 4 --cpus-per-task 1 --outdir "$out" \
    --gradus "$bin/gradus" --imgtool "$bin/imgtool" "$scene" -- "${opts[@]}" 2>&1) ||
    fail "slurm-render failed: $msg"
  echo "$msg"
  array=$(sed -n 's/^array job \([0-9]*\) .*, finish job \([0-9]*\)$/\1/p' <<<"$msg")
  fin=$(sed -n 's/^array job \([0-9]*\) .*, finish job \([0-9]*\)$/\2/p' <<<"$msg")
  [ -n "$array" ] && [ -n "$fin" ] || fail "no job ids in slurm-render's output"
  wait_job "$array" 300 || fail "$integrator: the array $array did not complete"
  wait_job "$fin" 300 || fail "$integrator: the finish job $fin did not complete"
  [ -f "$out/final.exr" ] || fail "$integrator: no $out/final.exr"
  for k in 0 1 2 3; do [ -f "$out/part_$k.ckpt" ] || fail "$integrator: no part_$k.ckpt"; done

  timeout 300 "$bin/gradus" "$scene" "${opts[@]}" --nthreads 2 --quiet --outfile "$work/single_$integrator.exr" ||
    fail "$integrator: the single-process render failed"
  # Every layer: the image and, for gpt, primal, dx, dy, their variances and reconstructions.
  layers=()
  while IFS= read -r l; do layers+=("$l"); done < <("$bin/imgtool" info "$work/single_$integrator.exr" |
    sed -n 's/^layer "\(.*\)":.*/\1/p')
  [ ${#layers[@]} -gt 0 ] || fail "$integrator: no layers listed by imgtool info"
  for l in "${layers[@]}"; do
    sel=()
    [ -z "$l" ] || sel=(--layer "$l")
    res=$("$bin/imgtool" diff "$out/final.exr" "$work/single_$integrator.exr" "${sel[@]}" \
      --tolerance 1e-12) ||
      fail "$integrator, layer \"$l\": the Slurm render differs from the single-process one by more than summation order: $res"
    echo "$integrator, layer \"$l\": $(tail -n 1 <<<"$res")"
  done
done

status=0
echo "PASS: slurm-render on a local Slurm cluster matches the single-process renders"
