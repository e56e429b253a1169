"""The objects (issue 42, item 3; docs/python.md "Objects"): a Scenario set key
by key and round-tripped through TOML, a Plant stepped from Python, the Firmware
stepped frame by frame, and a Python controller closing the loop through the
rig's plant side."""

from __future__ import annotations

import copy
import math
import signal
import threading

import numpy as np
import pytest

import painleve
from painleve import Firmware, PainleveError, Plant, Scenario


def painleve_repo():
    from pathlib import Path

    return Path(__file__).resolve().parents[2]


def short(duration: float = 0.5) -> Scenario:
    return Scenario.default().set("timing.duration_s", duration)


# --- Scenario ---------------------------------------------------------------


def test_scenario_set_validate_and_toml_round_trip() -> None:
    s = Scenario.default()
    assert s["plant.mu"] == 0.6 and s.get("timing.rate_hz") == 1000.0
    assert s.set("plant.mu", 0.45) is s  # chaining
    s.set("controller.pid.kp", [150, 0]).set("controller.kind", "pid")
    assert s["plant.mu"] == 0.45 and s["controller.pid.kp"] == [150.0, 0.0]
    s.validate()
    back = Scenario.from_toml(s.to_toml())
    assert back == s and back is not s
    assert back.to_dict()["plant"]["mu"] == 0.45
    assert Scenario(s.to_toml()) == s and Scenario() == Scenario.default()
    assert copy.deepcopy(s) == s
    s.set("sensors.seed", np.int64(3)).set("plant.e_n", np.float64(0.25))
    assert (s["sensors.seed"], s["plant.e_n"]) == (3, 0.25)
    from_file = Scenario(painleve_repo() / "scenarios" / "default.toml")
    assert from_file == Scenario.default() == Scenario(str(painleve_repo() / "scenarios" / "default.toml"))
    both = Scenario.default().update({"plant.mu": 0.5, "timing.duration_s": 1.0})
    assert (both["plant.mu"], both["timing.duration_s"], both.periods) == (0.5, 1.0, 1000)


def test_scenario_bad_keys_and_values_raise_painleve_error() -> None:
    s = Scenario.default()
    with pytest.raises(PainleveError, match=r"plant\.mu.*out of range") as e:
        s.set("plant.mu", -1.0)
    assert e.value.exit_code == 2
    assert s["plant.mu"] == 0.6, "a refused change leaves the scenario as it was"
    with pytest.raises(PainleveError, match="plant.nope"):
        s.set("plant.nope", 1.0)
    with pytest.raises(PainleveError, match="plant.mu"):
        s.set("plant.mu", "fast")
    with pytest.raises(TypeError, match="plant.mu"):
        s.set("plant.mu", object())
    with pytest.raises(PainleveError):
        Scenario.from_toml("this is not toml")
    with pytest.raises(KeyError):
        s["plant.nope"]


# --- Plant --------------------------------------------------------------------


def test_plant_equals_simulate_sample_by_sample() -> None:
    """``Plant()`` is ``simulate``'s plant: advanced to the same sample times it
    gives the same trace to the integrator's tolerance (``simulate`` reads its
    samples from the dense output of steps the tolerances set, the plant here stops
    at each sample: two step sequences of one solution), the same modes, and the
    same state at ``t = 0`` to the bit."""
    ref = painleve.simulate(duration=0.3, progress=False).trace
    plant = Plant()
    assert plant.mode == str(ref["mode"][0]) and plant.time == 0.0
    assert np.array_equal(plant.state, [ref[c][0] for c in ("theta1", "theta1_dot", "theta2", "theta2_dot")])
    worst = 0.0
    for k in range(1, ref.nrows):
        step = plant.advance_to(k * 1e-3)
        assert step.t == ref["t"][k]
        want = np.array([ref[c][k] for c in ("theta1", "theta1_dot", "theta2", "theta2_dot")])
        worst = max(worst, float(np.max(np.abs(step.state - want) / (1e-11 + 1e-9 * np.abs(want)))))
        assert step.mode == str(ref["mode"][k])
    # In tolerances (1e-11 + 1e-9 |x|): the accuracy contract's departure is 1000.
    assert worst < 100, worst
    assert plant.counters["lift_offs"] >= 1 and plant.validity["energy_gains"] == 0
    c = plant.counters  # as simulate's summary.json writes them (issue 67)
    assert c["lift_offs"] == c["lift_offs_from_contact"] + c["bounces"]


def test_plant_conserves_energy_in_flight_without_damping() -> None:
    plant = Plant(state=[0.8, 0.0, 0.2, 0.0], sigma=0.0)
    assert plant.mode == "flight" and plant.state.shape == (4,) and plant.tip.shape == (2,)
    e0 = plant.energy
    for _ in range(100):
        step = plant.advance(1e-3, (0.0, 0.0))
        assert step.mode == "flight" and not step.events
        assert np.array_equal(step.force, [0.0, 0.0])
    assert plant.time == pytest.approx(0.1)
    assert abs(plant.energy - e0) < 1e-8 * max(1.0, abs(e0))
    # With damping, energy decreases, and the ledger says by how much.
    damped = Plant(state=[0.8, 0.0, 0.2, 0.0])
    damped.advance(0.1)
    assert damped.energy < e0
    led = damped.ledger
    assert led["damping_j"] < 0 and led["belt_j"] == led["slip_j"] == led["motors_j"] == 0.0
    assert damped.energy - e0 == pytest.approx(led["damping_j"], abs=1e-9)
    assert led["energy_change_j"] == pytest.approx(damped.energy - e0, abs=1e-12) and led["violations"] == 0


def test_plant_advance_in_two_halves_equals_one_advance() -> None:
    a, b = Plant(mu=0.3), Plant(mu=0.3)
    a.advance(0.02, (0.1, -0.05))
    a.advance(0.02, (0.1, -0.05))
    b.advance(0.04, (0.1, -0.05))
    assert a.time == pytest.approx(b.time)
    assert np.allclose(a.state, b.state, rtol=1e-6, atol=1e-8)
    assert a.mode == b.mode


def test_plant_events_copy_reset_and_bad_input() -> None:
    plant = Plant()
    kinds = [e["kind"] for e in plant.startup_events]
    assert "impact_without_collision" in kinds  # x0a is inconsistent: the Painlevé paradox
    twin = plant.copy()
    step = plant.advance(0.5)
    assert all(0.0 <= e["t"] <= 0.5 for e in step.events)
    assert twin.time == 0.0, "a copy has its own state"
    plant.reset()
    assert plant.time == 0.0 and np.array_equal(plant.state, twin.state)
    for bad in (lambda: plant.advance(-1e-3), lambda: plant.advance(float("nan")), lambda: plant.advance(1e-3, (float("nan"), 0.0))):
        with pytest.raises(PainleveError) as e:
            bad()
        assert e.value.exit_code == 2
    with pytest.raises(TypeError):
        plant.advance(1e-3, "no")
    with pytest.raises(TypeError, match="speed"):
        Plant(speed=1.0)
    with pytest.raises(PainleveError, match="mu"):
        Plant(mu=-1.0)
    with pytest.raises(PainleveError):
        Plant(state=[0.0, 0.0, 0.0, 0.0])  # straight down, through the belt
    p = Plant(short(), mu=0.3, v_belt=-0.2)
    assert p.params["mu"] == 0.3 and p.params["v_belt"] == -0.2 and p.scenario["plant.x0"] == "d"


# --- Firmware -----------------------------------------------------------------


def test_firmware_step_gives_the_in_process_runs_first_command() -> None:
    """Without load-cell noise the frame of period 0 is the encoded true state:
    the firmware stepped on it answers what ``painleve.run``'s firmware did."""
    s = short(0.05).set("sensors.load_noise_n", 0.0)
    ref = painleve.run(s.to_dict(), progress=False).trace
    fw = Firmware(s)
    for k in range(3):
        frame = {c: float(ref[c][k]) for c in ("theta1", "theta2", "f_t", "f_n")}
        cmd = fw.step(frame)
        assert cmd.seq == k
        assert (cmd.u1, cmd.u2) == (ref["u1_cmd"][k], ref["u2_cmd"][k]), k
        assert cmd.status == ref["status"][k]
        assert cmd.torques.shape == (2,) and tuple(cmd) == (cmd.u1, cmd.u2)
    assert fw.k == 3 and fw.safe_state is None
    with pytest.raises(KeyError, match="theta2"):
        fw.step({"theta1": 0.0})
    with pytest.raises(TypeError):
        fw.step([1, 2, 3])


# --- The closed loop with a Python controller ---------------------------------


def test_a_python_controller_delegating_to_the_firmware_reproduces_run() -> None:
    """The controller's path is the firmware's: a callable that hands the frame
    to ``Firmware.step`` gives ``painleve.run``'s trace (its torques are the
    firmware's decoded codes, applied unchanged)."""
    s = short(0.5)
    ref = painleve.run(s.to_dict(), progress=False).trace
    fw = Firmware(s)
    got = painleve.run_controller(lambda t, sensed: fw.step(sensed), s).trace
    assert got.nrows == ref.nrows == 500
    for c in ("t", "theta1", "theta1_dot", "theta2", "theta2_dot", "z_t", "z_n", "f_t", "f_n", "u1_cmd", "u2_cmd", "u1_applied"):
        assert np.array_equal(got[c], ref[c]), c
    assert list(got["mode"]) == list(ref["mode"])


def test_a_pd_force_controller_in_ten_lines_holds_the_tip_on_the_belt() -> None:
    """The researcher's use: a PD law on theta1 with a feed-forward pressing the
    tip on the belt; the tip stays in contact and slides."""
    seen = []

    def pd(t: float, y: painleve.Sensed) -> tuple:
        seen.append((t, y.k))
        u1 = -2.0 * (y.theta1 - (-0.2)) - 0.1 * y.theta1_dot - 0.05 * (y.f_n - 5.0)
        return u1, 0.0

    r = painleve.run_controller(pd, short(0.5))
    tr = r.trace
    assert tr.nrows == 500 and r.failure is None and r.valid
    assert seen[0] == (0.0, 0) and seen[-1][1] == 499 and seen[1][0] == pytest.approx(1e-3)
    assert set(tr["mode"][50:]) <= {"sliding", "sticking"}
    assert not tr["lift_off_true"].any()
    assert np.all(tr["f_n"][50:] > 0.0)
    assert r.summary["transport"] == "python"
    # The torque takes effect at t_k + delta and is applied as returned.
    assert tr["u1_applied"][1] == tr["u1_cmd"][0]


def test_zero_torque_controller_sees_quantised_noisy_sensors() -> None:
    frames = []

    def zero(t, y):
        frames.append((y.theta1, y.theta2, y.f_n, y.valid, y.frame["theta1_count"]))
        return [0.0, 0.0]

    tr = painleve.run_controller(zero, short(0.2)).trace
    assert tr.nrows == 200 and np.all(tr["u1_applied"] == 0.0)
    lsb = 2 * math.pi / 2**14
    for (theta1, _, f_n, valid, count), true_theta1 in zip(frames, tr["theta1"]):
        assert valid and abs(theta1 - true_theta1) <= 0.5 * lsb + 1e-6
        assert theta1 == pytest.approx(np.float32(count * lsb) if count < 2**13 else np.float32(count * lsb) - 2 * math.pi, abs=1e-6)
    f_err = np.array([f for _, _, f, _, _ in frames]) - tr["f_n"]
    assert 0.0 < np.std(f_err) < 0.1, "load-cell noise (0.02 N rms) and quantisation"


def test_sensor_faults_reach_the_controller() -> None:
    """The scenario's sensor faults act on the frames the controller sees (the
    rig's `SensorFaults`): a NaN load cell at period 10 gives an invalid frame."""
    seen = {}

    def record(t, y):
        seen[y.k] = (y.valid, y.fault, y.f_n, y.theta1)
        return 0.0, 0.0

    s = short(0.05).set("faults", [{"kind": "nan_sensor", "at_s": 0.01, "signal": "f_n"}])
    painleve.run_controller(record, s)
    assert seen[9][0] and seen[11][0]
    valid, fault, f_n, theta1 = seen[10]
    assert not valid and "invalid" in fault and math.isnan(f_n) and math.isnan(theta1)


def test_controller_errors_propagate_and_bad_returns_name_the_period() -> None:
    class Boom(RuntimeError):
        pass

    def raises(t, y):
        if y.k == 7:
            raise Boom("at seven")
        return 0.0, 0.0

    with pytest.raises(Boom, match="at seven") as boom:
        painleve.run_controller(raises, short(0.1))
    # Issue 52, 8: the exception, kept as raised, says when it was raised.
    assert boom.value.__notes__ == ["raised by the controller at period 7 (t = 0.007 s)"]
    with pytest.raises(TypeError, match=r"period 3 \(t = 0.003 s\)"):
        painleve.run_controller(lambda t, y: (0.0, 0.0) if y.k < 3 else "garbage", short(0.1))
    with pytest.raises(TypeError, match="period 0"):
        painleve.run_controller(lambda t, y: (1.0, 2.0, 3.0), short(0.1))
    with pytest.raises(TypeError, match="period 0"):
        painleve.run_controller(lambda t, y: None, short(0.1))
    with pytest.raises(ValueError, match="period 2"):
        painleve.run_controller(lambda t, y: (float("nan") if y.k == 2 else 0.0, 0.0), short(0.1))
    with pytest.raises(TypeError, match="callable"):
        painleve.run_controller(42, short(0.1))  # type: ignore[arg-type]
    with pytest.raises(PainleveError) as e:
        painleve.run_controller(lambda t, y: (0.0, 0.0), short(0.1), duration=-1.0)
    assert e.value.exit_code == 2
    arr = painleve.run_controller(lambda t, y: np.zeros(2), short(0.05))
    assert arr.trace.nrows == 50
    # A partial scenario dict is merged onto the default; a bad key is named.
    merged = painleve.run_controller(lambda t, y: (0.0, 0.0), {"timing": {"duration_s": 0.03}, "plant": {"mu": 0.5}})
    assert merged.trace.nrows == 30 and merged.extras["scenario"]["plant"]["mu"] == 0.5
    with pytest.raises(PainleveError, match="plant.nope"):
        painleve.run_controller(lambda t, y: (0.0, 0.0), {"plant": {"nope": 1}})


def test_ctrl_c_stops_the_loop() -> None:
    # Driven by the event, not a race: from period 20 each call waits until the
    # signal has been raised. The interrupt then comes out of the loop's own check
    # or out of the wait inside the callable; either way, KeyboardInterrupt.
    raised = threading.Event()

    def ctrl_c():
        signal.raise_signal(signal.SIGINT)
        raised.set()

    def slow(t, y):
        if y.k == 20:
            threading.Timer(0.01, ctrl_c).start()
        if y.k >= 20:
            assert raised.wait(30.0), "the timer never fired"
        return 0.0, 0.0

    # A process started in the background by a non-interactive shell (CI's) inherits
    # SIGINT ignored, and Python then installs no KeyboardInterrupt handler: the test
    # gives this process Python's own for its duration (another test file that did so
    # in the same process hid this until the files ran in separate workers).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            painleve.run_controller(slow, short(60.0))
    finally:
        signal.signal(signal.SIGINT, previous)
