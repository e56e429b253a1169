#!/usr/bin/env bash
# The brute-force bifurcation diagram (`sil-host sweep`) as a Slurm job array:
# task K of N computes the runs whose index is K modulo N into its own folder,
# then one dependent job joins the folders with `sil-host merge`.
#
#   sbatch --array=0-15 scripts/sweep-slurm.sh            # 16 shards of the paper's grid
#   SWEEP_ARGS="--controller hybrid --ics d" sbatch --array=0-7 scripts/sweep-slurm.sh
#
# Every task must get the same SWEEP_ARGS (the shards of one sweep; `merge`
# refuses folders of different sweeps). A task that is killed or pre-empted keeps
# every finished run: requeueing it (sbatch --requeue, or running it again by
# hand with the same arguments) resumes where it stopped. The merge job runs
# after all tasks succeed and reports any missing run with its shard.
#
# Environment: SWEEP_ARGS (extra `sil-host sweep` arguments), SWEEP_DIR (output
# root, default sweep-out), SIL_HOST (the binary, default target/release/sil-host).
#SBATCH --job-name=painleve-sweep
#SBATCH --cpus-per-task=4
#SBATCH --time=01:00:00
#SBATCH --requeue
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail

SIL_HOST=${SIL_HOST:-target/release/sil-host}
SWEEP_DIR=${SWEEP_DIR:-sweep-out}
SWEEP_ARGS=${SWEEP_ARGS:-}

if [ -z "${SLURM_ARRAY_TASK_ID:-}" ]; then
  echo "run with sbatch --array=0-(N-1) $0 (SLURM_ARRAY_TASK_ID is not set)" >&2
  exit 2
fi
K=$SLURM_ARRAY_TASK_ID
N=$SLURM_ARRAY_TASK_COUNT

# shellcheck disable=SC2086  # SWEEP_ARGS is a list of arguments
"$SIL_HOST" sweep $SWEEP_ARGS --shard "$K/$N" --threads "${SLURM_CPUS_PER_TASK:-1}" --out "$SWEEP_DIR/shard-$K"

# The first task queues the merge, to start once every task of the array has succeeded.
if [ "$K" = "${SLURM_ARRAY_TASK_MIN:-0}" ] && [ "${SLURM_RESTART_COUNT:-0}" = 0 ]; then
  shards=()
  for ((i = 0; i < N; i++)); do shards+=("$SWEEP_DIR/shard-$i"); done
  sbatch --dependency="afterok:$SLURM_ARRAY_JOB_ID" --job-name=painleve-merge --output="slurm-%j-merge.out" \
    --wrap "$SIL_HOST merge --out $SWEEP_DIR/merged ${shards[*]}"
fi
