#!/usr/bin/env python3
"""Starts a law of one's own: copies examples/law-template (the impedance law, a
`firmware::ControlLaw` with its firmware process, MCU images, tests and scenario)
to examples/NAME, renamed throughout: the package NAME, its crate `NAME` with
`-` as `_`, its binaries NAME-arm, NAME-pil and NAME-firmware (their files and
its `[package.metadata.painleve.law]` table). Every crate under examples/ is a
workspace member, and the house finds a law crate by that table (scripts/laws.py),
so the copy gets every gate (images, budgets, cycle estimate, import cycles, the
end-to-end runs over every link) without an edit outside its folder.

    python3 scripts/new-law.py NAME [--root DIR]

NAME: lower case letters, digits and `-`, starting with a letter, not a
package or folder that exists. Exits 2 with a message for a bad or taken name."""

import argparse
import os
import re
import shutil
import sys

TEMPLATE = "law-template"


def new_law(name: str, root: str) -> str:
    """Copies the template to examples/`name` under `root`; the new folder."""
    if not re.fullmatch(r"[a-z][a-z0-9]*(-[a-z0-9]+)*", name):
        raise ValueError(f"{name!r}: a law's name is lower case letters, digits and single `-`, starting with a letter (a Cargo package name)")
    if name in (TEMPLATE, "firmware", "shared", "rig", "plant", "drivers", "tables", "analyses", "experiments", "figures", "fuzz"):
        raise ValueError(f"{name!r} is a package of this workspace already")
    src, dst = os.path.join(root, "examples", TEMPLATE), os.path.join(root, "examples", name)
    if os.path.exists(dst):
        raise ValueError(f"{dst} exists: pick another name, or remove it")
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("target", "__pycache__"))
    crate = name.replace("-", "_")
    # Examples take the crate's name as a prefix: two packages' examples of one
    # name would overwrite each other in the target folder (cargo's "output
    # filename collision").
    examples = os.path.join(dst, "examples")
    stems = sorted(f[:-3] for f in os.listdir(examples) if f.endswith(".rs")) if os.path.isdir(examples) else []
    for stem in stems:
        os.rename(os.path.join(examples, f"{stem}.rs"), os.path.join(examples, f"{crate}_{stem}.rs"))
    renames = [(f"--example {stem}", f"--example {crate}_{stem}") for stem in stems] + [
        (f"examples/{stem}.rs", f"examples/{crate}_{stem}.rs") for stem in stems
    ] + [
        (TEMPLATE.replace("-", "_"), crate),
        (TEMPLATE, name),
        ("law-arm", f"{name}-arm"),
        ("law-pil", f"{name}-pil"),
        ("law-firmware", f"{name}-firmware"),
    ]
    for folder, _, files in os.walk(dst):
        for f in files:
            path = os.path.join(folder, f)
            if not f.endswith((".rs", ".toml", ".md")):
                continue
            with open(path, encoding="utf-8") as h:
                text = h.read()
            # The repository's test of the template keeps its name in the docs.
            text = text.replace("tests/e2e/law_template.rs", "\0")
            # Cargo's variables naming a binary (`CARGO_BIN_EXE_law-firmware`).
            text = re.sub(r"CARGO_BIN_EXE_law-(arm|pil|firmware)\b", rf"CARGO_BIN_EXE_{name}-\1", text)
            for old, new in renames:
                text = re.sub(rf"(?<![\w-]){re.escape(old)}(?![\w])", new, text)
            text = text.replace("\0", "tests/e2e/law_template.rs")
            with open(path, "w", encoding="utf-8") as h:
                h.write(text)
    bins = os.path.join(dst, "src", "bin")
    for kind in ("arm", "pil", "firmware"):
        os.rename(os.path.join(bins, f"law-{kind}.rs"), os.path.join(bins, f"{name}-{kind}.rs"))
    return dst


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("name")
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    args = ap.parse_args()
    try:
        dst = new_law(args.name, os.path.abspath(args.root))
    except ValueError as e:
        print(f"new-law: {e}", file=sys.stderr)
        return 2
    rel = os.path.relpath(dst)
    print(f"new-law: {rel}, package {args.name}, binaries {args.name}-arm, {args.name}-pil, {args.name}-firmware")
    print(f"  the law: {rel}/src/lib.rs (its name, parameters and step); its scenario: {rel}/impedance.toml")
    print(f"  tests:   cargo test --release -p {args.name}")
    print(f"  PIL:     cargo build -p {args.name} --profile qemu --target thumbv7em-none-eabihf --no-default-features --features qemu --bin {args.name}-pil")
    print(f"  flash:   cargo run -p {args.name} --profile mcu --target thumbv7em-none-eabihf --bin {args.name}-arm")
    print("  the gates find it: python3 scripts/laws.py")
    return 0


if __name__ == "__main__":
    sys.exit(main())
