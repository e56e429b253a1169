"""examples/compare/: the paper's arm built in MuJoCo (PyPI `mujoco`, python/requirements-test.txt)
beside sil-host (issue 69, "Why not MuJoCo?"). The example's quick size runs the three cases
(the bounce from x0a at mu 0.6; mu 0.34 and 0.39 from x0a; x0d at mu 0.6), each with MuJoCo's
default and stiffest contacts at h 1e-4 s (two at 1e-5 s), checks the MuJoCo model against
docs/model.md, drops the tip on the belt, and asserts the outcomes: sil-host bounces or slides as
the rigid model says; MuJoCo's default contact never bounces; its stiffest bounces from x0d and
gives the large bounce only below sil-host's critical mu. About 15 s of wall time on 2 cores."""

from __future__ import annotations

import copy
import sys

import pytest

from conftest import REPO, sil_host

EXAMPLE = REPO / "examples" / "compare"


@pytest.fixture(scope="module")
def compare():
    sys.path.insert(0, str(EXAMPLE))
    try:
        import compare as module
    finally:
        sys.path.remove(str(EXAMPLE))
    return module


@pytest.fixture(scope="module")
def quick(compare, tmp_path_factory):
    """One quick run of the example (its check mode), its record written to a temporary file."""
    record = tmp_path_factory.mktemp("mujoco") / "results.md"
    code, result, checks = compare.run(["--quick", "--sil-host", str(sil_host()), "--record", str(record)])
    return code, result, checks, record


def test_every_check_passes(quick):
    code, result, checks, _ = quick
    failed = [text for ok, text in checks if not ok]
    assert code == 0 and result is not None and not failed, failed
    texts = "\n".join(text for _, text in checks)
    for needed in ("the MuJoCo model is docs/model.md's", "sil-host, case 1 ", "sil-host, case 2a ",
                   "sil-host, case 2b ", "sil-host, case 3 ", "MuJoCo default contact, h 0.0001 s, case 1 ",
                   "MuJoCo stiffest contact, h 0.0001 s, case 3 ", "MuJoCo stiffest contact, h 1e-05 s, case 3 ",
                   "the large bounce", "h 1e-05 s gives h 0.0001 s's outcome", "depends on the impact speed",
                   "where in a step"):
        assert needed in texts, f"no check for {needed!r}"


def test_the_outcomes(compare, quick):
    _, r, _, _ = quick
    cls = compare.classify
    assert [cls(r["sil"][k]) for k in ("1", "2a", "2b", "3")] == ["bounces", "slides", "bounces", "slides"]
    # sil-host's bounce at mu 0.6: about 316 lift-offs per 50 s, up to 4.8 cm (tests/siconos).
    assert 250 <= r["sil"]["1"]["lift_offs"] <= 400 and 0.04 <= r["sil"]["1"]["max_gap"] <= 0.06
    h = compare.H_COARSE
    for key in ("1", "2a", "2b", "3"):
        d = r["mj"][(key, "default", h)]
        assert cls(d) == "slides" and d["max_gap"] < compare.HIGH, (key, d)
        assert cls(r["mj"][(key, "stiffest", h)]) == "bounces", key
    gaps = {k: r["mj"][(k, "stiffest", h)]["max_gap"] for k in ("1", "2a", "2b", "3")}
    assert gaps["2a"] > 5 * max(gaps["1"], gaps["2b"], gaps["3"]), gaps
    m = r["model"]
    assert max(m["mass_matrix"], m["forces"], m["tip"]) < 1e-12, m


def test_a_check_fails_when_an_outcome_changes(compare, quick):
    """The checks read the measurements: a default contact that bounced, a stiffest contact that
    slid from x0d, a model that differed from docs/model.md each fail one."""
    _, r, _, _ = quick
    h = compare.H_COARSE

    def failing(result):
        return [text for ok, text in compare.evaluate(result) if not ok]

    def mutated(key, **changes):
        out = copy.deepcopy(r)
        out["mj"][key].update(changes)
        return out

    assert not failing(r)
    bounced = mutated(("1", "default", h), high_flights=300, max_gap=0.045)
    assert any("default contact, h 0.0001 s, case 1 " in t for t in failing(bounced))
    slid = mutated(("3", "stiffest", h), high_flights=0, max_gap=5e-6)
    assert any("case 3 (x0d, mu 0.6): bounces where sil-host slides" in t for t in failing(slid))
    other = dict(r, model=dict(r["model"], forces=1e-6))
    assert any("docs/model.md's" in t for t in failing(other))


def test_the_record(quick):
    _, r, checks, record = quick
    text = record.read_text()
    assert text.startswith("```\npython examples/compare/compare.py")
    assert f"MuJoCo {r['versions']['mujoco']}" in text and "sil-host at commit `" in text
    assert f"{len(checks)} of {len(checks)} checks passed" in text
    for row in ("| 1: the bounce from x0a (x0a, mu 0.6) | bounces: ", "| 2a: below the critical mu (x0a, mu 0.34) | slides",
                "| 2b: above the critical mu (x0a, mu 0.39) | bounces: ", "| 3: x0d (x0d, mu 0.6) | slides"):
        assert row in text, row


def test_a_missing_sil_host_is_a_setup_error(compare, tmp_path, capsys):
    assert compare.main(["--quick", "--sil-host", str(tmp_path / "no-sil-host")]) == 2
    assert "SETUP no sil-host" in capsys.readouterr().out
