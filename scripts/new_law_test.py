#!/usr/bin/env python3
"""Tests scripts/new-law.py and the house's discovery of law crates (issue 83):
a copy of the template made with the one command is a workspace member that
scripts/laws.py lists with its renamed binaries and scenario; scripts/budgets.py
--all holds its images to the budget (asking for their build, by its package,
while they are not built); the import-cycle gate reads its sources; clippy
lints it (in scripts/test.sh, as it builds), and its host and MCU builds build; nothing of the template's names is left in its
sources. A bad or taken name is refused (exit 2). The copy (examples/NAME in
this repository, made and removed here) and Cargo.lock are restored whatever
happens. Run by scripts/test.sh after its test build (which it reuses)."""

import json
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, HERE)
import laws  # noqa: E402

NAME = f"gate-law-{os.getpid()}"


def run(*argv: str, ok=(0,)) -> subprocess.CompletedProcess:
    p = subprocess.run(list(argv), cwd=ROOT, capture_output=True, text=True)
    if p.returncode not in ok:
        raise AssertionError(f"{' '.join(argv)} exited {p.returncode}:\n{p.stdout}{p.stderr}")
    return p


def main() -> int:
    lock = os.path.join(ROOT, "Cargo.lock")
    with open(lock, "rb") as f:
        lock_bytes = f.read()
    lock_stat = os.stat(lock)
    folder = os.path.join(ROOT, "examples", NAME)
    try:
        out = run(sys.executable, os.path.join(HERE, "new-law.py"), NAME).stdout
        assert f"binaries {NAME}-arm, {NAME}-pil, {NAME}-firmware" in out, out
        # The gates' discovery lists it, renamed, beside the template.
        found = {l.package: l for l in laws.laws(ROOT)}
        assert "law-template" in found and NAME in found, found
        law = found[NAME]
        assert (law.dir, law.arm, law.pil, law.firmware) == (f"examples/{NAME}", f"{NAME}-arm", f"{NAME}-pil", f"{NAME}-firmware"), law
        assert law.scenario == f"examples/{NAME}/impedance.toml", law
        # No name of the template's left in its sources and manifest.
        for dirpath, _, files in os.walk(folder):
            for f in files:
                if f.endswith((".rs", ".toml")):
                    text = open(os.path.join(dirpath, f), encoding="utf-8").read()
                    text = text.replace("tests/e2e/law_template.rs", "")
                    for old in ("law-template", "law_template", "law-arm", "law-pil", "law-firmware"):
                        assert not re.search(rf"(?<![\w-]){old}(?![\w])", text), f"{f}: {old}"
        # The budgets ask for its four images by its package while they are not built.
        p = run(sys.executable, os.path.join(HERE, "budgets.py"), "--all", "--json", ok=(0, 1))
        missing = json.loads(p.stdout)["missing"]
        for key in (f"mcu/{NAME}-arm", f"mcu/{NAME}-pil", f"qemu/{NAME}-arm", f"qemu/{NAME}-pil"):
            assert key in missing and f"-p {NAME} " in missing[key], (key, missing)
        # It builds: its crate, tests and examples linted as the workspace is, and its
        # MCU images checked for the target. Under scripts/test.sh, which lints as it
        # builds (RUSTC_WORKSPACE_WRAPPER=scripts/lint-rustc.sh), that is the script's
        # own test build, the rest of it fresh; run alone, `cargo clippy`.
        if os.environ.get("RUSTC_WORKSPACE_WRAPPER", "").endswith("lint-rustc.sh"):
            run("cargo", "test", "--workspace", "--release", "--features", "sil-host/full", "--no-run")
        else:
            run("cargo", "clippy", "--release", "--workspace", "--all-targets", "--features", "sil-host/full", "--", "-D", "warnings")
        run("cargo", "check", "-p", NAME, "--profile", "qemu", "--target", "thumbv7em-none-eabihf", "--no-default-features", "--features", "qemu", "--bin", f"{NAME}-arm", "--bin", f"{NAME}-pil")
        # The import-cycle gate reads its sources.
        out = run(sys.executable, os.path.join(HERE, "import_cycles.py"), law.src).stdout
        assert "import cycles between files: 0" in out and "unresolved paths: 0" in out, out
        # A bad name and a taken one are refused.
        for bad in ("Bad_Name", NAME):
            assert run(sys.executable, os.path.join(HERE, "new-law.py"), bad, ok=(2,)).returncode == 2
    finally:
        shutil.rmtree(folder, ignore_errors=True)
        with open(lock, "rb") as f:
            if f.read() != lock_bytes:
                with open(lock, "wb") as g:
                    g.write(lock_bytes)
                # Its time too, so that nothing that watches it sees an edit.
                os.utime(lock, ns=(lock_stat.st_atime_ns, lock_stat.st_mtime_ns))
    assert not os.path.exists(folder)
    print(f"new-law: a copy of the template ({NAME}) is found by scripts/laws.py, scripts/budgets.py and the import-cycle gate, and builds (clippy; its MCU images checked)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
