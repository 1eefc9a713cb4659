#!/usr/bin/env bash
# Runs a clutterscope batch command on one machine as N shard processes under GNU parallel,
# then merges them (and, for `report`, writes the report over the merged folder): the Slurm
# recipe of scripts/slurm/ without a scheduler.
#
# Usage: scripts/parallel/run.sh [--shards N] [--jobs-per-shard J] [--binary PATH] \
#            COMMAND DATASET WORK [OPTIONS...]
#   COMMAND   report, visibility, estimate or evaluate (as scripts/slurm/submit.sh)
#   WORK      the job's folder: WORK/shards/I, WORK/merged, WORK/parallel.joblog
#   OPTIONS   the command's options (not --out, --shard or --jobs)
#   --shards N (default: the number of cores) processes run at once, each with --jobs J
#   (default 1); --binary PATH as in submit.sh
# Exit status: 1 when a shard failed (WORK/parallel.joblog has each shard's exit code), else
# merge's and report's (clutterscope's exit codes). After a failure or an interruption run the
# same command again: every shard resumes its folder.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
script=run.sh
# shellcheck source=../lib/batch_args.sh
source "$here/../lib/batch_args.sh"
usage() {
  sed -n '6,13p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}
shards="$(nproc)" per_shard=1 binary=""
while [ "$#" -gt 0 ]; do
  case "$1" in
    --shards) shards="${2:?}"; shift 2 ;;
    --jobs-per-shard) per_shard="${2:?}"; shift 2 ;;
    --binary) binary="${2:?}"; shift 2 ;;
    -h | --help) usage ;;
    --*) echo "run.sh: unknown option $1" >&2; usage ;;
    *) break ;;
  esac
done
[ "$#" -ge 3 ] || usage
command="$1" dataset="$2" work="$3"
shift 3
batch_check_command "$command"
batch_check_count --shards "$shards"
batch_check_count --jobs-per-shard "$per_shard"
batch_refuse_set_options "WORK, --shards, --jobs-per-shard" "$@"
command -v parallel >/dev/null ||
  { echo "run.sh: GNU parallel is missing (apt-get install parallel)" >&2; exit 2; }
binary="$(batch_find_binary "$binary")"
mkdir -p "$work/shards"

# {} is the shard index, 0-based as --shard. --halt never: every shard runs to its end, so a
# rerun has as little left as possible; parallel's exit status counts the failed shards.
status=0
seq 0 $((shards - 1)) | parallel -q --jobs "$shards" --halt never --line-buffer --tagstring 'shard {}' \
  --joblog "$work/parallel.joblog" \
  "$binary" "$command" "$dataset" --out "$work/shards/{}" --shard "{}/$shards" \
  --jobs "$per_shard" "$@" || status=$?
if [ "$status" -ne 0 ]; then
  echo "run.sh: $status of $shards shards failed (their exit codes: $work/parallel.joblog);" \
    "run the same command again to resume them" >&2
  exit 1
fi
folders=()
for ((i = 0; i < shards; i++)); do folders+=("$work/shards/$i"); done
"$binary" merge "${folders[@]}" --out "$work/merged"
if [ "$command" = report ]; then
  exec "$binary" report "$dataset" --out "$work/merged" --jobs "$(nproc)" "$@"
fi
