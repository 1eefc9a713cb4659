#!/usr/bin/env bash
# scripts/slurm on a real one-node Slurm cluster (Debian's slurm-wlm and munge), started and
# stopped here in a temporary folder: submit.sh runs `report` as a 4-task job array; task 1 is
# frozen after its first image and requeued (`scontrol requeue` kills it midway and puts it
# back), resumes its shard; the merge job (afterok) merges and writes the report: the same
# bytes as one unsharded run. Then the same submit command again (the recovery after a failed
# task): every shard reuses all its images, same bytes.
# Usage: slurm_array_test.sh CLUTTERSCOPE_BINARY SOURCE_DIR
set -euo pipefail
binary="$1" source_dir="$2"
missing=()
for program in munged munge slurmctld slurmd sbatch scontrol squeue sinfo scancel; do
  command -v "$program" >/dev/null || missing+=("$program")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "FAIL: ${missing[*]} missing; scripts/install-deps.sh installs them (packages slurm-wlm," \
    "munge)" >&2
  exit 1
fi

scratch="$(mktemp -d)"
cluster="$scratch/cluster"
mkdir -p "$cluster/munge" "$cluster/ctld" "$cluster/spool" "$cluster/log"
chmod 700 "$cluster/munge"
export SLURM_CONF="$cluster/slurm.conf"

step() { echo "slurm_array_test: ${SECONDS} s: $*"; }
fail() {
  echo "FAIL: $*" >&2
  for log in "$cluster"/log/*.log "$scratch"/work/logs/*; do
    [ -f "$log" ] && { echo "--- $log" >&2; tail -n 30 "$log" >&2; }
  done
  exit 1
}
stop_daemon() {  # PID_FILE
  local pid
  pid="$(cat "$1" 2>/dev/null || true)"
  [ -n "$pid" ] || return 0
  kill "$pid" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null || true
}
cleanup() {
  # Jobs first (their processes belong to slurmstepd, not to slurmd), then the daemons.
  if [ -f "$cluster/ctld.pid" ]; then
    scancel --full --user="$(id -un)" 2>/dev/null || true
    for _ in $(seq 50); do
      [ -z "$(squeue -h -t running,completing 2>/dev/null)" ] && break
      sleep 0.1
    done
  fi
  stop_daemon "$cluster/slurmd.pid"
  stop_daemon "$cluster/slurmctld.pid"
  stop_daemon "$cluster/munge/munged.pid"
  # A job step whose slurmd went first (a failed run) lingers: its slurmstepd keeps the node's
  # log of this folder open.
  local fd
  for fd in /proc/[0-9]*/fd/*; do
    case "$(readlink "$fd" 2>/dev/null)" in
      "$cluster"/*) fd="${fd#/proc/}"; kill -KILL "${fd%%/*}" 2>/dev/null || true ;;
    esac
  done
  if [ -n "${CLUTTERSCOPE_TEST_KEEP:-}" ]; then echo "kept $scratch"; else rm -rf "$scratch"; fi
}
trap cleanup EXIT

# munge: a fresh key and a daemon with its own socket.
head -c 1024 /dev/urandom >"$cluster/munge/munge.key"
chmod 400 "$cluster/munge/munge.key"
munged --force --key-file="$cluster/munge/munge.key" --socket="$cluster/munge/socket" \
  --pid-file="$cluster/munge/munged.pid" --log-file="$cluster/log/munged.log" \
  --seed-file="$cluster/munge/seed" || fail "munged did not start"

# Slurm: controller and one node on localhost, on ports unlikely to be taken, no cgroups.
# cred_expire: a requeued job waits this long before it starts again (default 120 s); starting
# it earlier (scontrol update StartTime=now) can fail with "Job credential revoked".
# sched_interval: the scheduler looks at such a job again after this many seconds (default 60).
port=$((20000 + RANDOM % 20000))
user="$(id -un)"
cat >"$SLURM_CONF" <<CONF
ClusterName=clutterscope-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$cluster/munge/socket,cred_expire=10
CredType=cred/munge
StateSaveLocation=$cluster/ctld
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldLogFile=$cluster/log/slurmctld.log
SlurmdLogFile=$cluster/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=1
MpiDefault=none
ReturnToService=2
MinJobAge=600
SlurmdParameters=config_overrides
NodeName=node0 NodeHostname=$(hostname -s) NodeAddr=127.0.0.1 CPUs=4 RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=node0 Default=YES MaxTime=INFINITE State=UP
CONF
step "starting munged, slurmctld and slurmd"
# slurmd 22.05 loads a cgroup plugin even with proctrack/linuxproc and task/none, and stops
# when it finds no cgroup file system (a chroot) or a hybrid or undelegated one. A tmpfs as the
# mount point makes it take cgroup/v1 there, and nothing of this cluster uses it.
tmpfs=""
for dir in /dev/shm /run; do
  if [ "$(stat -f -c %T "$dir" 2>/dev/null)" = tmpfs ]; then tmpfs="$dir"; break; fi
done
[ -n "$tmpfs" ] || fail "neither /dev/shm nor /run is a tmpfs (slurmd's cgroup plugin needs one)"
cat >"$cluster/cgroup.conf" <<CONF
CgroupPlugin=cgroup/v1
CgroupMountpoint=$tmpfs
CgroupAutomount=no
CONF
slurmctld -c -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -N node0 -f "$SLURM_CONF" || fail "slurmd did not start"
for _ in $(seq 300); do
  [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break
  sleep 0.1
done
[ "$(sinfo -h -o %T 2>/dev/null)" = idle ] || fail "the node did not become idle: $(sinfo 2>&1)"

scripts_dir="$source_dir/tests/scripts"
# shellcheck source=tests/scripts/shard_recipes_common.sh
. "$scripts_dir/shard_recipes_common.sh"
step "node idle; generating the dataset and its unsharded report"
make_dataset_and_reference
expect_usage_errors "$source_dir/scripts/slurm/submit.sh" --cpus

# Task 1's first run runs clutterscope and freezes it (SIGSTOP) once it has finished an image,
# so that the requeue below kills it midway on any machine; every other run is clutterscope.
cat >"$scratch/clutterscope-wrapper" <<WRAP
#!/usr/bin/env bash
if [ "\${SLURM_ARRAY_TASK_ID:-}" != 1 ] || [ -e "$scratch/frozen" ]; then
  exec "$binary" "\$@"
fi
"$binary" "\$@" &
child=\$!
parts="\$4/estimate/.batch/parts"  # report DATASET --out DIR ...
until [ -n "\$(find "\$parts" -name '*.json' 2>/dev/null | head -1)" ]; do
  kill -0 "\$child" 2>/dev/null || { echo "task 1 ended before it was frozen" >"$scratch/frozen"; exit 1; }
  sleep 0.02
done
kill -STOP "\$child"
echo frozen >"$scratch/frozen"
wait "\$child"
WRAP
chmod +x "$scratch/clutterscope-wrapper"

submit() {
  bash "$source_dir/scripts/slurm/submit.sh" --shards 4 --cpus 1 \
    --binary "$scratch/clutterscope-wrapper" report "$scratch/data" "$scratch/work" \
    "${report_options[@]}"
}
# Waits until job $1 has ended (at most 4 minutes); fails unless it COMPLETED.
wait_for_job() {
  local state="" deadline=$((SECONDS + 240))
  while [ "$SECONDS" -lt "$deadline" ]; do
    state="$(scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -1)"
    case "$state" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) break ;; esac
    sleep 0.1
  done
  [ "$state" = COMPLETED ] || fail "job $1 ended $state: $(scontrol show job "$1" 2>&1 | head -5)"
}

step "submitting"
output="$(submit)" || fail "submit.sh: $output"
array="$(sed -n 's/^array //p' <<<"$output")"
merge="$(sed -n 's/^merge //p' <<<"$output")"
{ [ -n "$array" ] && [ -n "$merge" ]; } || fail "no job ids in: $output"

deadline=$((SECONDS + 240))
while [ ! -f "$scratch/frozen" ] && [ "$SECONDS" -lt "$deadline" ]; do sleep 0.1; done
[ "$(cat "$scratch/frozen" 2>/dev/null)" = frozen ] ||
  fail "task 1 was not frozen midway: $(cat "$scratch/frozen" 2>/dev/null)"
step "task 1 frozen midway: requeueing it"
scontrol requeue "${array}_1" || fail "scontrol requeue ${array}_1"
wait_for_job "$merge"
step "merge job $merge completed"

log="$scratch/work/logs/clutterscope-report-${array}_1.out"
grep -q 'restart 1: shard 1/4' "$log" || fail "task 1 did not run again after the requeue"
grep -q 'shard 1/4 done (.*, [1-9][0-9]* reused)' "$log" || fail "task 1 did not resume its shard"
expect_same_as_reference "$scratch/work/merged"

# After a failed task: the same command again resumes every shard.
step "submitting again"
output="$(submit)" || fail "submit.sh again: $output"
array="$(sed -n 's/^array //p' <<<"$output")"
wait_for_job "$(sed -n 's/^merge //p' <<<"$output")"
for i in 0 1 2 3; do
  grep -q "shard $i/4 done (0 images computed" "$scratch/work/logs/clutterscope-report-${array}_$i.out" ||
    fail "shard $i computed images again"
done
step "merge job completed"
expect_same_as_reference "$scratch/work/merged"
