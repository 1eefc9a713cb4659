#!/usr/bin/env bash
# The README's test command, and CI's (.ci/run): installs dependencies, builds build/ and runs
# the whole test suite there; then, under ASan + UBSan in one clang tree (build-san/), the
# suites without GL and every fuzz regression input (scripts/test-sanitizers.sh --unit) and a
# short run of every fuzz target (scripts/fuzz.sh, 15 s each). Ends with the time of each stage
# and the count of tests passed and failed. Extra arguments go to the first ctest.
# The whole suite under the sanitizers, GL included, is scripts/test-sanitizers.sh.
# Here a test that needs an EGL device or Chromium fails when it is missing instead of skipping
# (tests/common/requirements.hpp): this command is meant to test everything.
# CLUTTERSCOPE_QUICK=1 stops after the first suite (for a quick local run; CI runs everything).
set -euo pipefail
cd "$(dirname "$0")/.."
export CLUTTERSCOPE_REQUIRE_EGL=1 CLUTTERSCOPE_REQUIRE_CHROMIUM=1
jobs="${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}"
logs="$(mktemp -d)"
stage_names=()
stage_seconds=()
current=""
current_start=0
total_start=$SECONDS

# Runs one stage, its output also kept in $logs for the counts at the end.
stage() {
  current="$1"
  current_start=$SECONDS
  shift
  "$@" 2>&1 | tee "$logs/${#stage_names[@]}.log"
  stage_names+=("$current")
  stage_seconds+=($((SECONDS - current_start)))
  current=""
}

row() { printf 'test: %-18s %6d s  %3d:%02d%s\n' "$1" "$2" $(($2 / 60)) $(($2 % 60)) "${3:+  $3}"; }

# The stage table, then the tests run: ctest's "N% tests passed, F tests failed out of T" lines
# summed, and the fuzz targets that ran clean or failed. Also when a stage failed.
report() {
  local status=$?
  echo
  echo "test: stage                wall time"
  local i
  for i in "${!stage_names[@]}"; do
    row "${stage_names[$i]}" "${stage_seconds[$i]}"
  done
  if [ -n "$current" ]; then row "$current" $((SECONDS - current_start)) "FAILED"; fi
  row total $((SECONDS - total_start))
  local passed=0 failed=0 p f t
  while read -r p f t; do
    passed=$((passed + t - f))
    failed=$((failed + f))
  done < <(cat "$logs"/*.log 2>/dev/null |
    sed -n 's/^[0-9]*% tests passed, \([0-9]*\) tests\{0,1\} failed out of \([0-9]*\)$/x \1 \2/p')
  passed=$((passed + $(cat "$logs"/*.log 2>/dev/null | grep -c '^fuzz: .*, no crash$' || true)))
  failed=$((failed + $(cat "$logs"/*.log 2>/dev/null | grep -c '^fuzz: .*: FAILED' || true)))
  rm -rf "$logs"
  echo "test: tests run (ctest's tests and the fuzz targets of the smoke), exit status $status:"
  echo "$passed passed, $failed failed"
  exit "$status"
}
trap report EXIT

release_suite() {
  (cd build && ctest --output-on-failure --no-tests=error --timeout 900 -j "$jobs" "$@")
}

stage install bash scripts/install-deps.sh
stage "release build" bash scripts/build.sh
stage "release suite" release_suite "$@"
if [ "${CLUTTERSCOPE_QUICK:-0}" = 1 ]; then
  echo "test: CLUTTERSCOPE_QUICK=1, sanitizer suites and fuzz smoke left out"
  exit 0
fi
stage "sanitizer build" bash scripts/test-sanitizers.sh --unit build
stage "sanitizer suite" bash scripts/test-sanitizers.sh --unit suite
stage "fuzz regressions" bash scripts/test-sanitizers.sh --unit fuzz-regressions
# 15 s per target here (scripts/fuzz.sh's own default is 25 s): 14 targets, two at a time.
stage "fuzz smoke" env CLUTTERSCOPE_FUZZ_NO_BUILD=1 \
  CLUTTERSCOPE_FUZZ_SECONDS="${CLUTTERSCOPE_FUZZ_SECONDS:-15}" bash scripts/fuzz.sh
