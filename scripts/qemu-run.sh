#!/usr/bin/env bash
# Runs a Cortex-M4F image in QEMU's netduinoplus2 (an STM32F405), semihosting on:
# the image's defmt log (binary frames) goes to stdout and it exits through
# semihosting with its status. Usage: scripts/qemu-run.sh ELF [extra qemu args]
set -euo pipefail
elf="$1"; shift
if ! command -v qemu-system-arm >/dev/null; then
  echo "qemu-system-arm not found: apt-get install -y qemu-system-arm" >&2
  exit 127
fi
exec timeout "${QEMU_TIMEOUT:-120}" qemu-system-arm -machine netduinoplus2 -cpu cortex-m4 -nographic -monitor none \
  -serial null -semihosting-config enable=on,target=native -kernel "$elf" "$@"
