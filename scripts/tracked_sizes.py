#!/usr/bin/env python3
"""Fails on a file tracked by git that is larger than 1 MiB, outside the list of files
allowed to be (ALLOWED below, each with its reason). A wheel, an archive or a build's
output committed by mistake stays in the history of every clone; this check stops it
before it lands (scripts/test.sh runs it; docs/architecture.md "Hygiene").

Prints each offending path with its size and exits 1, or prints one line and exits 0."""

import os
import subprocess
import sys

LIMIT = 1 << 20

# Paths (from the repository's root) allowed above LIMIT, with why. None today: the
# largest tracked files are the recorded figures (docs/figures, under 1 MiB each) and the
# golden digests (tests/golden/digests.txt, a few kB).
ALLOWED: dict[str, str] = {}


def main() -> int:
    root = subprocess.run(["git", "rev-parse", "--show-toplevel"], check=True, capture_output=True, text=True).stdout.strip()
    paths = subprocess.run(["git", "ls-files", "-z"], check=True, capture_output=True, cwd=root).stdout.split(b"\0")
    big = []
    largest = (0, "")
    for raw in paths:
        if not raw:
            continue
        path = raw.decode()
        full = os.path.join(root, path)
        if not os.path.isfile(full):
            continue
        size = os.path.getsize(full)
        largest = max(largest, (size, path))
        if size > LIMIT and path not in ALLOWED:
            big.append((size, path))
    for size, path in sorted(big, reverse=True):
        print(f"{path}: {size / 1e6:.1f} MB tracked (limit {LIMIT >> 20} MiB; remove it, or add it to ALLOWED in scripts/tracked_sizes.py with the reason)")
    if big:
        return 1
    print(f"tracked files: none over {LIMIT >> 20} MiB outside the allowed list (largest {largest[1]}, {largest[0] / 1e6:.2f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
