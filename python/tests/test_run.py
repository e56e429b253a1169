"""`painleve.run` (the in-process SIL run) against `sil-host run --in-process`:
the same trace.csv and summary.json, for the default scenario, a scenario
file, a scenario dict and overrides."""

import pytest

import painleve
from conftest import REPO, assert_docs_equal, assert_tables_equal, cli, assert_raises_like_cli


def compare(mine, out):
    theirs = painleve.load(out)
    assert theirs.command == "run"
    assert_tables_equal(mine["trace"], theirs["trace"])
    assert_docs_equal(mine.summary, theirs.summary)
    assert mine.validity == theirs.validity == mine.summary["validity"]


def test_default_scenario(out):
    mine = painleve.run(duration=3.0, progress=False)
    cli("run", ["--in-process", "--duration", "3"], out)
    compare(mine, out)
    assert mine.trace.nrows == 3000
    assert mine.summary["lift_offs"] == 0 and mine.failure is None


def test_scenario_file_with_flags_and_overrides(out):
    path = REPO / "scenarios" / "pid-x0u.toml"
    mine = painleve.run(path, duration=2.5, seed=7, set={"plant.m": 0.24, "controller.pid.kp": [150, 0]}, progress=False)
    cli(
        "run",
        ["--in-process", "--scenario", str(path), "--duration", "2.5", "--seed", "7", "--set", "plant.m=0.24", "--set", "controller.pid.kp=[150,0]"],
        out,
    )
    compare(mine, out)
    assert mine.summary["controller"] == "pid"


def test_scenario_dict_equals_its_file(tmp_path, out):
    scenario = painleve.default_scenario()
    scenario["plant"]["mu"] = 0.5
    scenario["timing"]["duration_s"] = 2.0
    path = tmp_path / "s.toml"
    path.write_text(painleve.scenario_toml(scenario))
    from_dict = painleve.run(scenario, progress=False)
    cli("run", ["--in-process", "--scenario", str(path)], out)
    compare(from_dict, out)
    assert from_dict.extras["scenario"]["plant"]["mu"] == 0.5


def test_overrides_as_a_list_equal_a_dict():
    a = painleve.run(duration=1.0, set=["controller.target_z_t=0.05"], progress=False)
    b = painleve.run(duration=1.0, set={"controller.target_z_t": 0.05}, progress=False)
    assert_tables_equal(a["trace"], b["trace"])


@pytest.mark.parametrize(
    "kwargs,argv",
    [
        ({"duration": -1.0}, ["--duration", "-1"]),
        ({"set": {"plant.mu": -0.5}}, ["--set", "plant.mu=-0.5"]),
        ({"set": ["no.such.key=1"]}, ["--set", "no.such.key=1"]),
        ({"x0": "d", "set": {"plant.x0": "u"}}, ["--x0", "d", "--set", "plant.x0=u"]),
        ({"controller": "lqr"}, ["--controller", "lqr"]),
        ({"scenario": "scenarios/missing.toml"}, ["--scenario", "scenarios/missing.toml"]),
    ],
)
def test_bad_input_raises_the_cli_message(kwargs, argv, monkeypatch):
    monkeypatch.chdir(REPO)
    assert_raises_like_cli(lambda: painleve.run(progress=False, **kwargs), "run", ["--in-process", *argv])


def test_a_result_names_the_law_that_ran():
    # Issue 84: the paper's laws by the firmware's controller, a Python callable by
    # its name, an open-loop result none (a law of one's own: test_impedance_prototype.py).
    for controller in ("pid", "hybrid"):
        r = painleve.run(controller=controller, duration=0.02, progress=False)
        assert r.law == controller and repr(r).startswith(f"<painleve.Result run ({controller}): "), repr(r)

    def hold_still(t, sensed):
        return (0.0, 0.0)

    r = painleve.run_controller(hold_still, duration=0.02)
    assert r.law == "Python test_a_result_names_the_law_that_ran.<locals>.hold_still", r.law
    s = painleve.simulate(duration=0.01, progress=False)
    assert s.law is None and repr(s).startswith("<painleve.Result simulate: "), repr(s)
