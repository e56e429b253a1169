#!/usr/bin/env bash
# Runs a Cortex-M4F image built with the `qemu` feature in QEMU's netduinoplus2
# (an STM32F405) under `-icount shift=0,sleep=off` (virtual time follows retired
# instructions and skips idle time: deterministic), semihosting on: the image's
# defmt log goes to stdout (decoded with defmt-print when stdout is a terminal
# and `defmt-print` is installed: `cargo install defmt-print`), and it exits
# through semihosting with its status.
# Usage: scripts/qemu-run.sh ELF [extra qemu args]   (scripts/runner.sh calls it for profile `qemu`: `cargo qemu-arm`)
set -euo pipefail
elf="$1"; shift
if ! command -v qemu-system-arm >/dev/null; then
  echo "qemu-system-arm not found: apt-get install -y qemu-system-arm" >&2
  exit 127
fi
run() {
  timeout "${QEMU_TIMEOUT:-120}" qemu-system-arm -machine netduinoplus2 -cpu cortex-m4 -nographic -monitor none \
    -serial null -icount shift=0,sleep=off -semihosting-config enable=on,target=native -kernel "$elf" "$@"
}
if [ -t 1 ] && command -v defmt-print >/dev/null; then
  run "$@" | defmt-print -e "$elf"
  exit "${PIPESTATUS[0]}"
elif [ -t 1 ]; then
  echo "(binary defmt log follows: install defmt-print to read it: cargo install defmt-print)" >&2
fi
run "$@"
