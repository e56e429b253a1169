"""The long analyses against the CLI on small grids: `sweep` (open and closed
loop), `zmax` (ideal and sampled) and `poincare`."""

import pytest

import painleve
from conftest import assert_docs_equal, assert_tables_equal, cli, assert_raises_like_cli

SWEEP_CASES = [
    (
        {"mu": (0.3, 0.6), "mu_step": 0.1, "v_belt": (-0.6, -0.3), "v_belt_step": 0.1, "transient": 30.0, "record": 10.0, "e_n": [0.2, 0.5]},
        ["--mu", "0.3,0.6", "--mu-step", "0.1", "--v-belt", "-0.6,-0.3", "--v-belt-step", "0.1", "--transient", "30", "--record", "10", "--e-n", "0.2,0.5"],
    ),
    (
        {"mu": 0.6, "v_belt": (-0.5, -0.3), "v_belt_step": 0.1, "ics": "d", "controller": "hybrid", "transient": 4.0, "record": 2.0},
        ["--mu", "0.6", "--v-belt", "-0.5,-0.3", "--v-belt-step", "0.1", "--ics", "d", "--controller", "hybrid", "--transient", "4", "--record", "2"],
    ),
    (
        {"mu": 0.6, "v_belt": -0.4, "ics": ["a", "u"], "random_ics": 2, "seed": 3, "transient": 10.0, "record": 5.0, "impact_law": ["newton", "poisson"]},
        ["--mu", "0.6", "--v-belt", "-0.4", "--ics", "a,u", "--random-ics", "2", "--seed", "3", "--transient", "10", "--record", "5", "--impact-law", "newton,poisson"],
    ),
]


@pytest.mark.parametrize("kwargs,argv", SWEEP_CASES)
def test_sweep_equals_the_cli(kwargs, argv, out):
    mine = painleve.sweep(progress=False, **kwargs)
    cli("sweep", argv, out)
    theirs = painleve.load(out)
    assert theirs.command == "sweep"
    assert_tables_equal(mine["sweep"], theirs["sweep"])
    assert_docs_equal(mine.summary, theirs.summary)
    assert mine.validity == theirs.validity == mine.summary["results"]["validity"]
    assert mine.summary["status"] == "complete"
    assert list(mine["sweep"]["index"]) == list(range(mine["sweep"].nrows))


def test_sweep_shard_and_limit():
    base = {"mu": (0.5, 0.6), "v_belt": (-0.5, -0.3), "v_belt_step": 0.1, "transient": 5.0, "record": 5.0, "progress": False}
    whole = painleve.sweep(**base)["sweep"]
    halves = [painleve.sweep(shard=f"{k}/2", **base) for k in range(2)]
    assert sorted(i for h in halves for i in h["sweep"]["index"]) == list(whole["index"])
    assert all(h.summary["status"] == "complete" for h in halves)
    some = painleve.sweep(limit=3, **base)
    assert some["sweep"].nrows == 3 and some.summary["status"] == "incomplete"


ZMAX_CASES = [
    ({"controller": "pid", "x0": "d", "ideal": True, "tol": 0.01, "duration": 4.0}, ["--controller", "pid", "--x0", "d", "--ideal", "--tol", "0.01", "--duration", "4"]),
    ({"controller": "hybrid", "x0": "d", "tol": 0.01, "duration": 4.0}, ["--controller", "hybrid", "--x0", "d", "--tol", "0.01", "--duration", "4"]),
]


@pytest.mark.parametrize("kwargs,argv", ZMAX_CASES)
def test_zmax_equals_the_cli(kwargs, argv, out):
    mine = painleve.zmax(progress=False, **kwargs)
    cli("zmax", argv, out)
    theirs = painleve.load(out)
    assert theirs.command == "zmax"
    assert_tables_equal(mine["zmax"], theirs["zmax"], skip=["wall_s"])
    assert_tables_equal(mine["trials"], theirs["trials"], skip=["wall_s"])
    assert_docs_equal(mine.summary, theirs.summary)
    assert mine.validity == theirs.validity
    assert mine["zmax"]["z_t_sliding_m"][0] > 0.05
    (stem,) = mine.extras["limit_traces"]
    assert mine.extras["limit_traces"][stem].nrows > 0


def test_poincare_equals_the_cli(out):
    kwargs = {"v_belt": (-0.5, -0.36), "v_step": 0.02, "transient": 40.0, "record": 20.0, "lyap_iterations": 30, "lyap_skip": 3}
    argv = ["--v-belt", "-0.5,-0.36", "--v-step", "0.02", "--transient", "40", "--record", "20", "--lyap-iterations", "30", "--lyap-skip", "3"]
    mine = painleve.poincare(progress=False, **kwargs)
    cli("poincare", argv, out)
    theirs = painleve.load(out)
    assert theirs.command == "poincare"
    assert_tables_equal(mine["section"], theirs["section"])
    assert_tables_equal(mine["classes"], theirs["classes"], skip=["wall_s"])
    assert_docs_equal(mine.summary, theirs.summary)
    assert_docs_equal(mine.extras["classes"], theirs.extras["classes"])
    assert mine["classes"].nrows == 8
    assert mine["section"].nrows == mine.summary["section_points"] > 0


@pytest.mark.parametrize(
    "command,kwargs,argv",
    [
        ("sweep", {"mu": "a,b"}, ["--mu", "a,b"]),
        ("sweep", {"ics": "x"}, ["--ics", "x"]),
        ("sweep", {"scenario": "scenarios/default.toml"}, ["--scenario", "scenarios/default.toml"]),
        ("sweep", {"set": {"plant.mu": 0.2}}, ["--set", "plant.mu=0.2"]),
        ("sweep", {"shard": "3/2"}, ["--shard", "3/2"]),
        ("sweep", {"threads": 0}, ["--threads", "0"]),
        ("sweep", {"transient": -1.0}, ["--transient", "-1"]),
        ("zmax", {"tol": 0.0}, ["--tol", "0"]),
        ("zmax", {"x0": "a"}, ["--x0", "a"]),
        ("zmax", {"bracket": (0.2, 0.1)}, ["--bracket", "0.2,0.1"]),
        ("zmax", {"set": {"timing.duration_s": 3}}, ["--set", "timing.duration_s=3"]),
        ("zmax", {"reach_tol": -1.0}, ["--reach-tol", "-1"]),
        ("poincare", {"v_step": 0.0}, ["--v-step", "0"]),
        ("poincare", {"max_period": 0}, ["--max-period", "0"]),
        ("poincare", {"v_belt": (0.1, -0.1)}, ["--v-belt", "0.1,-0.1"]),
        ("poincare", {"threads": 0}, ["--threads", "0"]),
        ("sensitivity", {"size": "huge"}, ["--size", "huge"]),
        ("sensitivity", {"set": {"plant.e_n": 0.5}}, ["--set", "plant.e_n=0.5"]),
        ("sensitivity", {"threads": 0}, ["--threads", "0"]),
    ],
)
def test_bad_input_raises_the_cli_message(command, kwargs, argv, monkeypatch):
    from conftest import REPO

    monkeypatch.chdir(REPO)
    assert_raises_like_cli(lambda: getattr(painleve, command)(progress=False, **kwargs), command, argv)


def test_seeded_sweep_equals_the_cli(out):
    """``seeds=`` (issue 82): the cells over the sensor-noise seeds, each fraction
    with its Wilson interval, equal to the CLI's ``cells.csv``; seed 0 is the
    sweep of one seed."""
    kwargs = {"mu": (0.9, 0.95), "mu_step": 0.05, "v_belt": -0.5, "ics": "d", "controller": "hybrid", "transient": 3.0, "record": 2.0}
    argv = ["--mu", "0.9,0.95", "--mu-step", "0.05", "--v-belt", "-0.5", "--ics", "d", "--controller", "hybrid", "--transient", "3", "--record", "2"]
    mine = painleve.sweep(progress=False, seeds=4, **kwargs)
    cli("sweep", [*argv, "--seeds", "4"], out)
    theirs = painleve.load(out)
    assert_tables_equal(mine["sweep"], theirs["sweep"])
    assert_tables_equal(mine["cells"], theirs["cells"])
    assert_docs_equal(mine.summary, theirs.summary)
    cells = mine["cells"]
    assert list(cells["runs"]) == [4, 4]
    for i in range(cells.nrows):
        k, n = cells["lift_off"][i], cells["runs"][i]
        assert cells["lift_off_lo"][i] <= k / n <= cells["lift_off_hi"][i]
    one = painleve.sweep(progress=False, **kwargs)
    assert one.summary["samples"]["seeds"] == 1 and "one sample" in one.summary["samples"]["note"]
    seed0 = [i for i in range(mine["sweep"].nrows) if mine["sweep"]["seed"][i] == 0]
    # Bit for bit (a run that stopped early has NaN maxima: compared as text).
    assert [repr(float(mine["sweep"]["theta1_dot_max"][i])) for i in seed0] == [repr(float(x)) for x in one["sweep"]["theta1_dot_max"]]


def test_seeded_zmax_equals_the_cli(out):
    kwargs = {"controller": "hybrid", "x0": "d", "tol": 0.01, "duration": 4.0}
    argv = ["--controller", "hybrid", "--x0", "d", "--tol", "0.01", "--duration", "4", "--seeds", "3"]
    mine = painleve.zmax(progress=False, seeds=3, **kwargs)
    cli("zmax", argv, out)
    theirs = painleve.load(out)
    assert_tables_equal(mine["zmax_seeds"], theirs["zmax_seeds"])
    assert_docs_equal(mine.summary, theirs.summary)
    assert list(mine["zmax_seeds"]["seed"]) == [0, 1, 2]
    (d,) = mine.summary["distributions"]
    assert d["seeds"] == 3 and d["z_t_sliding"]["min_m"] <= d["z_t_sliding"]["median_m"] <= d["z_t_sliding"]["max_m"]
