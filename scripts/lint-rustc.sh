#!/usr/bin/env bash
# The lints run inside the build (scripts/test.sh): cargo calls this as
# RUSTC_WORKSPACE_WRAPPER (`lint-rustc.sh RUSTC ARGS...`) for the workspace's own crates.
# Host builds go through clippy-driver, which compiles as rustc does and lints with
# CLIPPY_ARGS (`-D warnings`, as `cargo clippy -- -D warnings`), so the lints cost no
# second compile of the dependencies (CI's 20 minutes; docs/measurements.md). The MCU
# builds (`--target thumbv7em-none-eabihf`) go to rustc unchanged: clippy-driver turns
# MIR optimisations off, which would change the images' code, their flash budgets and
# the step's cycle estimate (scripts/cycles.py). Those crates are linted on the host.
# Bash, not sh: Debian's dash drops the environment variables whose names are not shell
# names, and cargo passes the integration tests theirs so (`CARGO_BIN_EXE_sil-host`).
rustc="$1"
shift
for arg in "$@"; do
  case "$arg" in
    thumbv7em-none-eabihf) exec "$rustc" "$@" ;;
  esac
done
exec clippy-driver "$rustc" "$@"
