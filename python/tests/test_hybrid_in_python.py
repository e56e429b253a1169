"""examples/python/hybrid_in_python.py: the paper's hybrid law (eqs. 9 to 11) written in
Python over `painleve.Model`, run by `run_controller`, ends within 1 mm of the
firmware's run (issue 55), from both of the paper's initial conditions."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import painleve
from conftest import REPO

EXAMPLE = REPO / "examples" / "python" / "hybrid_in_python.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("hybrid_in_python", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("scenario", ["default.toml", "hybrid-x0u.toml"])
def test_the_python_law_ends_within_a_millimetre_of_the_firmware(example, scenario):
    s = painleve.Scenario.load(REPO / "scenarios" / scenario)
    c = example.compare(s)
    fw, py = c["firmware"].trace, c["python"].trace
    assert fw.nrows == py.nrows == s.periods == 10_000
    # The whole z_t path, and its end, within 1 mm (measured: 0.09 and 0.20 mm at most,
    # a few micrometres at the end).
    assert c["max_dz"] < 1e-3, f"max |dz_t| = {c['max_dz'] * 1e3:.3f} mm at t = {c['t_max_dz']} s"
    assert c["final_dz"] < 1e-3
    # Both reach the target, hold the tip on the belt, and never lift off.
    assert abs(py["z_t"][-1] - s["controller.target_z_t"]) < 1e-3
    assert c["python"].summary["lift_offs"] == c["firmware"].summary["lift_offs"] == 0
    assert c["law"].safe_at is None
    # The same law, not merely the same outcome: over the first periods (before the
    # f32 firmware and the float64 port round one torque to different 12-bit codes)
    # the applied torques are the firmware's, code for code (row k holds the torque
    # applied at t_k: period k-1's command; row 0 is the initial zero).
    n = 11
    assert np.array_equal(py["u1_applied"][:n], fw["u1_applied"][:n]), (py["u1_applied"][:n], fw["u1_applied"][:n])
    assert np.array_equal(py["u2_applied"][:n], fw["u2_applied"][:n])
    assert np.all(fw["u1_applied"][1:n] != 0) and np.all(fw["u2_applied"][1:n] != 0)


def test_the_script_prints_the_comparison_and_fails_above_the_bound(example, capsys):
    assert example.main([]) == 0
    out = capsys.readouterr().out
    assert "max |dz_t| = " in out and "final |dz_t| = " in out and "within 1.0 mm" in out
    # The bound can fail: without the firmware's model-driven velocity prediction
    # (Sensed.theta*_dot, the 40 Hz tracker alone, about 8 ms of lag) K'_D = 900/s
    # drives the arm straight, and the script says so and exits 1.
    assert example.main(["--observer", "sensed"]) == 1
    captured = capsys.readouterr()
    assert "J singular" in captured.out
    assert "more than 1.0 mm" in captured.err


@pytest.mark.parametrize("seed", range(4))
def test_the_bound_holds_over_random_hybrid_scenarios(example, seed):
    # The 1 mm bound over scenarios of the same kind as the paper's (hybrid law, sliding
    # on the belt), not only the two named ones: target, force reference, friction and
    # belt speed drawn at random (seeded), from either initial condition, 3 s each.
    rng = np.random.default_rng(seed)
    mu = float(rng.uniform(0.3, 0.6))
    s = painleve.Scenario.load(REPO / "scenarios" / ("default.toml" if seed % 2 == 0 else "hybrid-x0u.toml"))
    s.update(
        {
            "controller.target_z_t": float(rng.uniform(0.06, 0.12)),
            "controller.f_n_ref": float(rng.uniform(6.0, 14.0)),
            "plant.mu": mu,
            "controller.mu_hat": mu,
            "plant.v_belt": float(rng.uniform(-0.5, -0.3)),
            "timing.duration_s": 3.0,
        }
    )
    c = example.compare(s)
    if c["firmware"].summary["lift_offs"] or c["law"].safe_at is not None:
        pytest.skip(f"seed {seed}: the firmware's own run lifts off or stops: not the sliding case the bound is for")
    assert c["max_dz"] < 1e-3, f"seed {seed}: max |dz_t| = {c['max_dz'] * 1e3:.3f} mm at t = {c['t_max_dz']} s"
    assert c["final_dz"] < 1e-3
