#!/usr/bin/env bash
# The brute-force bifurcation diagram (`sil-host sweep`) as a Slurm job array, one
# shard (`--shard K/N`) per task, then one job that joins the shards' folders with
# `sil-host merge`. Submit from the login node (docs/analyses.md, "Cluster"):
#
#   scripts/sweep-slurm.sh submit --array=1-16 [SBATCH OPTIONS] [-- SWEEP ARGUMENTS]
#
# e.g. `scripts/sweep-slurm.sh submit --array=0-15 -p long -- --controller hybrid --ics d`.
# It submits the array (N tasks = N shards; any array form: 1-16, 0-30:2, 1,5,9,
# with or without a %limit: task K of the array, counted in ascending task ids, is
# shard K/N), then the merge job with --dependency=afterany on the array: it runs
# once every task has ended, whatever happened to them, and fails naming the
# missing shards and the command that re-runs them. It prints
# `ARRAY_JOB_ID MERGE_JOB_ID` on stdout. The SBATCH options go to both jobs
# (--array only to the array).
#
# Re-running shards: `SWEEP_SHARDS=N scripts/sweep-slurm.sh submit --array=3,7 ...`
# runs shards 3/N and 7/N (with SWEEP_SHARDS the task id is the shard) and merges
# again. A shard's folder resumes: its finished runs are kept, so a re-run, a
# requeued task (#SBATCH --requeue; `scontrol requeue JOB_TASK`) or a pre-empted
# one computes only what is missing.
#
# Environment at submission: SIL_HOST (the binary, default target/release/sil-host),
# SWEEP_DIR (output root, default sweep-out; shard K writes SWEEP_DIR/shard-K, the
# merge SWEEP_DIR/merged and its log SWEEP_DIR/slurm-merge-JOBID.out), SWEEP_ARGS
# (sweep arguments, words split on spaces, before those after `--`). Both paths
# are made absolute and must be on a filesystem every node sees. The jobs get
# their settings as arguments, not from the environment (--export does not matter).
#
# Also: `sbatch --array=0-15 scripts/sweep-slurm.sh` (the array alone, settings from
# the environment, a single range A-B[:S] only, no merge job), and
# `scripts/sweep-slurm.sh merge N` (join SWEEP_DIR/shard-0..N-1 by hand).
#SBATCH --job-name=painleve-sweep
#SBATCH --cpus-per-task=4
#SBATCH --time=01:00:00
#SBATCH --requeue
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail

die() {
  echo "sweep-slurm: $*" >&2
  exit 2
}

# The task ids of an array specification (sbatch --array), ascending, one a line.
array_ids() {
  local spec=${1%\%*} item a b s
  [ -n "$spec" ] || die "empty --array"
  local IFS=,
  for item in $spec; do
    if [[ $item =~ ^([0-9]+)$ ]]; then
      echo "$item"
    elif [[ $item =~ ^([0-9]+)-([0-9]+)(:([0-9]+))?$ ]]; then
      a=$((10#${BASH_REMATCH[1]})) b=$((10#${BASH_REMATCH[2]})) s=$((10#${BASH_REMATCH[4]:-1}))
      ((a <= b && s >= 1)) || die "--array=$1: bad range $item"
      seq "$a" "$s" "$b"
    else
      die "--array=$1: cannot read $item (expected A, A-B or A-B:S, comma-separated)"
    fi
  done | sort -n -u
}

# K N of this array task: from SHARDING (`array:SPEC`: position of the task id
# among the array's ids; `shards:N`: the task id itself), or without it from
# Slurm's variables (a single range: (ID - MIN) / STEP of COUNT).
shard_of_task() {
  local sharding=$1 id=${SLURM_ARRAY_TASK_ID:-}
  [[ $id =~ ^[0-9]+$ ]] || die "not an array task (SLURM_ARRAY_TASK_ID is '$id'): submit with scripts/sweep-slurm.sh submit --array=..."
  case $sharding in
    array:*)
      local ids
      ids=$(array_ids "${sharding#array:}")
      N=$(wc -l <<<"$ids")
      K=$(grep -n -x -- "$id" <<<"$ids" | cut -d: -f1) || die "task $id is not in --array=${sharding#array:}"
      K=$((K - 1))
      ;;
    shards:*)
      N=${sharding#shards:}
      K=$id
      ((K < N)) || die "SWEEP_SHARDS=$N: task id $id is not a shard (0..$((N - 1)))"
      ;;
    "")
      local min=${SLURM_ARRAY_TASK_MIN:-} step=${SLURM_ARRAY_TASK_STEP:-} count=${SLURM_ARRAY_TASK_COUNT:-} max=${SLURM_ARRAY_TASK_MAX:-}
      if [ -z "$min" ] || [ -z "$step" ] || [ -z "$count" ] || [ -z "$max" ]; then
        die "cannot tell this task's shard: SLURM_ARRAY_TASK_MIN/STEP/COUNT/MAX are not all set (submit with scripts/sweep-slurm.sh submit)"
      fi
      if ((step < 1 || (id - min) % step != 0 || min + (count - 1) * step != max)); then
        die "cannot tell this task's shard: the array (ids $min..$max, $count tasks, step $step) is not one range A-B[:S]; submit with scripts/sweep-slurm.sh submit, which reads any --array"
      fi
      K=$(((id - min) / step))
      N=$count
      ;;
    *) die "unknown sharding $sharding" ;;
  esac
}

# One task: shard K/N into SWEEP_DIR/shard-K (resumes what is there).
task() {
  local sharding=$1 sil_host=$2 dir=$3
  shift 3
  shard_of_task "$sharding"
  echo "task ${SLURM_ARRAY_JOB_ID:-?}_${SLURM_ARRAY_TASK_ID}: shard $K/$N into $dir/shard-$K (restart ${SLURM_RESTART_COUNT:-0})" >&2
  exec "$sil_host" sweep "$@" --shard "$K/$N" --threads "${SLURM_CPUS_PER_TASK:-1}" --out "$dir/shard-$K"
}

# The merge job: joins SWEEP_DIR/shard-0..N-1 into SWEEP_DIR/merged; on missing
# runs, names the shards and how to re-run them.
merge() {
  local n=$1 sil_host=$2 dir=$3
  shift 3
  local dirs=() absent=() k
  for ((k = 0; k < n; k++)); do
    if [ -f "$dir/shard-$k/sweep.json" ]; then dirs+=("$dir/shard-$k"); else absent+=("$k"); fi
  done
  if ((${#absent[@]} > 0)); then
    echo "sweep-slurm: no folder for shards $(IFS=,; echo "${absent[*]}") of $n (their tasks failed before starting the sweep, or never ran)" >&2
  fi
  local status=0 log
  log=$(mktemp)
  if ((${#dirs[@]} == 0)); then
    echo "sweep-slurm: no shard folder in $dir: nothing to merge" >&2
    status=1
    printf 'shards with missing runs: %s\n' "$(seq -s, 0 $((n - 1)))" >"$log"
  else
    "$sil_host" merge --out "$dir/merged" "${dirs[@]}" 2>"$log" || status=$?
    cat "$log" >&2
  fi
  if ((status != 0)); then
    local missing
    missing=$(grep -o 'shards with missing runs: [0-9,]*' "$log" | head -n 1 | sed 's/.*: //') || true
    echo "sweep-slurm: the merge failed (exit $status). To finish the sweep, re-run the shards with missing runs (their finished runs are kept) and merge again:" >&2
    printf '  SWEEP_SHARDS=%s SWEEP_DIR=%q SIL_HOST=%q %s submit --array=%s [the same sbatch options] --' \
      "$n" "$dir" "$sil_host" "scripts/sweep-slurm.sh" "${missing:-K1,K2,...}" >&2
    (($# == 0)) || printf ' %q' "$@" >&2
    echo >&2
  fi
  rm -f "$log"
  return "$status"
}

submit() {
  local spec="" sbatch_opts=() sweep_args=()
  while [ $# -gt 0 ]; do
    case $1 in
      --)
        shift
        sweep_args=("$@")
        break
        ;;
      --array=*) spec=${1#--array=} ;;
      --array | -a)
        [ $# -ge 2 ] || die "$1 needs a value"
        spec=$2
        shift
        ;;
      -a*) spec=${1#-a} ;;
      *) sbatch_opts+=("$1") ;;
    esac
    shift
  done
  [ -n "$spec" ] || die "submit needs --array=SPEC (e.g. --array=1-16): one task per shard"
  command -v sbatch >/dev/null || die "sbatch is not on the PATH: submit from a machine of the cluster"
  local ids n sharding
  ids=$(array_ids "$spec")
  if [ -n "${SWEEP_SHARDS:-}" ]; then
    [[ $SWEEP_SHARDS =~ ^[1-9][0-9]*$ ]] || die "SWEEP_SHARDS must be a count >= 1, got $SWEEP_SHARDS"
    n=$SWEEP_SHARDS
    (($(tail -n 1 <<<"$ids") < n)) || die "SWEEP_SHARDS=$n: the task ids are the shards, so --array must lie within 0-$((n - 1))"
    sharding=shards:$n
  else
    n=$(wc -l <<<"$ids")
    sharding=array:$spec
  fi

  local sil_host=${SIL_HOST:-target/release/sil-host} dir=${SWEEP_DIR:-sweep-out}
  [ -x "$sil_host" ] || die "SIL_HOST=$sil_host is not an executable (build it: cargo build --release -p sil-host)"
  sil_host=$(cd "$(dirname "$sil_host")" && pwd)/$(basename "$sil_host")
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  # shellcheck disable=SC2206  # SWEEP_ARGS is a list of words
  local env_args=(${SWEEP_ARGS:-})
  sweep_args=("${env_args[@]}" "${sweep_args[@]}")

  # The sweep's arguments are checked here (a typo would fail every task): the
  # same command as a task's, computing nothing, into a scratch folder.
  local scratch
  scratch=$(mktemp -d)
  if ! "$sil_host" sweep "${sweep_args[@]}" --shard "0/$n" --threads 1 --limit 0 --json --out "$scratch/check" >/dev/null 2>"$scratch/err"; then
    cat "$scratch/err" >&2
    rm -rf "$scratch"
    die "the sweep arguments were refused (nothing submitted)"
  fi
  rm -rf "$scratch"

  local script array_id merge_id
  script=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/$(basename "${BASH_SOURCE[0]}")
  array_id=$(sbatch --parsable "${sbatch_opts[@]}" --array="$spec" "$script" task "$sharding" "$sil_host" "$dir" "${sweep_args[@]}")
  array_id=${array_id%%;*}
  if ! merge_id=$(sbatch --parsable "${sbatch_opts[@]}" --dependency="afterany:$array_id" --job-name=painleve-merge \
    --cpus-per-task=1 --output="$dir/slurm-merge-%j.out" "$script" merge "$n" "$sil_host" "$dir" "${sweep_args[@]}"); then
    echo "sweep-slurm: the array job $array_id is queued but the merge job was refused; merge by hand once it has ended:" >&2
    echo "  SWEEP_DIR=$dir SIL_HOST=$sil_host $script merge $n" >&2
    exit 1
  fi
  merge_id=${merge_id%%;*}
  echo "sweep-slurm: array job $array_id ($n shards into $dir/shard-K), merge job $merge_id after it (into $dir/merged, log $dir/slurm-merge-$merge_id.out)" >&2
  echo "$array_id $merge_id"
}

case ${1:-} in
  submit)
    shift
    [ -z "${SLURM_JOB_ID:-}" ] || echo "sweep-slurm: note: submitting from inside job $SLURM_JOB_ID" >&2
    submit "$@"
    ;;
  task)
    [ $# -ge 4 ] || die "usage: $0 task SHARDING SIL_HOST DIR [SWEEP ARGUMENTS] (written by submit)"
    shift
    task "$@"
    ;;
  merge)
    [ $# -ge 2 ] || die "usage: $0 merge N (SWEEP_DIR, SIL_HOST from the environment)"
    [[ $2 =~ ^[1-9][0-9]*$ ]] || die "merge: N must be a count >= 1, got $2"
    if [ $# -ge 4 ]; then
      shift
      merge "$@"
    else
      # shellcheck disable=SC2206  # SWEEP_ARGS is a list of words
      sweep_args=(${SWEEP_ARGS:-})
      merge "$2" "${SIL_HOST:-target/release/sil-host}" "${SWEEP_DIR:-sweep-out}" "${sweep_args[@]}"
    fi
    ;;
  "")
    # `sbatch --array=A-B[:S] scripts/sweep-slurm.sh`: settings from the environment.
    [ -n "${SLURM_ARRAY_TASK_ID:-}" ] ||
      die "submit with: $0 submit --array=1-16 [SBATCH OPTIONS] [-- SWEEP ARGUMENTS] (SLURM_ARRAY_TASK_ID is not set)"
    # shellcheck disable=SC2206
    sweep_args=(${SWEEP_ARGS:-})
    task "" "${SIL_HOST:-target/release/sil-host}" "${SWEEP_DIR:-sweep-out}" "${sweep_args[@]}"
    ;;
  *) die "unknown mode $1 (submit, task, merge)" ;;
esac
