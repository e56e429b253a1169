"""`painleve.simulate` against `sil-host simulate`: the same trace, events and
summary for the same arguments; bad input raises with the CLI's message."""

import pytest

import painleve
from conftest import assert_docs_equal, assert_tables_equal, cli, assert_raises_like_cli

CASES = [
    # (keyword arguments, the same on the command line)
    ({"duration": 5.0}, ["--duration", "5"]),
    ({"x0": "d", "duration": 3.0, "sample_dt": 0.002}, ["--x0", "d", "--duration", "3", "--sample-dt", "0.002"]),
    (
        {"x0_deg": (32, 0, 18.27, 0), "impact_law": "poisson", "e_n": 0.5, "mu": 0.45, "v_belt": -0.37, "duration": 4.0},
        ["--x0-deg", "32,0,18.27,0", "--impact-law", "poisson", "--e-n", "0.5", "--mu", "0.45", "--v-belt", "-0.37", "--duration", "4"],
    ),
    (
        {"duration": 3.0, "iwc": "plastic", "set": {"plant.m": 0.24}},
        ["--duration", "3", "--iwc", "plastic", "--set", "plant.m=0.24"],
    ),
]


@pytest.mark.parametrize("kwargs,argv", CASES)
def test_simulate_equals_the_cli(kwargs, argv, out):
    mine = painleve.simulate(progress=False, **kwargs)
    cli("simulate", argv, out)
    theirs = painleve.load(out)
    assert theirs.command == "simulate"
    assert_tables_equal(mine["trace"], theirs["trace"])
    assert_tables_equal(mine["events"], theirs["events"])
    assert_docs_equal(mine.summary, theirs.summary)
    assert mine.validity == theirs.validity == mine.summary["validity"]
    assert mine.trace.nrows == round(kwargs["duration"] / kwargs.get("sample_dt", 1e-3)) + 1
    assert mine.failure is None and mine.exit_code == 0


def test_counters_and_validity_are_carried():
    r = painleve.simulate(duration=10.0, progress=False)
    assert set(r.validity) == {"energy_gains", "newton_fallbacks", "poisson_fallbacks", "cone_violations", "zeno_stops", "integrator_failures"}
    assert r.summary["counters"]["lift_offs"] == r.summary["lift_offs"] > 0, "x0a at mu 0.6, v_belt -0.4 bounces"
    # Issue 67: lift_offs is every departure from the belt, as in sweep's rows; the
    # plant's own count (without the bounces) is lift_offs_from_contact.
    c = r.summary["counters"]
    assert c["lift_offs"] == c["lift_offs_from_contact"] + c["bounces"] and c["lift_offs_from_contact"] == 1
    # used_deg is the projected start before any impulse (the rates as given),
    # after_startup_deg the state after the impact without collision at t = 0.
    ic = r.summary["initial_condition"]
    assert ic["used_deg"][1] == ic["used_deg"][3] == 0.0 and ic["after_startup_deg"][1] > 100
    assert ic["used_deg"][0] == ic["after_startup_deg"][0] and ic["used_deg"][2] == ic["after_startup_deg"][2]
    assert r.valid and r.violations is None
    assert (r.trace["mode"] == "flight").any()


def test_the_energy_ledger_closes_and_says_where_the_energy_went():
    # docs/plant.md "The energy ledger": E(t) - E(0) = motors + damping + belt + slip + projections + residual.
    r = painleve.simulate(duration=10.0, progress=False)
    led = r.summary["ledger"]
    parts = led["motors_j"] + led["damping_j"] + led["belt_j"] + led["slip_j"] + led["projections_j"]
    assert led["energy_change_j"] == pytest.approx(parts + led["residual_j"], abs=1e-12)
    assert abs(led["residual_j"]) < 1e-9 and led["violations"] == 0
    assert led["motors_j"] == 0.0, "open loop: no motor torque"
    assert led["damping_j"] < 0 and led["slip_j"] < 0 < led["belt_j"], "the belt feeds the bouncing, damping and friction take it"
    # E(0) is the state as given, before the start-up events at t = 0 (x0a starts
    # with an impact without collision, x0d with its projection onto the belt, both
    # booked in the ledger). From x0d as projected (on the belt, sliding, no start-up
    # event) the trace's own energies give the same change.
    used = painleve.simulate(x0="d", duration=0.01, progress=False).summary["initial_condition"]["used_deg"]
    d = painleve.simulate(x0_deg=tuple(used), duration=3.0, progress=False)
    e = d.trace["energy"]
    assert float(e[len(e) - 1] - e[0]) == pytest.approx(d.summary["ledger"]["energy_change_j"], abs=1e-9)


@pytest.mark.parametrize(
    "kwargs,argv",
    [
        ({"mu": -1.0}, ["--mu", "-1"]),
        ({"duration": 0.0}, ["--duration", "0"]),
        ({"sample_dt": 20.0}, ["--sample-dt", "20"]),
        ({"x0_deg": (1, 2, 3)}, ["--x0-deg", "1,2,3"]),
        ({"impact_law": "elastic"}, ["--impact-law", "elastic"]),
        ({"e_n": 1.5}, ["--e-n", "1.5"]),
        ({"set": {"plant.mu": 0.3}}, ["--set", "plant.mu=0.3"]),
        ({"set": ["plant.nope=1"]}, ["--set", "plant.nope=1"]),
        ({"set": {"plant.m": -2}}, ["--set", "plant.m=-2"]),
        ({"x0": "d", "x0_deg": (32, 0, 18.27, 0)}, ["--x0", "d", "--x0-deg", "32,0,18.27,0"]),
    ],
)
def test_bad_input_raises_the_cli_message(kwargs, argv):
    assert_raises_like_cli(lambda: painleve.simulate(progress=False, **kwargs), "simulate", argv)
