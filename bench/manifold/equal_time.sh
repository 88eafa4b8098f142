#!/usr/bin/env bash
# Equal-time before/after table of bench/manifold/RESULTS.md: every integrator that
# walks, on the shared scenes with pbrt-v3 references, against the integrator it is
# compared with, at one budget and several seeds (bench/run; same filter and reference).
#   bench/manifold/equal_time.sh BEFORE_BIN_DIR AFTER_BIN_DIR OUT_DIR [SECONDS] [SEEDS]
set -euo pipefail
before=$1 after=$2 out=$3 t=${4:-20} seeds=${5:-2}
run() { bench/run --bin-dir "$1" --scenes "$2" --integrators "$3" --times "$t" --seeds "$seeds" --out "$4"; }
run "$before" veach-ajar gbdpt,pmlt,gmlt "$out/before-veach-ajar"
run "$before" water-caustic gbdpt,gvcm "$out/before-water-caustic"
run "$before" caustic-glass gbdpt,gvcm "$out/before-caustic-glass"
run "$after" veach-ajar bdpt,gbdpt,pmlt,gmlt "$out/after-veach-ajar"
run "$after" water-caustic bdpt,vcm,gbdpt,gvcm "$out/after-water-caustic"
run "$after" caustic-glass bdpt,vcm,gbdpt,gvcm "$out/after-caustic-glass"
