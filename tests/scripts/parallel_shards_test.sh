#!/usr/bin/env bash
# scripts/parallel/run.sh: 4 shards of `report` under GNU parallel, one shard interrupted and
# resumed by running the same command again, merged and reported: the same bytes as one
# unsharded run. Usage: parallel_shards_test.sh CLUTTERSCOPE_BINARY SOURCE_DIR
set -euo pipefail
binary="$1" source_dir="$2"
if ! command -v parallel >/dev/null; then
  echo "FAIL: GNU parallel is missing; scripts/install-deps.sh installs it (package parallel)" >&2
  exit 1
fi
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
# shellcheck source=tests/scripts/shard_recipes_common.sh
. "$source_dir/tests/scripts/shard_recipes_common.sh"
make_dataset_and_reference
expect_usage_errors "$source_dir/scripts/parallel/run.sh" --jobs-per-shard

# An interrupted run: shard 1 alone, killed once its first image is done.
"$binary" report "$scratch/data" --out "$scratch/work/shards/1" --shard 1/4 --jobs 1 \
  "${report_options[@]}" &
shard=$!
parts="$scratch/work/shards/1/estimate/.batch/parts"
for _ in $(seq 600); do
  [ -n "$(find "$parts" -name '*.json' 2>/dev/null | head -1)" ] && break
  sleep 0.05
done
kill -KILL "$shard" 2>/dev/null || true
status=0
wait "$shard" 2>/dev/null || status=$?
[ "$status" -eq 137 ] || { echo "FAIL: shard 1 ended (status $status) before it was killed" >&2; exit 1; }

bash "$source_dir/scripts/parallel/run.sh" --shards 4 --binary "$binary" report "$scratch/data" \
  "$scratch/work" "${report_options[@]}" >"$scratch/run.log" 2>&1 ||
  { cat "$scratch/run.log" >&2; echo "FAIL: run.sh exit status $?" >&2; exit 1; }
grep -q 'shard 1/4 done (.*, [1-9][0-9]* reused)' "$scratch/run.log" ||
  { cat "$scratch/run.log" >&2; echo "FAIL: shard 1 did not resume its folder" >&2; exit 1; }
expect_same_as_reference "$scratch/work/merged"
