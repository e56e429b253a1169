#!/usr/bin/env bash
# The cargo runner of thumbv7em-none-eabihf (.cargo/config.toml): `cargo run` (and the
# aliases `cargo arm`, `cargo pil`, `cargo qemu-arm`) hand it the image's ELF.
#   - An image built with profile `qemu` (target/thumbv7em-none-eabihf/qemu/...: feature
#     `qemu`, semihosting logs) runs in QEMU's netduinoplus2: scripts/qemu-run.sh.
#   - Any other image is flashed to a board with probe-rs, which prints its defmt log
#     over RTT (the knurling app-template's runner). Without probe-rs it says how to
#     install it, and what runs without a board, and exits 127.
# PAINLEVE_CHIP overrides the chip probe-rs is told (default STM32F405RGTx), PAINLEVE_PROBE_RS
# the probe-rs program (default `probe-rs` on PATH; tests/e2e/aliases.rs names a missing one).
# Usage: scripts/runner.sh ELF [args...]   (docs/board.md "Flash the arm image")
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: scripts/runner.sh ELF [args...] (the cargo runner of thumbv7em-none-eabihf)" >&2
  exit 2
fi
elf="$1"; shift
here="$(cd "$(dirname "$0")" && pwd)"
case "$elf" in
  */thumbv7em-none-eabihf/qemu/*)
    exec bash "$here/qemu-run.sh" "$elf" "$@"
    ;;
esac
probe_rs="${PAINLEVE_PROBE_RS:-probe-rs}"
if ! command -v "$probe_rs" >/dev/null; then
  cat >&2 <<MSG
error: probe-rs is not installed ($probe_rs not found): it flashes $(basename "$elf") to the board and prints its defmt log.
  install it:  cargo install probe-rs-tools --locked   (or https://probe.rs/docs/getting-started/installation/)
  then connect a debug probe (ST-LINK, J-Link, CMSIS-DAP) to the board's SWD pins (PA13/PA14) and run this again.
  without a board:
    cargo qemu-arm                                     # the arm image in QEMU (semihosting log)
    cargo build-pil && cargo run --release -p sil-host -- pil   # the PIL image in QEMU, the plant on the PC
    cargo build-arm && cargo run --release -p sil-host --features board -- run --link emulator   # the flashed bytes, emulated
  (docs/board.md "Tools (once)", "Under QEMU")
MSG
  exit 127
fi
exec "$probe_rs" run --chip "${PAINLEVE_CHIP:-STM32F405RGTx}" "$elf" "$@"
