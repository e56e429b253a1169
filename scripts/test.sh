#!/usr/bin/env bash
# The project's test command (README): builds the no_std crates for the MCU target
# and runs every test of the workspace. Safe to run on a fresh machine.
set -euo pipefail
cd "$(dirname "$0")/.."

# The MCU target (rustup does not install it by itself: RUSTUP_AUTO_INSTALL=0).
rustup target add thumbv7em-none-eabihf

echo "== no_std build of shared and firmware for thumbv7em-none-eabihf"
cargo build --release -p shared -p firmware --target thumbv7em-none-eabihf

echo "== tests (release: the simulator is numerical)"
cargo test --workspace --release
