#!/usr/bin/env python3
"""Checks that the two fronts resolve the features of every crate they share alike:
`cargo build --release -p sil-host --features full` (what scripts/test.sh and the tests
build) and the Python package's build (`maturin build`,
`pip install ./python`: `cargo build -p painleve-py`) then share their artefacts, and the
second compiles only the Python-only crates (docs/python.md "Install"); and that the
workspace's test build (`cargo test --workspace --features sil-host/full`, every member's
dev-dependencies with it) resolves them as the command line does, so it compiles only the
tests and their dev-dependencies (issue 68: `either`, `figures`' `default` and
`tungstenite`'s had it recompile a fifth of the tree).

Reads `cargo tree -e normal,build` of each front; prints each shared crate whose features
differ and exits 1, or prints one line and exits 0. The fix for a difference is in the
front that lacks the feature: the "One feature set" dependencies of sil-host/Cargo.toml
or python/Cargo.toml."""

import subprocess
import sys
from collections import defaultdict


def features(package, *extra: str) -> dict:
    """Each crate's builds in `cargo tree -p package` (the whole workspace for None),
    `-e normal,build` unless `extra` gives its own edges."""
    edges = [] if "-e" in extra else ["-e", "normal,build"]
    scope = ["-p", package] if package else []
    out = subprocess.run(
        ["cargo", "tree", *scope, *extra, *edges, "-f", "{p}|{f}", "--prefix", "none"],
        check=True, capture_output=True, text=True,
    ).stdout
    # A crate built for the target and for the host (a build script's or a proc macro's
    # dependency) resolves its features apart (resolver 2): each build is one feature
    # set, and a crate's builds are the set of them (a union would hide a target build
    # whose features differ while the host's cover them: issue 68, `either`).
    seen = defaultdict(set)
    for line in out.splitlines():
        line = line.removesuffix(" (*)").replace(" (proc-macro)", "")
        name, _, feats = line.partition("|")
        seen[name.strip()].add(frozenset(f for f in feats.split(",") if f))
    return seen


def show(builds: set) -> list:
    """A crate's builds as sorted feature lists."""
    return sorted(sorted(b) for b in builds)


def compare(a: dict, b: dict, name_a: str, name_b: str, what: str) -> bool:
    """Prints the shared crates whose builds differ; whether none does."""
    shared = sorted(set(a) & set(b))
    bad = [(n, show(a[n] - b[n]), show(b[n] - a[n])) for n in shared if a[n] != b[n]]
    for name, only_a, only_b in bad:
        print(f"{name}: builds only in {name_a} {only_a}, only in {name_b} {only_b}")
    if bad:
        print(f"{len(bad)} of {len(shared)} shared crates differ in features: {what}", file=sys.stderr)
        return False
    print(f"front features: the {len(shared)} crates {name_a} and {name_b} share have the same features")
    return True


def main() -> int:
    cli = features("sil-host", "--features", "full")
    ok = compare(cli, features("painleve-py"), "sil-host", "painleve-py", "the Python build recompiles them")
    # The tests (scripts/test.sh: `cargo test --workspace --features sil-host/full`, every
    # member's dev-dependencies with them) build on the command line's artefacts too.
    tests = features(None, "--workspace", "--features", "sil-host/full", "-e", "normal,build,dev")
    ok &= compare(cli, tests, "sil-host", "the workspace's tests", "the test build recompiles them")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
