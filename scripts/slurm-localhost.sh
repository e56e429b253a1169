#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for testing scripts/sweep-slurm.sh on a
# real Slurm (CI: tests/e2e/slurm.rs). Installs nothing: it needs Debian's
# `slurm-wlm` and `munge` (apt-get install -y slurm-wlm munge) and root (the
# daemons run as root: SlurmUser=root).
#
#   scripts/slurm-localhost.sh start DIR   # writes DIR/slurm.conf, starts munged,
#                                          # slurmctld and slurmd, waits for the node
#   scripts/slurm-localhost.sh stop DIR    # stops them (by their pid files in DIR)
#   scripts/slurm-localhost.sh run DIR CMD...  # start, run CMD with SLURM_CONF set, stop
#
# Everything lives in DIR (configuration, munge key and socket, state, spool, logs,
# pid files): nothing under /etc is touched, so it runs beside a system Slurm. The
# clients find the cluster through SLURM_CONF=DIR/slurm.conf.
#
# The configuration is the smallest that runs jobs in a container: no cgroups
# (proctrack/linuxproc, task/none), no accounting, select/cons_tres over the CPUs
# given (SLURM_LOCALHOST_CPUS, default 2: the machine may be shared). Ports:
# SLURM_LOCALHOST_PORT (slurmctld; slurmd uses the next one), default 16817.
set -euo pipefail

usage() {
  echo "usage: $0 start DIR | stop DIR | run DIR CMD..." >&2
  exit 2
}

[ $# -ge 2 ] || usage
action=$1
dir=$2
shift 2

stop() {
  local d=$1
  # slurmd first (it reports to slurmctld), munged last (both need it to talk).
  for name in slurmd slurmctld munged; do
    local pidfile="$d/$name.pid"
    [ -f "$pidfile" ] || continue
    local pid
    pid=$(cat "$pidfile")
    if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
      done
      kill -9 "$pid" 2>/dev/null || true
    fi
    rm -f "$pidfile"
  done
}

start() {
  local d=$1
  for cmd in munged slurmctld slurmd sinfo; do
    command -v "$cmd" >/dev/null || {
      echo "$cmd is missing: apt-get install -y slurm-wlm munge" >&2
      exit 1
    }
  done
  [ "$(id -u)" = 0 ] || {
    echo "the local cluster runs its daemons as root (SlurmUser=root): run as root" >&2
    exit 1
  }
  mkdir -p "$d"
  d=$(cd "$d" && pwd)
  # munged refuses directories that others can write to.
  chmod 0700 "$d"
  mkdir -p "$d/state" "$d/spool" "$d/munge"
  chmod 0700 "$d/munge"

  local host cpus port
  host=$(uname -n | cut -d. -f1)
  cpus=${SLURM_LOCALHOST_CPUS:-2}
  port=${SLURM_LOCALHOST_PORT:-16817}

  # munge: a fresh key, a private socket (slurm.conf's AuthInfo points at it).
  dd if=/dev/urandom of="$d/munge/munge.key" bs=1024 count=1 status=none
  chmod 0400 "$d/munge/munge.key"
  munged --force --key-file="$d/munge/munge.key" --socket="$d/munge/munge.socket" \
    --pid-file="$d/munged.pid" --log-file="$d/munged.log" --seed-file="$d/munge/munged.seed"

  cat >"$d/slurm.conf" <<EOF
# One node on localhost (scripts/slurm-localhost.sh).
ClusterName=localhost
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
# cred_expire: a requeued job waits this long before it starts again (default 120 s).
AuthInfo=socket=$d/munge/munge.socket,cred_expire=10
StateSaveLocation=$d/state
SlurmdSpoolDir=$d/spool
SlurmctldPidFile=$d/slurmctld.pid
SlurmdPidFile=$d/slurmd.pid
SlurmctldLogFile=$d/slurmctld.log
SlurmdLogFile=$d/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
# Start jobs at once (defaults: batch jobs wait up to 3 s, the scheduler runs at most
# every 2 s): a test's jobs last about a second.
SchedulerParameters=batch_sched_delay=0,sched_min_interval=100000,sched_interval=1
ReturnToService=2
# Finished jobs stay visible (scontrol show job) for 10 minutes.
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

  export SLURM_CONF="$d/slurm.conf"
  # -i: ignore any state of an earlier cluster in DIR.
  slurmctld -i -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF"

  local state=""
  for _ in $(seq 300); do
    state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.1
  done
  if [ "$state" != idle ]; then
    echo "the node did not become idle within 30 s (state: ${state:-none}); logs in $d:" >&2
    tail -n 20 "$d/slurmctld.log" "$d/slurmd.log" >&2 || true
    stop "$d"
    exit 1
  fi
  echo "export SLURM_CONF=$SLURM_CONF"
}

case $action in
  start)
    # A start that fails half way leaves nothing running.
    on_exit() {
      local status=$?
      [ "$status" = 0 ] || stop "$dir"
    }
    trap on_exit EXIT
    start "$dir"
    ;;
  stop) stop "$dir" ;;
  run)
    [ $# -ge 1 ] || usage
    trap 'stop "$dir"' EXIT
    start "$dir" >/dev/null
    SLURM_CONF="$(cd "$dir" && pwd)/slurm.conf" "$@"
    ;;
  *) usage ;;
esac
