#!/usr/bin/env bash
# The Python package's section of scripts/test.sh (docs/python.md "Tests"), runnable alone after
# `cargo build --release -p sil-host --features full`:
#   1. the build tools (python/requirements-build.txt: maturin, ziglang, auditwheel) in target/venv-python;
#   2. scripts/build-wheel.sh: the manylinux2014 abi3 wheel and the sdist in target/wheels, cargo in the
#      workspace's target dir (sil-host's release artefacts reused);
#   3. a fresh target/venv-wheel, made anew each run, whose PATH is its own bin, /usr/bin and /bin: no
#      cargo, no rustc (checked here and by python/tests/test_wheel_install.py). pip installs the wheel
#      (binary packages only: nothing is built) and the tests' packages (python/requirements-test.txt);
#      the wheel's install is timed;
#   4. pytest from that environment against target/release/sil-host (or $PAINLEVE_SIL_HOST).
# Exit status: pytest's, or 1 with a message when a step before it fails.
set -euo pipefail
cd "$(dirname "$0")/.."
die() { echo "python-tests: $*" >&2; exit 1; }

sil_host="${PAINLEVE_SIL_HOST:-$PWD/target/release/sil-host}"
[ -x "$sil_host" ] || die "$sil_host is missing: cargo build --release -p sil-host --features full (or set PAINLEVE_SIL_HOST)"

# Debian's python3 has no ensurepip (so no venv) without python3-venv.
if ! python3 -c "import ensurepip, venv" 2>/dev/null; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update && apt-get install -y python3-venv
  else
    die "python3 with venv is missing: sudo apt-get install -y python3-venv"
  fi
fi

# 1 and 2. The build tools in target/venv-python (made if missing), the wheel and the sdist.
PAINLEVE_BUILD_VENV=target/venv-python bash scripts/build-wheel.sh
wheel="$(ls target/wheels/painleve-*-cp39-abi3-manylinux_2_17_x86_64.manylinux2014_x86_64.whl)"

# 3. A fresh environment without Rust.
venv="$PWD/target/venv-wheel"
rm -rf "$venv"
python3 -m venv "$venv"
clean_path="$venv/bin:/usr/bin:/bin"
for tool in cargo rustc rustup; do
  if found="$(env PATH="$clean_path" sh -c "command -v $tool")"; then
    die "$tool is on the test environment's PATH ($found): the wheel must install and run without Rust"
  fi
done
run() { env PATH="$clean_path" PAINLEVE_WHEEL_VENV="$venv" "$@"; }
pip_quiet=(--quiet --disable-pip-version-check --only-binary :all:)
t0="$(date +%s.%N)"
# From scripts/test.sh's downloaded wheels when it set PIP_NO_INDEX (PIP_FIND_LINKS), else
# from the index; from the index again if a package was missing there.
pip_install() {
  run "$venv/bin/pip" install "${pip_quiet[@]}" "$@" && return 0
  [ -n "${PIP_NO_INDEX:-}" ] || return 1
  echo "python-tests: not all in $PIP_FIND_LINKS: from the index" >&2
  run env -u PIP_NO_INDEX "$venv/bin/pip" install "${pip_quiet[@]}" "$@"
}
pip_install -c python/requirements-test.txt "$wheel" \
  || die "pip could not install $wheel into $venv"
t1="$(date +%s.%N)"
# --no-compile: no bytecode for the tests' packages' many modules the tests never import
# (Jupyter's, MuJoCo's, polars'), compiled on import instead.
pip_install --no-compile -r python/requirements-test.txt \
  || die "pip could not install python/requirements-test.txt into $venv"
t2="$(date +%s.%N)"
awk -v a="$t0" -v b="$t1" -v c="$t2" -v w="$(basename "$wheel")" 'BEGIN {
  printf "python-tests: %s installed (with NumPy) into a fresh venv without Rust in %.1f s; the tests%s packages %.1f s\n", w, b - a, "\047", c - b }'

# 4. The tests, from that environment: `painleve` is the installed wheel's (python/tests/test_defaults.py).
run env PAINLEVE_SIL_HOST="$sil_host" "$venv/bin/python" -m pytest python/tests -q -p no:cacheprovider -n auto --dist loadfile --durations=12
