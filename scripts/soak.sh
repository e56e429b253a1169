#!/usr/bin/env bash
# The soak test of the SIL rig at any length (docs/rig.md, "Soak test"):
#
#   scripts/soak.sh SECONDS SEED [OUT]      e.g. scripts/soak.sh 3600 1   (the hour)
#
# Runs tests/soak.rs in release with SOAK_SECONDS=SECONDS of simulated time and
# SOAK_SEED=SEED (the random fault schedule's and the sensor noise's seed): `sil-host
# run` over iceoryx2 in lockstep with the seeded faults, then the checks (counts
# against the faults, no leak in /dev/shm, /tmp/iceoryx2 or the temp folder, flat
# memory), then a short run ended by kill_firmware. Everything is kept in OUT
# (default target/soak/SECONDSs-seedSEED): soak/scenario.toml (rerun it by hand with
# `sil-host run --scenario OUT/soak/scenario.toml`), the run's outputs in soak/out/,
# and soak/soak-report.json (wall time, faults per kind, both sides' counts, RSS of
# both processes, iceoryx2 files before and after). Exit status: the test's.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
  echo "usage: scripts/soak.sh SECONDS SEED [OUT]   (SECONDS of simulated time >= 8, SEED an integer >= 0)" >&2
  exit 2
}
[ $# -ge 2 ] && [ $# -le 3 ] || usage
seconds="$1"
seed="$2"
[[ "$seconds" =~ ^[0-9]+([.][0-9]+)?$ ]] && awk -v s="$seconds" 'BEGIN { exit !(s >= 8 && s <= 100000) }' || usage
[[ "$seed" =~ ^[0-9]+$ ]] || usage
out="${3:-target/soak/${seconds}s-seed${seed}}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

echo "== /dev/shm before: $(find /dev/shm -mindepth 1 | wc -l) entries; iceoryx2 files: $(find /tmp/iceoryx2 -mindepth 1 2>/dev/null | wc -l)"
start=$(date +%s)
status=0
SOAK_SECONDS="$seconds" SOAK_SEED="$seed" SOAK_OUT="$out" \
  cargo test --release -p sil-host --features full --test soak -- --nocapture --test-threads 1 || status=$?
echo "== /dev/shm after: $(find /dev/shm -mindepth 1 | wc -l) entries; iceoryx2 files: $(find /tmp/iceoryx2 -mindepth 1 2>/dev/null | wc -l)"
echo "== $(($(date +%s) - start)) s of wall time (build included); report: $out/soak/soak-report.json"
exit "$status"
