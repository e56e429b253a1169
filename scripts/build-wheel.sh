#!/usr/bin/env bash
# Builds the Python package's distributions (docs/python.md "Install"): into target/wheels,
#   painleve-<version>-cp39-abi3-manylinux_2_17_x86_64.manylinux2014_x86_64.whl  one wheel for every
#       CPython from 3.9 (abi3) on any x86_64 Linux with glibc 2.17 or later (manylinux2014: CentOS 7,
#       RHEL 8, Debian 10, Ubuntu 18.04 and later), installable with pip and no Rust;
#   painleve-<version>.tar.gz  the sdist: `pip install` builds it with cargo (Rust 1.95 or later).
#
# How: `maturin build --release --compatibility manylinux2014` with cargo in the workspace's target dir
# (target/release, so every crate `cargo build --release -p sil-host` built is reused and only the
# binding crate painleve-py is compiled), and the extension linked by zig's `cc` against glibc 2.17's
# symbol versions (`-C linker=`, passed by maturin to the final rustc call only: the dependencies' own
# builds and their fingerprints stay the host's). `maturin build --zig` does the same but builds for an
# explicit `--target`, a second tree of every crate: 10 min 46 s here against 45 s (docs/python.md).
# maturin's own check refuses a library above the policy's symbol versions; then `auditwheel show`
# must find manylinux_2_17 and no external library, and no undefined symbol may be left without a
# version but Python's own (`Py*`, resolved by the interpreter) and weak ones (looked up at run time).
#
# Usage: scripts/build-wheel.sh [--no-sdist]
# The tools (maturin, ziglang, auditwheel: python/requirements-build.txt, pinned, from PyPI) come from
# the virtual environment $PAINLEVE_BUILD_VENV (default target/venv-python), made if missing.
set -euo pipefail
cd "$(dirname "$0")/.."

die() { echo "build-wheel: $*" >&2; exit 1; }
sdist=1
for a in "$@"; do
  case "$a" in
    --no-sdist) sdist=0 ;;
    -h | --help) awk 'NR > 1 && /^#/ { print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) die "unknown argument '$a' (usage: scripts/build-wheel.sh [--no-sdist])" ;;
  esac
done

[ "$(uname -m)" = x86_64 ] && [ "$(uname -s)" = Linux ] || die "this script builds the x86_64 Linux wheel; here is $(uname -s) $(uname -m)"
# The tools: the pinned python/requirements-build.txt in $PAINLEVE_BUILD_VENV (default
# target/venv-python), made here if missing. A virtual environment holds its own absolute path: one
# whose target folder was moved or copied (a cache restored elsewhere) no longer runs, and is made afresh.
tools="${PAINLEVE_BUILD_VENV:-target/venv-python}"
if [ ! -x "$tools/bin/pip" ] || ! "$tools/bin/pip" --version >/dev/null 2>&1; then
  python3 -c "import ensurepip, venv" 2>/dev/null || die "python3 with venv is missing: apt-get install -y python3-venv"
  rm -rf "$tools" && python3 -m venv "$tools" || die "could not make a virtual environment at $tools"
fi
# From scripts/test.sh's downloaded wheels when it set PIP_NO_INDEX, and from the index
# again if one was missing there.
"$tools/bin/pip" install --quiet --disable-pip-version-check -r python/requirements-build.txt \
  || { [ -n "${PIP_NO_INDEX:-}" ] && env -u PIP_NO_INDEX "$tools/bin/pip" install --quiet --disable-pip-version-check -r python/requirements-build.txt; } \
  || die "pip could not install python/requirements-build.txt into $tools"
tools="$(cd "$tools" && pwd)"
for exe in maturin auditwheel python; do
  [ -x "$tools/bin/$exe" ] || die "$tools/bin/$exe is missing after installing python/requirements-build.txt"
done
zig="$("$tools/bin/python" -c 'import os, ziglang; print(os.path.join(os.path.dirname(ziglang.__file__), "zig"))' 2>/dev/null)" \
  || die "the ziglang package is missing from $tools: $tools/bin/pip install -r python/requirements-build.txt"
[ -x "$zig" ] || die "ziglang's zig is not at $zig"
command -v nm >/dev/null || die "nm (binutils) is missing: apt-get install -y binutils"

# The linker: maturin's `zig cc` wrapper (it turns rustc's linker arguments into zig's) for glibc 2.17.
# Written anew each run, with this checkout's paths; CARGO_ZIGBUILD_ZIG_PATH names the zig to run.
linker_dir="$PWD/target/zig-linker"
mkdir -p "$linker_dir"
linker="$linker_dir/cc-x86_64-linux-gnu.2.17"
cat >"$linker.tmp" <<EOF
#!/bin/sh
# Written by scripts/build-wheel.sh: zig's cc linking against glibc 2.17 (manylinux2014).
CARGO_ZIGBUILD_ZIG_PATH='$zig' exec '$tools/bin/maturin' zig cc -- -fno-sanitize=all -target x86_64-linux-gnu.2.17 "\$@"
EOF
chmod +x "$linker.tmp" && mv "$linker.tmp" "$linker"

out="target/wheels"
rm -rf "$out"
started=$SECONDS
"$tools/bin/maturin" build --release --compatibility manylinux2014 -m python/Cargo.toml \
  --interpreter "$tools/bin/python" --out "$out" -- -C "linker=$linker" \
  || die "maturin build failed (above); a 'not manylinux_2_17 compliant' error names the symbols a dependency needs from a newer glibc"
build_s=$((SECONDS - started))

shopt -s nullglob
wheels=("$out"/painleve-*-cp39-abi3-manylinux_2_17_x86_64.manylinux2014_x86_64.whl)
all=("$out"/*.whl)
[ "${#wheels[@]}" -eq 1 ] && [ "${#all[@]}" -eq 1 ] || die "expected one manylinux2014 abi3 wheel in $out, found: ${all[*]:-none}"
wheel="${wheels[0]}"

# auditwheel's verdict: the tag the symbols allow, and no library outside the policy.
"$tools/bin/auditwheel" show --json "$wheel" >"$out/auditwheel.json" || die "auditwheel show failed on $wheel"
"$tools/bin/python" - "$out/auditwheel.json" <<'EOF' || die "auditwheel show: the wheel is not manylinux2014 (target/wheels/auditwheel.json)"
import json, sys
d = json.load(open(sys.argv[1]))
ok = d["overall_tag"] == "manylinux_2_17_x86_64" and not d["external_libs"]
glibc = sorted({v for vs in d["versioned_symbols"].values() for v in vs if v.startswith("GLIBC_")}, key=lambda v: [int(x) for x in v[6:].split(".")])
print(f"auditwheel: {d['overall_tag']}, newest glibc symbol version {glibc[-1]}, external libraries {sorted(d['external_libs']) or 'none'}")
sys.exit(0 if ok else 1)
EOF

# No strong undefined symbol without a version but the interpreter's: a C dependency compiled
# against a newer glibc's headers would leave one (glibc 2.17's stubs lack it) and fail on import.
so_dir="$(mktemp -d)"
trap 'rm -rf "$so_dir"' EXIT
"$tools/bin/python" -c 'import sys, zipfile; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])' "$wheel" "$so_dir"
so=("$so_dir"/painleve/_painleve*.so)
[ "${#so[@]}" -eq 1 ] || die "no painleve/_painleve*.so in $wheel"
loose="$(nm -D --undefined-only "${so[0]}" | awk '$1 == "U" && $2 !~ /@/ && $2 !~ /^_?Py/ { print $2 }')"
[ -z "$loose" ] || die "the extension leaves symbols undefined without a version (not in glibc 2.17): $loose"

size_kb=$(($(stat -c %s "$wheel") / 1024))
echo "build-wheel: $wheel ($size_kb KiB) in ${build_s} s"
if [ "$sdist" = 1 ]; then
  "$tools/bin/maturin" sdist -m python/Cargo.toml --out "$out" || die "maturin sdist failed (above)"
  sdists=("$out"/painleve-*.tar.gz)
  [ "${#sdists[@]}" -eq 1 ] || die "expected one sdist in $out, found: ${sdists[*]:-none}"
  # The crates' sources, and the file rig embeds from outside its crate (include_str!).
  listing="$(tar tzf "${sdists[0]}")"
  for f in pyproject.toml python/Cargo.toml rig/src/lib.rs scenarios/default.toml; do
    grep -qx "painleve-[^/]*/$f" <<<"$listing" || die "the sdist ${sdists[0]} lacks $f"
  done
  echo "build-wheel: ${sdists[0]} ($(($(stat -c %s "${sdists[0]}") / 1024)) KiB)"
fi
