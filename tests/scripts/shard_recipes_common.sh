# shellcheck shell=bash disable=SC2154
# Shared by the tests of scripts/slurm and scripts/parallel (sourced): a small generated
# dataset, its unsharded report, and the byte comparison of a merged folder with it.
# Expects $binary (the clutterscope executable) and $scratch (a temporary folder).

# Small and quick: 8 images (2 per shard of 4), few particles; --no-time, because the
# estimates' time columns are wall times and would differ between any two runs.
report_options=(--particles 20 --iterations 3 --icp-samples 5 --no-notebook --no-time -q)

make_dataset_and_reference() {
  "$binary" generate --out "$scratch/data" --scenes 8 --objects 4 --width 320 --height 240 \
    --tessellation 200 --seed 3 --quiet
  "$binary" report "$scratch/data" --out "$scratch/reference" --jobs 1 "${report_options[@]}" \
    >/dev/null
}

# The merged folder holds the same files with the same bytes as the unsharded run, apart from
# the run records (.batch/: parts and input digests; run.json: times, counts computed/reused),
# as tests/common/bop_fixture_support.hpp's batch_result_files compares them.
expect_same_as_reference() {
  local merged="$1"
  if ! diff -r --exclude=.batch --exclude=run.json "$scratch/reference" "$merged" >"$scratch/diff.txt"; then
    echo "FAIL: $merged differs from the unsharded run:" >&2
    head -40 "$scratch/diff.txt" >&2
    return 1
  fi
  local count
  count=$(find "$scratch/reference" -type f -not -path '*/.batch/*' -not -name run.json | wc -l)
  [ "$count" -ge 20 ] || { echo "FAIL: only $count files in the reference" >&2; return 1; }
  echo "ok: $merged equals the unsharded run byte for byte ($count files)"
}

# The usage errors both recipes share (scripts/lib/batch_args.sh): each exits 2 before
# anything runs and names what was wrong. expect_usage_errors SCRIPT COUNT_OPTION
expect_usage_errors() {
  local script="$1" count_option="$2" status
  expect_refused() {
    local expected="$1"
    shift
    status=0
    bash "$script" "$@" >"$scratch/usage.log" 2>&1 || status=$?
    if [ "$status" -ne 2 ] || ! grep -qF -- "$expected" "$scratch/usage.log"; then
      cat "$scratch/usage.log" >&2
      echo "FAIL: $(basename "$script") $* exited $status, expected 2 and \"$expected\"" >&2
      return 1
    fi
  }
  expect_refused "COMMAND must be report, visibility, estimate or evaluate, not frobnicate" \
    --binary "$binary" frobnicate "$scratch/data" "$scratch/usage-work"
  expect_refused "--shards must be >= 1, got 0" \
    --shards 0 --binary "$binary" report "$scratch/data" "$scratch/usage-work"
  expect_refused "$count_option must be >= 1, got x" \
    "$count_option" x --binary "$binary" report "$scratch/data" "$scratch/usage-work"
  expect_refused "--jobs=3 is set by the script" \
    --binary "$binary" report "$scratch/data" "$scratch/usage-work" --jobs=3
  expect_refused "no clutterscope executable (--binary PATH)" \
    --binary "$scratch/no-such-binary" report "$scratch/data" "$scratch/usage-work"
  [ ! -e "$scratch/usage-work" ] || { echo "FAIL: a refused run created its WORK folder" >&2; return 1; }
  echo "ok: $(basename "$script") refuses bad arguments with exit 2"
}
