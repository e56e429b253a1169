#!/usr/bin/env python3
"""Checks that the two fronts resolve the features of every crate they share alike:
`cargo build --release -p sil-host --features full` (what scripts/test.sh and the tests
build) and the Python package's build (`maturin build`,
`pip install ./python`: `cargo build -p painleve-py`) then share their artefacts, and the
second compiles only the Python-only crates (docs/python.md "Install").

Reads `cargo tree -e normal,build` of each front; prints each shared crate whose features
differ and exits 1, or prints one line and exits 0. The fix for a difference is in the
front that lacks the feature: the "One feature set" dependencies of sil-host/Cargo.toml
or python/Cargo.toml."""

import subprocess
import sys
from collections import defaultdict


def features(package: str, *extra: str) -> dict:
    out = subprocess.run(
        ["cargo", "tree", "-p", package, *extra, "-e", "normal,build", "-f", "{p}|{f}", "--prefix", "none"],
        check=True, capture_output=True, text=True,
    ).stdout
    seen = defaultdict(set)
    for line in out.splitlines():
        line = line.removesuffix(" (*)").replace(" (proc-macro)", "")
        name, _, feats = line.partition("|")
        seen[name.strip()].update(f for f in feats.split(",") if f)
    return seen


def main() -> int:
    a, b = features("sil-host", "--features", "full"), features("painleve-py")
    shared = sorted(set(a) & set(b))
    bad = [(n, sorted(a[n] - b[n]), sorted(b[n] - a[n])) for n in shared if a[n] != b[n]]
    for name, only_a, only_b in bad:
        print(f"{name}: only sil-host {only_a}, only painleve-py {only_b}")
    if bad:
        print(f"{len(bad)} of {len(shared)} shared crates differ in features: the Python build recompiles them", file=sys.stderr)
        return 1
    print(f"front features: the {len(shared)} crates sil-host and painleve-py share have the same features")
    return 0


if __name__ == "__main__":
    sys.exit(main())
