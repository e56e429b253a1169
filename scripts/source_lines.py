#!/usr/bin/env python3
"""Fails on a tracked Rust source file with more than 500 non-test lines
(docs/architecture.md, "One concept per module": a file that long holds more than
one idea; issue 83). Non-test lines are a source file's lines before its first
`#[cfg(test)]` line; test files (under a `tests/` folder, `tests.rs`, `*_tests.rs`)
and benches do not count.

The command line's crate has a ceiling of its own: `sil-host/src` at most
`FOLDER_LIMITS["sil-host/src"]` non-test lines summed over its files (issue 83: library ideas
grew back into the commands; a command is thin, what it runs lives in a library crate).

Prints each offending path or folder with its count and exits 1, or prints one line (the
longest file, and each folder's sum against its ceiling) and exits 0."""

import os
import subprocess
import sys

LIMIT = 500
#: Ceilings on a folder's non-test lines, summed over its files (issue 83, item 2).
FOLDER_LIMITS = {"sil-host/src": 10_500}


def non_test_lines(path: str) -> int:
    n = 0
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("#[cfg(test)]"):
                break
            n += 1
    return n


def is_test(path: str) -> bool:
    parts = path.split("/")
    name = parts[-1]
    return "tests" in parts[:-1] or "benches" in parts[:-1] or name == "tests.rs" or name.endswith("_tests.rs")


def main() -> int:
    root = subprocess.run(["git", "rev-parse", "--show-toplevel"], check=True, capture_output=True, text=True).stdout.strip()
    paths = subprocess.run(["git", "ls-files", "-z", "*.rs"], check=True, capture_output=True, cwd=root).stdout.split(b"\0")
    long, longest = [], (0, "")
    folders = dict.fromkeys(FOLDER_LIMITS, 0)
    for raw in paths:
        path = raw.decode()
        if not path or is_test(path) or not os.path.isfile(os.path.join(root, path)):
            continue
        n = non_test_lines(os.path.join(root, path))
        longest = max(longest, (n, path))
        for folder in folders:
            if path.startswith(folder + "/"):
                folders[folder] += n
        if n > LIMIT:
            long.append((n, path))
    for n, path in sorted(long, reverse=True):
        print(f"{path}: {n} non-test lines (limit {LIMIT}: split it by idea, docs/architecture.md \"One concept per module\")")
    over = [(f, n) for f, n in folders.items() if n > FOLDER_LIMITS[f]]
    for folder, n in over:
        print(f"{folder}: {n} non-test lines (ceiling {FOLDER_LIMITS[folder]}: the commands are thin; move what they compute into a library crate)")
    if long or over:
        return 1
    sums = ", ".join(f"{f} {n} of {FOLDER_LIMITS[f]}" for f, n in folders.items())
    print(f"source files: none over {LIMIT} non-test lines (longest {longest[1]}, {longest[0]}); {sums}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
