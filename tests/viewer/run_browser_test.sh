#!/usr/bin/env bash
# ctest imgtool_compare_browser: installs playwright-core (package-lock.json)
# into WORK_DIR with npm ci when missing or changed, then runs the test.
# Chromium missing (or, in the test, failing to start) skips (exit 77), except
# under CI (CI=true), where it fails (exit 1).
# usage: run_browser_test.sh BIN_DIR WORK_DIR   (CHROMIUM: the browser, default /usr/bin/chromium)
set -euo pipefail
bin=$1 work=$2
src=$(cd "$(dirname "$0")" && pwd)
chromium=${CHROMIUM:-/usr/bin/chromium}
if [ ! -x "$chromium" ]; then
  if [ "${CI:-}" = true ]; then
    echo "FAIL: $chromium is missing, and CI=true requires the browser test to run (scripts/deps installs Debian's chromium)"
    exit 1
  fi
  echo "SKIP: $chromium is missing (scripts/deps installs Debian's chromium)"
  exit 77
fi
mkdir -p "$work"
if ! cmp -s "$src/package-lock.json" "$work/package-lock.json" || [ ! -d "$work/node_modules/playwright-core" ]; then
  cp "$src/package.json" "$src/package-lock.json" "$work/"
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
fi
exec node "$src/compare_browser_test.mjs" "$bin" "$work"
