#!/usr/bin/env bash
# Runs a clutterscope batch command on a Slurm cluster as a job array, one task per shard, and
# merges the shards in a job that starts when every task has succeeded (afterok); for `report`
# the merge job then writes the report over the merged folder.
#
# Usage: scripts/slurm/submit.sh [--shards N] [--cpus C] [--binary PATH] \
#            COMMAND DATASET WORK [OPTIONS...]
#   COMMAND   report (visibility and estimate per shard, then the report), visibility, estimate
#             or evaluate (OPTIONS then hold --results FILE...)
#   DATASET   BOP dataset folder; WORK: the job's folder (WORK/shards/I, WORK/merged, WORK/logs);
#             both on a file system every node sees
#   OPTIONS   the command's options (not --out, --shard or --jobs: the scripts set them)
#   --shards N   array tasks (default 4); --cpus C: CPUs per task, the command's --jobs (default 4)
#   --binary PATH   the clutterscope executable every node runs (default: build/clutterscope of
#                   this checkout when it exists, else clutterscope on PATH)
# Other sbatch settings come from sbatch's environment variables (SBATCH_PARTITION,
# SBATCH_ACCOUNT, SBATCH_TIMELIMIT, ...). Prints the two job ids ("array JOBID", "merge JOBID")
# and where the results will be.
#
# Resuming: a task that Slurm requeues (node failure, preemption, `scontrol requeue JOBID_I`
# while it runs) reruns into WORK/shards/I and reuses its finished images; the merge job still
# waits for it. A task that FAILED (exit code != 0) cancels the merge job, whose dependency can
# no longer be met (Slurm keeps an array's afterok failed even after the task is requeued):
# fix the cause and run the same submit command again; every shard resumes its folder (finished
# shards take seconds).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
script=submit.sh
# shellcheck source=../lib/batch_args.sh
source "$here/../lib/batch_args.sh"
usage() {
  sed -n '6,18p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}
shards=4 cpus=4 binary=""
while [ "$#" -gt 0 ]; do
  case "$1" in
    --shards) shards="${2:?}"; shift 2 ;;
    --cpus) cpus="${2:?}"; shift 2 ;;
    --binary) binary="${2:?}"; shift 2 ;;
    -h | --help) usage ;;
    --*) echo "submit.sh: unknown option $1" >&2; usage ;;
    *) break ;;
  esac
done
[ "$#" -ge 3 ] || usage
command="$1" dataset="$2" work="$3"
shift 3
batch_check_command "$command"
batch_check_count --shards "$shards"
batch_check_count --cpus "$cpus"
batch_refuse_set_options "WORK, --shards, --cpus" "$@"
[ -d "$dataset" ] || { echo "submit.sh: no dataset folder $dataset" >&2; exit 2; }
command -v sbatch >/dev/null || { echo "submit.sh: sbatch not found (not a Slurm submit host?)" >&2; exit 2; }
binary="$(batch_find_binary "$binary")"
# The jobs run elsewhere, maybe in another folder: absolute paths.
binary="$(realpath "$binary")"
dataset="$(realpath "$dataset")"
mkdir -p "$work/shards" "$work/logs"
work="$(realpath "$work")"

export CLUTTERSCOPE="$binary" CLUTTERSCOPE_SHARDS="$shards"
array=$(sbatch --parsable --array="0-$((shards - 1))" --cpus-per-task="$cpus" \
  --job-name="clutterscope-$command" --output="$work/logs/%x-%A_%a.out" --export=ALL \
  "$here/shard.sbatch" "$command" "$dataset" "$work/shards" "$@")
array="${array%%;*}"  # --parsable prints JOBID[;CLUSTER]
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --cpus-per-task="$cpus" --job-name="clutterscope-merge" --output="$work/logs/%x-%j.out" \
  --export=ALL "$here/merge.sbatch" "$command" "$dataset" "$work" "$@")
merge="${merge%%;*}"
echo "array $array"
echo "merge $merge"
echo "submit.sh: $shards shards of \`clutterscope $command\` in job $array (logs: $work/logs);" \
  "job $merge merges them into $work/merged when all have succeeded"
