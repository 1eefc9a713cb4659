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
