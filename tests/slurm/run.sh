#!/usr/bin/env bash
# End-to-end test of `pt slurm` against a real Slurm (issue 25), on this machine alone:
#  1. installs Debian's slurm-wlm and munge if they are missing (needs root, as CI is);
#  2. starts munged, slurmctld and slurmd on localhost with a one-node configuration written to
#     a scratch folder (nothing under /etc is changed; every daemon's files are in that folder);
#  3. `pt slurm --submit`s the Cornell box as a 4-part job array plus the merge job;
#  4. kills one part's renderer (SIGKILL) after its first checkpoint: the task must be requeued
#     by Slurm and resume from its part file (its log says so), not start over;
#  5. waits (bounded) for the merge job, checks the merged EXR is bit-identical to a local render
#     of the same scene, seed and spp (`pt compare --identical`), and `pt slurm --status`;
#  6. stops the daemons it started and removes the scratch folder, whatever happened.
#
# Usage: tests/slurm/run.sh [PT_BINARY]   (default: target/debug/pt, which `cargo test` builds
# optimised; built with `cargo build --bin pt` if missing). Prints "1 passed, 0 failed" or
# "0 passed, 1 failed" and exits 0 or 1; 2 when the test could not be set up.
set -uo pipefail
cd "$(dirname "$0")/../.."
REPO=$(pwd)
PT=${1:-target/debug/pt}
TIMEOUT=${PT_SLURM_TIMEOUT:-300}

say() { echo "[slurm test $(date -u +%T)] $*"; }
fail() { say "FAILED: $*"; echo "0 passed, 1 failed"; exit 1; }
setup_fail() { say "cannot set up: $*"; exit 2; }

if [ ! -x "$PT" ]; then
  say "building pt"
  cargo build --bin pt || setup_fail "cargo build failed"
fi
PT=$(readlink -f "$PT")

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  [ "$(id -u)" = 0 ] || setup_fail "slurm-wlm and munge are missing and installing them needs root"
  say "installing slurm-wlm and munge (Debian packages)"
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge) \
    >/tmp/pt-slurm-apt.log 2>&1 || { tail -20 /tmp/pt-slurm-apt.log; setup_fail "apt-get install failed"; }
fi

W=$(mktemp -d /tmp/pt-slurm.XXXXXX)
chmod 755 "$W"
PIDS=()
cleanup() {
  if [ -n "${SLURM_CONF:-}" ] && [ -f "$SLURM_CONF" ]; then
    scancel --quiet --user="$(id -un)" 2>/dev/null || true
  fi
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
  sleep 1
  for p in "${PIDS[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  # Renderers started by the test's jobs (slurmd is gone, they would linger).
  pkill -9 -f "$W/run/parts" 2>/dev/null || true
  rm -rf "$W"
}
trap cleanup EXIT

HOST=$(hostname -s)
USER_NAME=$(id -un)
# Ports well away from Slurm's defaults (6817/6818), so a real Slurm on the machine is untouched.
CTLD_PORT=16917
SLURMD_PORT=16918

# munge: a key of our own, a socket in the scratch folder.
dd if=/dev/urandom of="$W/munge.key" bs=1024 count=1 status=none
chmod 400 "$W/munge.key"
mkdir -p "$W/munge" && chmod 700 "$W/munge"
munged --force --foreground --key-file="$W/munge.key" --socket="$W/munge/munge.sock" \
  --pid-file="$W/munge/munged.pid" --log-file="$W/munge/munged.log" --seed-file="$W/munge/seed" \
  >"$W/munge/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$W/munge/munge.sock" ] && break; sleep 0.1; done
[ -S "$W/munge/munge.sock" ] || setup_fail "munged did not start: $(cat "$W/munge/munged.log" 2>/dev/null)"

# The node as slurmd sees it (CPUs, sockets, memory), so the configuration matches the machine.
NODE=$(slurmd -C 2>/dev/null | head -1 | sed 's/UpTime=.*//')
[ -n "$NODE" ] || setup_fail "slurmd -C printed nothing"
mkdir -p "$W/state" "$W/spool"
export SLURM_CONF="$W/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=ptci
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
AuthType=auth/munge
AuthInfo=socket=$W/munge/munge.sock
CredType=cred/munge
SlurmUser=$USER_NAME
SlurmdUser=root
StateSaveLocation=$W/state
SlurmdSpoolDir=$W/spool
SlurmctldPidFile=$W/slurmctld.pid
SlurmdPidFile=$W/slurmd.pid
SlurmctldLogFile=$W/slurmctld.log
SlurmdLogFile=$W/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
JobRequeue=1
KillWait=5
MinJobAge=600
$NODE NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=ptci Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF

slurmctld -D -i -f "$SLURM_CONF" >"$W/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -f "$SLURM_CONF" -N "$HOST" >"$W/slurmd.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 120); do
  sinfo -h -N -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)' && break
  sleep 0.5
done
if ! sinfo -h -N -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
  tail -20 "$W/slurmctld.log" "$W/slurmd.log" "$W/slurmctld.out" "$W/slurmd.out" 2>/dev/null
  setup_fail "the Slurm node did not come up"
fi
say "slurm up: $(sinfo -h -o '%P %D %T %c CPUs')"

# The render: Cornell box, 64x64, 6000 spp in 4 parts (each about 5 s on one core), so that a
# part is still running when it is killed.
SPP=6000
ARGS=(--width 64 --height 64)
"$PT" slurm scenes/cornell-box.xml --parts 4 --spp $SPP --out "$W/run" --checkpoint 1 \
  --cpus-per-task 1 --max-retries 2 --submit -- "${ARGS[@]}" || fail "pt slurm --submit"
cat "$W/run/jobs.txt"

# Kill part 2's renderer once it has a checkpoint: Slurm must requeue the task, and the part
# resume from its file.
VICTIM="$W/run/parts/cornell-box.part2of4.ptpart"
deadline=$((SECONDS + TIMEOUT))
until [ -f "$VICTIM" ] && pgrep -f -- "--part 2/4" >/dev/null; do
  [ $SECONDS -lt $deadline ] || fail "part 2/4 never wrote a checkpoint"
  sleep 0.2
done
pkill -9 -f -- "render .*--part 2/4" || fail "part 2/4 was not running"
say "killed part 2/4 after its first checkpoint"
# Slurm holds a requeued job back for a while (its begin time moves about two minutes on, so a
# failing job cannot requeue in a tight loop); the test lifts that hold once the task is back in
# the queue, so that it runs in seconds. The requeue itself is Slurm's.
ARRAY=$(awk '/^array/ {print $2}' "$W/run/jobs.txt")
for _ in $(seq 120); do
  state=$(squeue -h -j "${ARRAY}_1" -o %T 2>/dev/null | head -1)
  [ "$state" = PENDING ] && break
  sleep 0.25
done
[ "$state" = PENDING ] || fail "part 2/4 was not requeued (state '$state')"
scontrol update JobId="${ARRAY}_1" StartTime=now || fail "scontrol update StartTime"

MERGED="$W/run/cornell-box.exr"
until [ -f "$MERGED" ]; do
  if [ $SECONDS -ge $deadline ]; then
    squeue; tail -30 "$W"/run/logs/*.log "$W/slurmctld.log"
    fail "no merged image after ${TIMEOUT} s"
  fi
  sleep 1
done
# The merge job writes atomically; wait for it to leave the queue.
for _ in $(seq 60); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.5; done
say "merged image written; part logs:"
cat "$W/run/logs/part-1.log"

grep -q "attempt 2" "$W/run/logs/part-1.log" || fail "part 2/4 was not run a second time"
grep -q "requeued" "$W/run/logs/part-1.log" || fail "part 2/4's failure did not requeue it"
grep -q "resuming part 2/4 from" "$W/run/logs/part-1.log" || fail "part 2/4 started over instead of resuming"

"$PT" slurm --status "$W/run" | tee "$W/status.txt"
grep -q "4 of 4 parts done, 1 of 1 images merged" "$W/status.txt" || fail "--status"

"$PT" render scenes/cornell-box.xml --spp $SPP "${ARGS[@]}" -o "$W/local.exr" --variance --quiet ||
  fail "local render"
"$PT" compare --identical "$MERGED" "$W/local.exr" || fail "the merged image differs from the local render"
"$PT" compare --identical "$W/run/cornell-box_var.exr" "$W/local_var.exr" ||
  fail "the merged variance differs from the local render's"
say "merged = local render, bit for bit; a killed part was requeued and resumed"
echo "1 passed, 0 failed"
