#!/usr/bin/env python3
"""The architecture invariants of docs/architecture.md ("Architecture invariants"),
checked on the dependency graph cargo resolves (`cargo tree -e normal`, each package
built alone with its default features): what each layer may not know. Prints one
line per invariant and exits 1 if any is broken, naming the package and the crate
that breaks it. Usage: scripts/invariants.py (from the workspace root; no build).
"""
import subprocess
import sys

# Our host crates: what the MCU crates may never depend on.
HOST = {"plant", "tables", "rig", "analyses", "experiments", "figures", "board-description", "board-twin",
        "board-emulator", "board-link", "arm-view", "sil-host", "painleve-py", "painleve-fuzz"}
# Crates that need an operating system or belong to a front: none of them in the MCU crates.
HOST_ONLY = {"std", "clap", "serde_json", "tokio", "iceoryx2", "plotters", "rayon", "foxglove", "arrow-array", "mcap"}
# The board's crates: none of them under what only simulates.
BOARD = {"board-twin", "board-emulator", "board-link", "rsemu"}
MCU_TARGET = "thumbv7em-none-eabihf"


def deps(package, target=None, features=None):
    """The names of the crates `package` builds with (itself excluded), as `cargo tree`
    resolves its normal dependencies with its default features, or with `features`
    ("none" for `--no-default-features`, else a feature list), for `target` if given."""
    cmd = ["cargo", "tree", "-p", package, "-e", "normal", "--prefix", "none", "--format", "{p}"]
    if target:
        cmd += ["--target", target]
    if features == "none":
        cmd += ["--no-default-features"]
    elif features:
        cmd += ["--features", features]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"cargo tree -p {package} failed:\n{out.stderr}")
    names = {line.split()[0] for line in out.stdout.splitlines() if line.strip()}
    names.discard(package)
    return names


def main():
    broken = 0

    def check(name, packages, forbidden, target=None, features=None):
        nonlocal broken
        bad = []
        for p in packages:
            hit = sorted(deps(p, target, features) & forbidden)
            if hit:
                bad.append(f"{p} builds {', '.join(hit)}")
        print(("ok     " if not bad else "BROKEN ") + name + ("" if not bad else ": " + "; ".join(bad)))
        broken += bool(bad)

    # The checks can fail: the command line does build clap and the emulator, and the
    # firmware nalgebra, so an empty or misread graph cannot pass them all.
    probe = deps("sil-host", features="full")
    if not ({"clap", "rsemu", "board-link", "tokio", "arrow-csv"} <= probe and "nalgebra" in deps("firmware", MCU_TARGET)):
        sys.exit("scripts/invariants.py: cargo tree's graph was not read (sil-host without clap or rsemu?)")
    mcu = ["shared", "firmware", "drivers", "arm-app"]
    check("the firmware knows no host types: shared, firmware, drivers, arm-app build none of our host crates "
          "and nothing that needs an operating system, for the MCU", mcu, HOST | HOST_ONLY, MCU_TARGET)
    check("only the fronts know clap: no library of the workspace builds it with its default features",
          ["shared", "firmware", "drivers", "arm-app", "plant", "tables", "rig", "analyses", "experiments", "figures",
           "board-description", "board-twin", "board-emulator", "board-link", "arm-view"], {"clap"})
    check("what only simulates builds no board: rig, analyses, experiments, figures and the Python package build "
          "neither the board twin nor the emulator", ["rig", "analyses", "experiments", "figures", "painleve-py"], BOARD)
    check("figures knows no command: it builds no front, no board link and no command line",
          ["figures"], {"sil-host", "painleve-py", "board-link", "arm-view", "clap"})
    check("figures sits below experiments: it draws rows whoever made them, and builds neither the experiments "
          "nor the analyses", ["figures"], {"experiments", "analyses"})
    check("the Python package never depends on the command line", ["painleve-py"], {"sil-host"})
    # The lean build (sil-host/Cargo.toml `[features]`): each optional part stays behind its feature.
    lean = {"rsemu", "board-link", "board-twin", "board-emulator", "tokio", "foxglove", "arm-view", "arrow-array",
            "arrow-csv", "arrow-cast", "mcap", "zstd-sys", "svg2pdf"}
    check("the lean command line: sil-host --no-default-features builds no board, async runtime, Arrow, MCAP or PDF "
          "writer", ["sil-host"], lean, features="none")
    check("the default command line adds the PDF writer alone", ["sil-host"], lean - {"svg2pdf"})
    print(f"architecture invariants broken: {broken}")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
