#!/usr/bin/env bash
# ctest imgtool_compare_browser_ci: the browser test with a Chromium that is
# missing, or present but unable to start (a stand-in that exits at once),
# skips (exit 77) without CI and fails (exit 1) under CI=true.
# usage: ci_skip_test.sh BIN_DIR WORK_DIR (WORK_DIR shared with imgtool_compare_browser)
set -uo pipefail
bin=$1 work=$2
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '#!/bin/sh\nexit 1\n' > "$tmp/chromium"
chmod +x "$tmp/chromium"
fails=0
expect() {  # NAME EXPECTED_EXIT EXPECTED_LINE_START ENV_ARGS...
  local name=$1 want=$2 line=$3 out code
  shift 3
  out=$(env "$@" bash "$here/run_browser_test.sh" "$bin" "$work" 2>&1)
  code=$?
  if [ "$code" = "$want" ] && echo "$out" | grep -q "^$line"; then
    echo "ok   $name (exit $code): $(echo "$out" | grep -E '^(SKIP|FAIL)' | head -1)"
  else
    echo "FAIL $name: exit $code, expected $want and a line '$line...'; output:"
    echo "$out" | tail -8
    fails=$((fails + 1))
  fi
}
expect "missing Chromium under CI fails" 1 "FAIL: $tmp/none is missing" CI=true CHROMIUM="$tmp/none"
expect "missing Chromium without CI skips" 77 "SKIP: $tmp/none is missing" -u CI CHROMIUM="$tmp/none"
expect "Chromium that cannot start under CI fails" 1 "FAIL: chromium cannot start" CI=true CHROMIUM="$tmp/chromium"
expect "Chromium that cannot start without CI skips" 77 "SKIP: chromium cannot start" -u CI CHROMIUM="$tmp/chromium"
echo "$fails failure(s)"
[ "$fails" = 0 ]
