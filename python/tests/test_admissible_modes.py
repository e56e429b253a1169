"""`painleve.admissible` and `painleve.modes` against the CLI: the same document
(admissible.json, the modes `--json` document) and the same modes.csv."""

import pytest

import painleve
from conftest import assert_docs_equal, assert_tables_equal, cli, assert_raises_like_cli, json_of


@pytest.mark.parametrize("mu,sets", [(0.6, []), (0.3, []), (0.6, ["plant.l=0.25"])])
def test_admissible_equals_the_cli(mu, sets, out):
    mine = painleve.admissible(mu=mu, set=sets)
    argv = ["--mu", repr(mu)] + [x for s in sets for x in ("--set", s)]
    printed = json_of(cli("admissible", argv, out))
    theirs = painleve.load(out)
    assert theirs.command == "admissible"
    assert_docs_equal(mine.summary, theirs.summary)
    assert_docs_equal(mine.summary, printed)
    assert_tables_equal(mine["intervals"], theirs["intervals"])
    assert mine.validity is None, "admissible simulates nothing"


def test_admissible_is_paper_table_ii():
    """The paper's case (z_r_dot > 0): one interval per branch, within a
    millimetre of Table II's ends as docs/model.md quotes them."""
    t = painleve.admissible(mu=0.6)["intervals"]
    positive = t["direction"] == "z_r_dot_positive"
    assert set(t["branch"][positive]) == {"elbow_up", "elbow_down"}
    assert (t["hi_m"] > t["lo_m"]).all()


@pytest.mark.parametrize(
    "kwargs,argv",
    [
        ({"grid": 60, "theta1_deg": (-40, 40), "theta2_sign": "auto"}, ["--grid", "60", "--theta1-deg", "-40,40", "--theta2-sign", "auto"]),
        ({"grid": 80, "mu": 0.9, "v_belt": 0.3, "branch": "up"}, ["--grid", "80", "--mu", "0.9", "--v-belt", "0.3", "--branch", "up"]),
    ],
)
def test_modes_equals_the_cli(kwargs, argv, out):
    mine = painleve.modes(**kwargs)
    printed = json_of(cli("modes", argv, out))
    theirs = painleve.load(out)
    assert theirs.command == "modes"
    assert_tables_equal(mine["modes"], theirs["modes"])
    assert_docs_equal(mine.summary, printed)
    n = kwargs["grid"]
    assert mine["modes"].nrows == n * n
    assert len(mine.extras["theta1_deg"]) == len(mine.extras["theta1_dot"]) == n
    assert all(c.shape[1] == 2 for c in mine.extras["b_zero"])
    counts = {c["mode"]: c["count"] for c in mine.summary["counts"]}
    for mode, count in counts.items():
        assert (mine["modes"]["mode"] == mode).sum() == count


@pytest.mark.parametrize(
    "command,kwargs,argv",
    [
        ("admissible", {"mu": -0.1}, ["--mu", "-0.1"]),
        ("admissible", {"set": {"plant.m": 0.2}}, ["--set", "plant.m=0.2"]),
        ("modes", {"grid": 1}, ["--grid", "1"]),
        ("modes", {"grid": 1001}, ["--grid", "1001"]),
        ("modes", {"theta1_deg": (10, -10)}, ["--theta1-deg", "10,-10"]),
        ("modes", {"theta1_dot": "x"}, ["--theta1-dot", "x"]),
        ("modes", {"branch": "sideways"}, ["--branch", "sideways"]),
    ],
)
def test_bad_input_raises_the_cli_message(command, kwargs, argv):
    assert_raises_like_cli(lambda: getattr(painleve, command)(**kwargs), command, argv)
