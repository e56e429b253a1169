"""Reading tables: ``painleve.read_csv`` and ``load`` read through the compiled
module (the ``tables`` crate, arrow-csv) and give, for every CSV table the CLI
writes, the columns of its declaration, bit for bit against a reference that
reads each cell with Python (columns, dtypes, values, NaN for an empty float
cell, ``""`` for an empty text cell); Arrow tables read as their CSV; a file
that is no table of the CLI reads with arrow-csv's inferred types; bad files are
refused with the file and the line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import painleve
from conftest import cli
from reference_csv import declaration, declared_dtypes, reference_read_csv

# One folder per command, on small settings: every kind of CSV table the CLI writes.
FOLDERS = {
    # trace.csv (samples) and events.csv (impacts, touchdowns, lift-offs: text and empty cells)
    "simulate": ("simulate", ["--x0", "a", "--v-belt", "-0.5", "--e-n", "0.2", "--duration", "2"]),
    # the closed loop's period records (trace.csv: flags, counters, the status word)
    "run": ("run", ["--in-process", "--duration", "0.5"]),
    # sweep.csv and the runs.csv journal (several initial conditions and impact laws)
    "sweep": ("sweep", ["--mu", "0.6", "--v-belt", "-0.5,-0.4", "--v-belt-step", "0.1", "--ics", "a,u", "--random-ics", "1", "--seed", "3",
                        "--transient", "5", "--record", "5", "--impact-law", "newton,poisson"]),
    # section.csv and classes.csv
    "poincare": ("poincare", ["--v-belt", "-0.5,-0.46", "--v-step", "0.02", "--transient", "10", "--record", "5",
                              "--lyap-iterations", "10", "--lyap-skip", "2"]),
    # zmax.csv, trials.csv and the limit traces
    "zmax": ("zmax", ["--controller", "pid", "--x0", "d", "--ideal", "--tol", "0.02", "--duration", "3"]),
    "modes": ("modes", ["--grid", "40"]),
    "admissible": ("admissible", []),
}


@pytest.fixture(scope="module")
def folders(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("tables")
    for name, (command, args) in FOLDERS.items():
        cli(command, args, root / name)
    return root


def assert_identical(new: painleve.Table, old: dict, where: str) -> None:
    """The same columns in the same order, the same dtypes (string widths
    included), and the same values: floats by their bits (NaN's too)."""
    assert list(new) == list(old), f"{where}: columns {list(new)} != {list(old)}"
    for c, want in old.items():
        got = new[c]
        assert got.dtype == want.dtype, f"{where}.{c}: dtype {got.dtype} != {want.dtype}"
        assert got.shape == want.shape, f"{where}.{c}: shape {got.shape} != {want.shape}"
        if want.dtype.kind == "f":
            same = got.view(np.uint64) == want.view(np.uint64)
        else:
            same = got == want
        if not np.all(same):
            i = int(np.flatnonzero(~same)[0])
            raise AssertionError(f"{where}.{c}: {int((~same).sum())} cells differ, the first at row {i}: {got[i]!r} != {want[i]!r}")


def test_every_csv_table_reads_with_its_declared_types(folders):
    files = sorted(folders.rglob("*.csv"))
    names = {p.stem for p in files}
    for want in ("trace", "events", "sweep", "runs", "section", "classes", "zmax", "trials", "modes"):
        assert want in names, f"no {want}.csv written"
    dtypes = declared_dtypes()
    kinds = set()
    for p in files:
        assert declaration(p) is not None, f"{p.relative_to(folders)}: its header is no declared table"
        new = painleve.read_csv(p)
        assert new.name == p.stem
        assert_identical(new, reference_read_csv(p), str(p.relative_to(folders)))
        assert [new[c].dtype.kind for c in new.columns] == dtypes[tuple(new.columns)], p.name
        kinds |= {a.dtype.kind for a in new.values()}
    assert kinds == {"f", "i", "b", "U"}, f"the tables hold floats, integers, flags and text: {kinds}"
    # load reads the same tables.
    for name in FOLDERS:
        r = painleve.load(folders / name)
        for p in sorted((folders / name).glob("*.csv")):
            assert_identical(r.tables[p.stem], reference_read_csv(p), f"load {name}/{p.stem}")


def test_the_declared_types_do_not_depend_on_the_cells(tmp_path):
    """A text column whose cells are all empty stays text, an optional count is
    float64 whether or not a cell is empty, and a table without rows has its
    declared dtypes (a column's type is its declaration's, not its cells')."""
    events = next(names for names, _ in painleve._painleve.declared_tables() if "resolution" in names)
    p = tmp_path / "events.csv"
    row = ["0.5" if n not in ("kind", "mode_after", "resolution") else "" for n in events]
    row[events.index("kind")], row[events.index("mode_after")] = "touchdown", "sticking"
    p.write_text(",".join(events) + "\n" + ",".join(row) + "\n")
    t = painleve.read_csv(p)
    assert t["resolution"].dtype.kind == "U" and list(t["resolution"]) == [""], "an all-empty text column is text"
    p.write_text(",".join(events) + "\n")
    t = painleve.read_csv(p)
    assert t.nrows == 0 and [t[c].dtype.kind for c in t.columns] == declared_dtypes()[tuple(events)]
    classes = next(names for names, _ in painleve._painleve.declared_tables() if "lyapunov_iterations" in names)
    assert declared_dtypes()[tuple(classes)][classes.index("period")] == "f", "an optional count is float64 (NaN when empty)"


# Files the CLI does not write: arrow-csv's inferred types (the reader's documented fallback).
UNDECLARED = {
    "types": ("a,b,c,d,e,f,g\n1,1.5,true,x,,2,\n2,NaN,false,,,,\n", ["i", "f", "b", "U", "f", "f", "f"]),
    "quoted": ('t,kind\n0.0,"a,b"\n1.0,"say ""hi"""\n2.0,"two\nlines"\n', ["f", "U"]),
    "unicode": ("name,v\nÉlan,1\nμ,2\n", ["U", "i"]),
    "header only": ("t,z_t,mode\n", ["f", "f", "f"]),
    "crlf": ("a,b\r\n1,x\r\n2,y\r\n", ["i", "U"]),
    "flags with a gap": ("a,b\ntrue,1\n,2\n", ["U", "i"]),
    "dates are text": ("day,n\n2024-01-02,1\n", ["U", "i"]),
    "empty": ("", []),
}


@pytest.mark.parametrize("name", sorted(UNDECLARED))
def test_a_file_of_no_declared_table_has_arrow_csvs_inferred_types(name, tmp_path):
    text, kinds = UNDECLARED[name]
    p = tmp_path / "t.csv"
    p.write_bytes(text.encode("utf-8"))
    t = painleve.read_csv(p)
    assert [t[c].dtype.kind for c in t.columns] == kinds, name
    assert all(not np.ma.isMaskedArray(a) for a in t.values())


def test_undeclared_values():
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "t.csv"
        p.write_text(UNDECLARED["types"][0])
        t = painleve.read_csv(p)
        assert list(t["a"]) == [1, 2] and t["b"][0] == 1.5 and np.isnan(t["b"][1])
        assert list(t["d"]) == ["x", ""] and np.isnan(t["e"]).all()
        assert t["f"][0] == 2.0 and np.isnan(t["f"][1]), "an integer column with an empty cell is float64"
        p.write_text(UNDECLARED["quoted"][0])
        assert list(painleve.read_csv(p)["kind"]) == ["a,b", 'say "hi"', "two\nlines"]
        p.write_text(UNDECLARED["flags with a gap"][0])
        assert list(painleve.read_csv(p)["a"]) == ["true", ""], "a flag column with an empty cell is text"


def test_arrow_reads_with_the_files_own_types(tmp_path):
    """``read_arrow`` hands each column over with the file's type: an all-empty
    text column is text, a text column of digits is text, a table without rows
    keeps its types."""
    pa = pytest.importorskip("pyarrow")
    import pyarrow.ipc

    columns = {
        "t": pa.array([0.0, 0.001, 0.002], pa.float64()),
        "empty_text": pa.array(["", "", ""], pa.string()),
        "mode": pa.array(["flight", "", "sliding"], pa.string()),
        "numbers_as_text": pa.array(["1", "2", "3"], pa.string()),
        "n": pa.array([1, 2, 3], pa.int64()),
        "flag": pa.array([True, False, True], pa.bool_()),
    }
    for rows in (3, 0):
        table = pa.table({k: v[:rows] for k, v in columns.items()})
        arrow = tmp_path / f"t{rows}.arrow"
        with pa.OSFile(str(arrow), "wb") as sink, pyarrow.ipc.new_file(sink, table.schema) as w:
            w.write_table(table)
        a = painleve.read_arrow(arrow)
        assert [a[c].dtype.kind for c in a.columns] == ["f", "U", "U", "U", "i", "b"], rows
        assert a.nrows == rows
        for c in columns:
            assert a[c].tolist() == columns[c][:rows].to_pylist(), c


def test_a_simulate_folder_reads_alike_from_csv_and_arrow(tmp_path):
    args = FOLDERS["simulate"][1]
    cli("simulate", args + ["--format", "csv"], tmp_path / "csv")
    cli("simulate", args + ["--format", "arrow"], tmp_path / "arrow")
    a, c = painleve.load(tmp_path / "arrow"), painleve.load(tmp_path / "csv")
    for name in ("trace", "events"):
        assert_identical(a.tables[name], dict(c.tables[name]), f"{name}: arrow against csv")


def test_the_float_and_integer_arrays_share_the_readers_memory(tmp_path):
    """No copy: a float or integer column is a NumPy view of the Arrow buffer,
    whose base object keeps it alive after the table is gone."""
    cli("simulate", FOLDERS["simulate"][1] + ["--format", "arrow"], tmp_path)
    for read, name in ((painleve.read_arrow, "trace.arrow"), (painleve.read_csv, None)):
        if name is None:
            cli("simulate", FOLDERS["simulate"][1], tmp_path / "csv")
            path = tmp_path / "csv" / "trace.csv"
        else:
            path = tmp_path / name
        t = read(path)
        z = t["z_t"]
        assert z.base is not None and type(z.base).__name__ == "ArrowMemory", type(z.base)
        keep = z.copy()
        del t
        import gc

        gc.collect()
        assert np.array_equal(z.view(np.uint64), keep.view(np.uint64))


@pytest.mark.parametrize(
    "content, line, words",
    [
        (b"t,z_t\n0.0,1.0\n0.001,1.", 3, "ends inside a row"),
        (b"t,z_t\n0.0,1.0\n0.001\n", 3, "Expected 2 records, found 1"),
        (b"t,z_t\n0.0,1.0,2.0\n", 2, "Expected 2 records, found 3"),
        (b"t,t\n0.0,1.0\n", 1, "`t` twice"),
        (b"t,mode\n0.0,fl\xffight\n", 2, "utf-8"),
        (b"ARROW1\x00\x00\xff\xff\xff\xff", 1, "ends inside a row"),
    ],
)
def test_a_bad_csv_is_a_painleve_error_naming_the_file_and_line(tmp_path, content, line, words):
    p = tmp_path / "trace.csv"
    p.write_bytes(content)
    with pytest.raises(painleve.PainleveError) as e:
        painleve.read_csv(p)
    message = str(e.value)
    assert str(p) in message and f"line {line}" in message and words.lower() in message.lower(), message
    assert e.value.exit_code == 2
    # load names the file too.
    with pytest.raises(painleve.PainleveError, match="trace.csv"):
        painleve.load(tmp_path)


def test_a_declared_table_with_a_cell_not_of_its_type_is_refused_with_its_line(tmp_path):
    header = next(names for names, _ in painleve._painleve.declared_tables() if "theta1_dot" in names and "energy" in names)
    good = ",".join("sliding" if n == "mode" else "0.5" for n in header)
    bad = ",".join("sliding" if n == "mode" else ("x" if n == "z_t" else "0.5") for n in header)
    p = tmp_path / "trace.csv"
    p.write_text(",".join(header) + "\n" + good + "\n" + bad + "\n")
    with pytest.raises(painleve.PainleveError) as e:
        painleve.read_csv(p)
    assert str(p) in str(e.value) and "line 3:" in str(e.value) and "'x'" in str(e.value), str(e.value)


def test_a_missing_file_or_a_folder_is_file_not_found(tmp_path):
    for read in (painleve.read_csv, painleve.read_arrow):
        with pytest.raises(FileNotFoundError, match="no file"):
            read(tmp_path / "none.csv")
        with pytest.raises(FileNotFoundError, match="not a file"):
            read(tmp_path)
    with pytest.raises(TypeError):
        painleve.read_csv(3)


def test_a_long_file_reads_over_the_readers_batches(tmp_path):
    """A file of more rows than a record batch (65 536) reads as one table:
    a long trace of the CLI, against the reference, and its Arrow file alike."""
    cli("simulate", ["--duration", "70"], tmp_path / "csv")
    cli("simulate", ["--duration", "70", "--format", "arrow"], tmp_path / "arrow")
    p = tmp_path / "csv" / "trace.csv"
    got = painleve.read_csv(p)
    assert got.nrows > 65_536
    assert_identical(got, reference_read_csv(p), "long")
    assert_identical(painleve.read_arrow(tmp_path / "arrow" / "trace.arrow"), dict(got), "long, arrow")
