#!/usr/bin/env python3
"""The laws of one's own the house finds (issue 83): every workspace member whose
Cargo.toml has a `[package.metadata.painleve.law]` table (examples/law-template's
says what each key means), read through `cargo metadata --no-deps`. The gates
(scripts/test.sh, scripts/budgets.py, tests/e2e/common.rs) run on each law this
lists, so a copy made with scripts/new-law.py gets them without an edit outside
its folder.

    python3 scripts/laws.py            one line per law: package, folder, arm, pil, firmware, scenario
    python3 scripts/laws.py --json     the same as a JSON list
    python3 scripts/laws.py --field F  one value of field F per law (package, dir, src, arm, pil, firmware, scenario)

Exits 1 with a message naming the crate when a law's table lacks a key or names
a binary the crate does not have."""

import argparse
import json
import os
import subprocess
import sys
from dataclasses import asdict, dataclass
from typing import List, Optional

KEYS = ("arm", "pil", "firmware", "scenario")


@dataclass(frozen=True)
class Law:
    """A law crate: its package, its folder (relative to the workspace root), the
    binaries of its MCU images and firmware process, its scenario (relative to
    the workspace root)."""

    package: str
    dir: str
    arm: str
    pil: str
    firmware: str
    scenario: str

    @property
    def src(self) -> str:
        return f"{self.dir}/src"


class LawError(Exception):
    pass


def laws(root: Optional[str] = None) -> List[Law]:
    """The workspace's law crates, in the workspace's member order."""
    root = root or subprocess.run(["git", "rev-parse", "--show-toplevel"], check=True, capture_output=True, text=True).stdout.strip()
    meta = json.loads(
        subprocess.run(
            ["cargo", "metadata", "--no-deps", "--format-version", "1", "--offline", "--manifest-path", os.path.join(root, "Cargo.toml")],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    )
    found = []
    for p in meta["packages"]:
        table = ((p.get("metadata") or {}).get("painleve") or {}).get("law")
        if table is None:
            continue
        name = p["name"]
        missing = [k for k in KEYS if not isinstance(table.get(k), str)]
        if missing:
            raise LawError(f"{name}: [package.metadata.painleve.law] lacks {', '.join(missing)} (examples/law-template/Cargo.toml says each)")
        bins = {t["name"] for t in p["targets"] if "bin" in t["kind"]}
        for k in ("arm", "pil", "firmware"):
            if table[k] not in bins:
                raise LawError(f"{name}: [package.metadata.painleve.law] {k} = \"{table[k]}\" is none of its binaries ({', '.join(sorted(bins))})")
        folder = os.path.relpath(os.path.dirname(p["manifest_path"]), root)
        scenario = os.path.join(folder, table["scenario"])
        if not os.path.isfile(os.path.join(root, scenario)):
            raise LawError(f"{name}: [package.metadata.painleve.law] scenario = \"{table['scenario']}\": no such file {scenario}")
        found.append(Law(name, folder, table["arm"], table["pil"], table["firmware"], scenario))
    return found


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--field", choices=("package", "dir", "src") + KEYS)
    ap.add_argument("--root", help="the workspace's root (default: this repository's)")
    args = ap.parse_args()
    try:
        found = laws(args.root)
    except LawError as e:
        print(f"laws: {e}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps([asdict(l) for l in found], indent=1))
    elif args.field:
        for l in found:
            print(getattr(l, args.field))
    else:
        for l in found:
            print(l.package, l.dir, l.arm, l.pil, l.firmware, l.scenario)
    return 0


if __name__ == "__main__":
    sys.exit(main())
