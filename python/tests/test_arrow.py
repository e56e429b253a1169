"""``simulate --format arrow``: the Arrow IPC tables hold what the CSV tables
hold, bit for bit, and ``painleve.load``, pandas and polars read them."""

import numpy as np
import pytest

import painleve
from conftest import assert_columns_equal, cli

# A bouncing run from x0a (touchdowns and an impact without collision), so the
# events table has several kinds and resolutions.
ARGS = ["--x0", "a", "--v-belt", "-0.5", "--e-n", "0.2", "--duration", "2"]


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    root = tmp_path_factory.mktemp("arrow")
    cli("simulate", ARGS + ["--format", "csv"], root / "csv")
    cli("simulate", ARGS + ["--format", "arrow"], root / "arrow")
    return root / "csv", root / "arrow"


def test_the_arrow_folder_has_the_csv_tables_with_the_same_bits(folders):
    csv_dir, arrow_dir = folders
    assert sorted(p.name for p in arrow_dir.iterdir()) == ["events.arrow", "summary.json", "trace.arrow", "trace.html", "trace.pdf", "trace.svg"]
    a, c = painleve.load(arrow_dir), painleve.load(csv_dir)
    assert a.command == c.command == "simulate"
    assert sorted(a.tables) == sorted(c.tables) == ["events", "trace"]
    assert a.events.nrows > 5 and len(set(a.events["kind"])) >= 2
    for name in ("trace", "events"):
        assert a.tables[name].columns == c.tables[name].columns, name
        for col in c.tables[name].columns:
            x, y = a.tables[name][col], c.tables[name][col]
            assert_columns_equal(x, y, f"{name}.{col}")
            if x.dtype.kind == "f":
                # The CSV's shortest round-trip digits read back to the same bits.
                assert np.array_equal(x.view(np.int64), y.view(np.int64)), f"{name}.{col}"
    files = a.summary["files"]
    assert [f.rsplit("/", 1)[-1] for f in files] == ["trace.arrow", "events.arrow", "trace.svg", "trace.pdf", "trace.html", "summary.json"]


def test_pandas_and_polars_read_the_arrow_tables(folders):
    pd = pytest.importorskip("pandas")
    pl = pytest.importorskip("polars")
    _, arrow_dir = folders
    r = painleve.load(arrow_dir)
    for name in ("trace", "events"):
        df = pd.read_feather(arrow_dir / f"{name}.arrow")
        assert list(df.columns) == r.tables[name].columns
        assert len(df) == r.tables[name].nrows
        pf = pl.read_ipc(arrow_dir / f"{name}.arrow")
        assert pf.columns == r.tables[name].columns
        for col in r.tables[name].columns:
            want = r.tables[name][col]
            got = df[col].to_numpy()
            if want.dtype.kind == "f":
                assert df[col].dtype == np.float64 and pf[col].dtype == pl.Float64, col
                assert np.array_equal(got.view(np.int64), want.view(np.int64)), col
                assert np.array_equal(pf[col].to_numpy().view(np.int64), want.view(np.int64)), col
            else:
                assert list(got) == list(want), col
                assert pf[col].to_list() == list(want), col


def test_a_cut_arrow_file_gives_its_whole_batches_and_text_is_an_error_naming_it(folders, tmp_path):
    # Cut in its footer (a killed writer's file ends before it): every batch.
    _, arrow_dir = folders
    whole = painleve.read_arrow(arrow_dir / "trace.arrow")
    bad = tmp_path / "trace.arrow"
    bad.write_bytes((arrow_dir / "trace.arrow").read_bytes()[:-40])
    cut = painleve.read_arrow(bad)
    assert cut.columns == whole.columns and cut.nrows == whole.nrows > 0
    bad.write_text("t,z_t\n0,1\n")
    # A file being read that cannot be: "cannot read", never "cannot write" (issue 66).
    with pytest.raises(painleve.PainleveError, match="^cannot read .*trace.arrow"):
        painleve.read_arrow(bad)


def test_an_unknown_format_is_refused():
    from conftest import cli_error

    message, code = cli_error("simulate", ["--format", "parquet"])
    assert code == 2 and "parquet" in message and "arrow" in message


def test_a_runs_arrow_file_loads_as_its_csv_trace(tmp_path):
    # `run --format arrow`: the trace is an Arrow IPC file like simulate's (one
    # `.arrow` convention, issue 55), written a batch at a time; painleve.load,
    # pandas.read_feather and polars.read_ipc read it.
    cli("run", ["--in-process", "--duration", "0.5", "--format", "csv"], tmp_path / "csv")
    cli("run", ["--in-process", "--duration", "0.5", "--format", "arrow"], tmp_path / "arrow")
    a, c = painleve.load(tmp_path / "arrow"), painleve.load(tmp_path / "csv")
    # Issue 69 (5): the folder is known as a run's, whatever its format.
    assert a.command == c.command == "run", (a.command, c.command)
    assert a.validity is not None and a.validity == c.validity and "no simulation" not in str(a)
    assert a.trace.columns == c.trace.columns and a.trace.nrows == c.trace.nrows == 500
    for col in c.trace.columns:
        assert_columns_equal(a.trace[col], c.trace[col], f"trace.{col}")
    import pandas
    import polars

    path = tmp_path / "arrow" / "trace.arrow"
    assert len(pandas.read_feather(path)) == 500
    assert polars.read_ipc(path).height == 500


def test_every_arrow_file_the_cli_writes_is_read_by_pandas_and_polars(tmp_path):
    # One `.arrow` convention (issue 55): every `.arrow` of every command that
    # writes one is an Arrow IPC file, the same columns as its CSV.
    import pandas
    import polars

    cli("simulate", ["--duration", "0.5", "--format", "arrow"], tmp_path / "simulate")
    cli("run", ["--in-process", "--duration", "0.3", "--format", "arrow"], tmp_path / "run")
    files = sorted(tmp_path.glob("*/*.arrow"))
    assert [f.relative_to(tmp_path).as_posix() for f in files] == [
        "run/frames.arrow",
        "run/trace.arrow",
        "simulate/events.arrow",
        "simulate/trace.arrow",
    ]
    for f in files:
        table = painleve.read_arrow(f)
        frame, pl = pandas.read_feather(f), polars.read_ipc(f)
        assert list(frame.columns) == list(pl.columns) == table.columns, f
        assert len(frame) == pl.height == table.nrows, f
