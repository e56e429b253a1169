"""examples/python/impedance_prototype.py: a law of one's own prototyped in Python
(`run_controller`) is the same law as its Rust port on the firmware
(examples/law-template, issue 70): the Rust law's run over iceoryx2 (its firmware
process `law-firmware`, `sil-host run --attach`) and the prototype end within a
hundredth of a millimetre of each other, and follow each other within 0.1 mm."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

import painleve
from conftest import REPO, sil_host

EXAMPLE = REPO / "examples" / "python" / "impedance_prototype.py"
SCENARIO = REPO / "examples" / "law-template" / "impedance.toml"


@pytest.fixture(scope="module")
def example():
    sys.path.insert(0, str(EXAMPLE.parent))
    spec = importlib.util.spec_from_file_location("impedance_prototype", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def law_firmware():
    exe = os.environ.get("PAINLEVE_LAW_FIRMWARE", str(REPO / "target" / "release" / "law-firmware"))
    if not os.path.isfile(exe):
        pytest.fail(f"{exe} is missing: cargo build --release -p law-template --bin law-firmware (scripts/test.sh builds it)")
    return exe


def test_the_python_prototype_is_the_rust_law(example, tmp_path):
    rig = f"py-law-{os.getpid()}"
    args = ["--scenario", str(SCENARIO), "--set", "timing.duration_s=2"]
    fw = subprocess.Popen([law_firmware(), "firmware", "--rig", rig, *args], stdout=subprocess.DEVNULL)
    try:
        out = tmp_path / "rust"
        run = [str(sil_host()), "run", "--attach", rig, *args, "--no-page", "--format", "mcap", "--out", str(out)]
        done = subprocess.run(run, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
    finally:
        assert fw.wait(timeout=60) == 0
    loaded = painleve.load(out)
    rust = loaded.trace
    scenario = painleve.Scenario.load(SCENARIO).set("timing.duration_s", 2.0)
    prototype = painleve.run_controller(example.Impedance(scenario), scenario)
    py = prototype.trace
    # Each result names the law that ran (issue 84: every law was "hybrid").
    assert loaded.law == "law `impedance` (d_n = 60, d_t = 90, k_n = 1000, k_t = 2000, the rest at their defaults)", loaded.law
    # The trace's /log says the same at its first period (the words of rig::scenario::Scenario::law_in_words).
    from test_mcap import log_lines

    assert log_lines(out / "trace.mcap")[0] == f"control law: {loaded.law}", log_lines(out / "trace.mcap")[:2]
    from test_mcap import run_metadata

    assert run_metadata(out / "trace.mcap") == {"law": loaded.law}, run_metadata(out / "trace.mcap")
    assert "(law `impedance` (" in repr(loaded), repr(loaded)
    assert prototype.law == "Python Impedance" and "(Python Impedance)" in repr(prototype), repr(prototype)
    z_rust, z_py = np.asarray(rust["z_t"], dtype=float), np.asarray(py["z_t"], dtype=float)
    assert len(z_rust) == len(z_py) == 2000
    assert abs(z_rust[-1] - z_py[-1]) < 1e-5, (z_rust[-1], z_py[-1])
    assert np.max(np.abs(z_rust - z_py)) < 1e-4, np.max(np.abs(z_rust - z_py))
    # Both slide on the belt at the end, pressing with about f_n* = 10 N.
    for t in (rust, py):
        assert abs(float(np.asarray(t["f_n"], dtype=float)[-1]) - 10.0) < 1.0
    # The velocities Sensed gives (no model-driven prediction) lift this law off.
    lifted = painleve.run_controller(example.Impedance(scenario, "sensed"), scenario).trace
    assert float(np.asarray(lifted["f_n"], dtype=float)[-1]) < 1.0
