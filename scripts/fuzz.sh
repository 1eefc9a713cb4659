#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz in build-san/ (clang, ASan + UBSan; the tree of
# scripts/test-sanitizers.sh, see scripts/sanitizer-env.sh) and runs each one from its seed
# corpus (tests/fuzz/corpus/NAME) and its saved crash inputs (tests/fuzz/regressions/NAME) for
# CLUTTERSCOPE_FUZZ_SECONDS seconds (default 25), as many targets at a time as
# CLUTTERSCOPE_BUILD_JOBS (default: the number of cores).
# Arguments: target names (default: every target with a corpus folder).
# New inputs go to build-san/fuzz-corpus/NAME, crash inputs to build-san/fuzz-artifacts/NAME,
# the fuzzer's log to build-san/fuzz-logs/NAME.log. Fails when any target crashes, leaks,
# hangs (CLUTTERSCOPE_FUZZ_TIMEOUT seconds for one input, default 10) or runs out of memory.
# CLUTTERSCOPE_FUZZ_NO_BUILD=1 skips the build.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer-env.sh
seconds="${CLUTTERSCOPE_FUZZ_SECONDS:-25}"
timeout_s="${CLUTTERSCOPE_FUZZ_TIMEOUT:-10}"
jobs="${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}"

if [ "${CLUTTERSCOPE_FUZZ_NO_BUILD:-0}" != 1 ]; then
  start=$SECONDS
  configure_sanitizer_tree
  cmake --build "$sanitizer_tree" --parallel "$jobs" --target clutterscope_fuzz_targets
  echo "fuzz: build took $((SECONDS - start)) s"
fi

targets=("$@")
if [ "${#targets[@]}" -eq 0 ]; then
  for dir in tests/fuzz/corpus/*/; do targets+=("$(basename "$dir")"); done
fi

# Runs one target; its result goes to $log.status (the exit status) for the summary below.
fuzz_one() {
  local target="$1"
  local binary="build-san/tests/fuzz/fuzz_$target"
  local work="build-san/fuzz-corpus/$target"
  local artifacts="build-san/fuzz-artifacts/$target"
  local log="build-san/fuzz-logs/$target.log"
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  local inputs=("tests/fuzz/corpus/$target")
  if [ -d "tests/fuzz/regressions/$target" ]; then inputs+=("tests/fuzz/regressions/$target"); fi
  local start=$SECONDS status=0
  "$binary" -max_total_time="$seconds" -timeout="$timeout_s" -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" "$work" "${inputs[@]}" >"$log" 2>&1 ||
    status=$?
  echo "$status $((SECONDS - start))" >"$log.status"
}

# One target per core at a time: each runs its full time, the smoke takes 1/jobs of the wall time.
for target in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  rm -f "build-san/fuzz-logs/$target.log.status"
  fuzz_one "$target" &
done
wait

failed=()
for target in "${targets[@]}"; do
  log="build-san/fuzz-logs/$target.log"
  if ! read -r status elapsed 2>/dev/null <"$log.status"; then
    echo "fuzz: $target: FAILED, the run left no result (log $log)"
    failed+=("$target")
    continue
  fi
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  if [ "$status" -eq 0 ]; then
    echo "fuzz: $target: ${executions:-?} executions in $elapsed s, no crash"
  else
    echo "fuzz: $target: FAILED (exit $status) after $elapsed s; log $log:"
    grep -E "ERROR|SUMMARY|Test unit written|runtime error" "$log" | head -20 || true
    tail -40 "$log"
    failed+=("$target")
  fi
done
if [ "${#failed[@]}" -gt 0 ]; then
  echo "fuzz: ${#failed[@]} target(s) failed: ${failed[*]}"
  exit 1
fi
