"""`painleve.load` and the result objects: column types, pandas, failures,
strict, and the folders of other commands."""

import numpy as np
import pytest

import painleve
from conftest import cli


def test_read_csv_types(tmp_path):
    # A file of no table of the CLI: arrow-csv's inferred types.
    p = tmp_path / "t.csv"
    p.write_text("a,b,c,d,e,f,g\n1,1.5,true,x,,2,\n2,NaN,false,,,,\n")
    t = painleve.read_csv(p)
    assert t.columns == list("abcdefg")
    assert t["a"].dtype == np.int64 and list(t["a"]) == [1, 2]
    assert t["b"].dtype == np.float64 and np.isnan(t["b"][1])
    assert t["c"].dtype == bool and list(t["c"]) == [True, False]
    assert t["d"].dtype.kind == "U" and list(t["d"]) == ["x", ""]
    assert t["e"].dtype == np.float64 and np.isnan(t["e"]).all(), "an all-empty column is NaN"
    assert t["f"].dtype == np.float64 and t["f"][0] == 2 and np.isnan(t["f"][1]), "an integer column with an empty cell is float"


def test_to_pandas():
    pd = pytest.importorskip("pandas")
    r = painleve.simulate(duration=1.0, progress=False)
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == r.trace.columns and len(df) == r.trace.nrows
    assert np.array_equal(df["z_t"].to_numpy(), r.trace["z_t"])
    assert r.to_pandas("events").shape == (r.events.nrows, len(r.events))


def test_to_polars():
    pl = pytest.importorskip("polars")
    r = painleve.simulate(duration=1.0, progress=False)
    assert r.to_polars().shape == (r.trace.nrows, len(r.trace))
    assert isinstance(r.to_polars(), pl.DataFrame)


def test_a_failure_warns_and_strict_raises_it():
    """A result the CLI would exit 1 for (written, then failed): a warning with
    the CLI's message, or with strict=True the PainleveError carrying the result."""
    from painleve._api import _finish

    raw = {
        "command": "simulate",
        "summary": {"status": "failed"},
        "tables": {},
        "extras": {},
        "validity": {"cone_violations": 2},
        "violations": "2 friction-cone violations",
        "failure": "results violate the model (--strict): 2 friction-cone violations",
        "exit_code": 1,
    }
    with pytest.warns(painleve.PainleveWarning, match="friction-cone"):
        r = _finish(raw, strict=False)
    assert not r.valid and r.exit_code == 1
    with pytest.raises(painleve.PainleveError) as e:
        _finish(raw, strict=True)
    assert e.value.exit_code == 1 and e.value.result.failure == raw["failure"]
    ok = painleve.simulate(duration=0.5, progress=False, strict=True)
    assert ok.check() is ok and ok.failure is None


def test_load_a_sweep_folder_has_the_journal_and_the_spec(tmp_path):
    out = tmp_path / "s"
    cli("sweep", ["--mu", "0.6", "--v-belt", "-0.5,-0.4", "--v-belt-step", "0.1", "--transient", "5", "--record", "5"], out)
    r = painleve.load(out)
    assert r.command == "sweep" and set(r.tables) == {"runs", "sweep"}
    assert r.extras["sweep"]["spec"]["mu"]["start"] == 0.6
    assert r.validity == r.summary["results"]["validity"] and r.valid
    assert any(f.endswith(".svg") for f in r.extras["figures"])
    assert sorted(r["runs"]["index"]) == list(r["sweep"]["index"])


def test_load_rejects_a_missing_folder(tmp_path):
    with pytest.raises(FileNotFoundError):
        painleve.load(tmp_path / "nothing")


def test_load_and_scenario_load_refuse_unbounded_files(tmp_path):
    # Issue 80: a summary.json of 10 GB (sparse) is refused naming its bound,
    # not read until memory runs out; a scenario that is a device likewise.
    out = tmp_path / "huge"
    out.mkdir()
    with open(out / "summary.json", "wb") as f:
        f.truncate(10_000_000_000)
    with pytest.raises(painleve.PainleveError, match=r"summary\.json: it is 10000000000 bytes.*at most 64 MiB"):
        painleve.load(out)
    with pytest.raises(painleve.PainleveError, match=r"it is a character device, not a regular file.*at most 4 MiB") as e:
        painleve.Scenario.load("/dev/zero")
    assert e.value.exit_code == 2


def test_load_of_a_killed_runs_folder_says_so(tmp_path):
    # Issue 52, 8: a killed run's folder (its streamed trace as
    # `trace.csv.partial`, no summary) loaded as an empty result, silently.
    out = tmp_path / "killed"
    out.mkdir()
    (out / "trace.csv.partial").write_text("t,z_n\n0.001,0.1\n")
    (out / ".sil-host.owner").write_text("pid 1: sil-host run\n")
    with pytest.raises(ValueError, match=r"killed.*trace\.csv\.partial"):
        painleve.load(out)
    # Beside finished results, a partial file is named in a warning and left out.
    (out / "summary.json").write_text("{}")
    with pytest.warns(UserWarning, match=r"trace\.csv\.partial"):
        r = painleve.load(out)
    assert r.summary == {} and r.tables == {}


def test_result_repr_and_attributes():
    r = painleve.simulate(duration=0.5, progress=False)
    assert "simulate" in repr(r) and "valid" in repr(r)
    assert r.trace is r["trace"]
    with pytest.raises(AttributeError):
        r.no_such_table
    assert "trace" in dir(r)


def test_load_a_report_folder_loads_its_experiments(tmp_path):
    """A report's folder: report.json, report.md and one folder per experiment
    (here one, made by the CLI), each loaded as a Result."""
    root = tmp_path / "report"
    cli("simulate", ["--duration", "1"], root / "simulate")
    (root / "report.json").write_text('{"experiments": [{"id": "simulate", "status": "ok"}]}')
    (root / "report.md").write_text("# report\n")
    r = painleve.load(root)
    assert r.command == "report" and r.summary["experiments"][0]["id"] == "simulate"
    assert r.extras["report"] == "# report\n"
    sim = r.extras["experiments"]["simulate"]
    assert sim.command == "simulate" and sim.trace.nrows == 1001 and sim.valid


def test_a_result_prints_its_tables():
    # Issue 42, 4: print(painleve.admissible()) shows paper Table II, not a repr.
    r = painleve.admissible()
    text = str(r)
    assert text.startswith("painleve.Result admissible: no simulation")
    assert "intervals: 4 rows x 4 columns" in text, "Table II: two branches, two slip directions"
    for word in ("direction", "branch", "lo_m", "hi_m", "elbow_up", "elbow_down"):
        assert word in text, word
    # Every interval's ends, to 6 significant digits.
    for lo, hi in zip(r.intervals["lo_m"], r.intervals["hi_m"]):
        assert f"{lo:.6g}" in text and f"{hi:.6g}" in text
    html = r._repr_html_()
    assert html.count("<table>") == len(r.tables) and "<th>lo_m</th>" in html


def test_a_long_table_prints_its_ends_and_elides_the_middle():
    t = painleve.Table({"t": np.arange(100) * 0.5, "mode": np.array(["a&b"] * 100)}, "trace")
    lines = str(t).splitlines()
    assert lines[0] == "trace: 100 rows x 2 columns"
    assert len(lines) == 2 + 20, "the title, the header and 20 rows"
    assert lines[2].split()[0] == "0" and lines[-1].split()[0] == "49.5"
    assert any(line.split()[0] == "..." for line in lines)
    html = t._repr_html_()
    assert "a&amp;b" in html and "a&b" not in html.replace("a&amp;b", "")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"mu": [1, 2]}, "mu: expected a number, got list [1, 2]"),
        ({"mu": True}, "mu: expected a number, got bool True"),
        ({"mu": None}, "mu: expected a number, got NoneType None"),
        ({"duration": "10"}, "duration: expected a number, got str '10'"),
        ({"impact_law": 3}, "impact_law: expected 'newton', 'poisson' or 'energetic', got int 3"),
    ],
)
def test_a_wrong_type_is_a_type_error_naming_the_parameter(kwargs, message):
    # Issue 42, 2: Python types are checked at the boundary, not as CLI syntax.
    with pytest.raises(TypeError) as e:
        painleve.simulate(progress=False, **kwargs)
    assert str(e.value) == message
    assert "--" not in str(e.value), "no CLI syntax"


def test_right_types_pass_the_check():
    # Integers and NumPy scalars are numbers; Optional takes None; a sequence of numbers is a list.
    r = painleve.simulate(mu=np.float64(0.6), duration=1, max_step=None, progress=False)
    assert r.valid
    r = painleve.admissible(mu=1)
    assert r.intervals.nrows == 4


def test_a_painleve_error_always_has_its_result():
    # Issue 42, 2: `PainleveError.result` as documented: None for bad input.
    with pytest.raises(painleve.PainleveError) as e:
        painleve.simulate(mu=-1.0, progress=False)
    assert e.value.exit_code == 2 and e.value.result is None
