"""Reading tables (issue 44, 5): ``painleve.read_csv`` and ``load`` read through
the compiled module and give, for every CSV table the CLI writes, what the
former pure-Python reader gave, bit for bit (columns, dtypes, values, NaN for
empty cells, text); Arrow tables read as their CSV (an all-empty text column is
NaN from both); bad files are refused with the file and the line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import painleve
from conftest import cli
from reference_csv import reference_read_csv

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


def test_every_csv_table_reads_as_the_former_reader_read_it(folders):
    files = sorted(folders.rglob("*.csv"))
    names = {p.stem for p in files}
    for want in ("trace", "events", "sweep", "runs", "section", "classes", "zmax", "trials", "modes"):
        assert want in names, f"no {want}.csv written"
    kinds = set()
    for p in files:
        new = painleve.read_csv(p)
        assert new.name == p.stem
        assert_identical(new, reference_read_csv(p), str(p.relative_to(folders)))
        kinds |= {a.dtype.kind for a in new.values()}
    assert kinds >= {"f", "i", "b", "U"}, f"the tables hold floats, integers, flags and text: {kinds}"
    # load reads the same tables.
    for name in FOLDERS:
        r = painleve.load(folders / name)
        for p in sorted((folders / name).glob("*.csv")):
            assert_identical(r.tables[p.stem], reference_read_csv(p), f"load {name}/{p.stem}")


# Files the CLI does not write, with the cases of the typing rule; each is read as
# the former reader read it.
EDGE_FILES = {
    "types": "a,b,c,d,e,f,g\n1,1.5,true,x,,2,\n2,NaN,false,,,,\n",
    "numbers": "x,y,z,w\n1e-320,-0.0,inf,1\n5e-324,1.7976931348623157e308,-inf,1.0\n0.1,+2,-Infinity,-3\n",
    "text after numbers": "n,f,b\n1,0.5,true\n2,1.5,false\nthree,x,\n",
    "empty columns": "t,empty_text,mode,empty_last\n0.0,,flight,\n0.001,,,\n0.002,,sliding,\n",
    "quoted": 't,kind\n0.0,"a,b"\n1.0,"say ""hi"""\n2.0,"two\nlines"\n',
    "unicode": "name,v\nÉlan,1\nμ,2\n",
    "blank lines": "a,b\n\n1,2\n\n3,4\n",
    "u64": "seed,small\n18446744073709551615,1\n9223372036854775808,2\n",
    "ints with a gap": "i\n1\n\n2\n",
    "one column with empties": "a,b\n1,\n,\n",
    "header only": "t,z_t,mode\n",
    "whitespace and underscores": "x,y\n 1.5,1_000\n2.5 ,2_000.5\n",
    "crlf": "a,b\r\n1,x\r\n2,y\r\n",
    # "-0" is an integer, but -0.0 once its column is floats; a cell of 20 digits and a
    # letter is text (no integer that overflows).
    "negative zero": "i,j,k\n-0,-0,10000000000000000000e\n1.5,2,1\n",
    "empty": "",
}


@pytest.mark.parametrize("name", sorted(EDGE_FILES))
def test_edge_files_read_as_the_former_reader_read_them(name, tmp_path):
    p = tmp_path / "t.csv"
    p.write_bytes(EDGE_FILES[name].encode("utf-8"))
    assert_identical(painleve.read_csv(p), reference_read_csv(p), name)


def test_the_typing_rule():
    # The documented rule (painleve.read_csv's docstring, docs/python.md).
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "t.csv"
        p.write_text(EDGE_FILES["empty columns"])
        t = painleve.read_csv(p)
        assert t["empty_text"].dtype == np.float64 and np.isnan(t["empty_text"]).all(), "a column of empty cells is NaN"
        assert t["mode"].dtype.kind == "U" and list(t["mode"]) == ["flight", "", "sliding"], "text keeps its empty cells as ''"
        p.write_text(EDGE_FILES["header only"])
        t = painleve.read_csv(p)
        assert t.columns == ["t", "z_t", "mode"] and all(a.dtype == np.float64 and a.shape == (0,) for a in t.values())
        p.write_text(EDGE_FILES["u64"])
        assert painleve.read_csv(p)["seed"].dtype == np.uint64


def test_arrow_reads_as_its_csv_empty_text_and_empty_tables_included(tmp_path):
    """The note of issue 44: an all-empty text column read as text from Arrow but
    as NaN from CSV. Both now give NaN (a CSV cell carries no type); a text column
    of numbers is numbers from both, and a table without rows has float64 columns."""
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
    csv_text = "t,empty_text,mode,numbers_as_text,n,flag\n0.0,,flight,1,1,true\n0.001,,,2,2,false\n0.002,,sliding,3,3,true\n"
    for rows, text in ((3, csv_text), (0, csv_text.split("\n")[0] + "\n")):
        table = pa.table({k: v[:rows] for k, v in columns.items()})
        arrow = tmp_path / f"t{rows}.arrow"
        with pa.OSFile(str(arrow), "wb") as sink, pyarrow.ipc.new_file(sink, table.schema) as w:
            w.write_table(table)
        csv = tmp_path / f"t{rows}.csv"
        csv.write_text(text)
        a, c = painleve.read_arrow(arrow), painleve.read_csv(csv)
        assert_identical(a, reference_read_csv(csv), f"arrow, {rows} rows")
        assert_identical(c, reference_read_csv(csv), f"csv, {rows} rows")
        if rows:
            assert a["empty_text"].dtype == np.float64 and np.isnan(a["empty_text"]).all()
            assert a["numbers_as_text"].dtype == np.int64


def test_a_simulate_folder_reads_alike_from_csv_and_arrow(tmp_path):
    args = FOLDERS["simulate"][1]
    cli("simulate", args + ["--format", "csv"], tmp_path / "csv")
    cli("simulate", args + ["--format", "arrow"], tmp_path / "arrow")
    a, c = painleve.load(tmp_path / "arrow"), painleve.load(tmp_path / "csv")
    for name in ("trace", "events"):
        assert_identical(a.tables[name], dict(c.tables[name]), f"{name}: arrow against csv")


@pytest.mark.parametrize(
    "content, line, words",
    [
        (b"t,z_t\n0.0,1.0\n0.001,1.", 3, "ends inside a row"),
        (b"t,z_t\n0.0,1.0\n0.001\n", 3, "1 cells where the header has 2"),
        (b"t,z_t\n0.0,1.0,2.0\n", 2, "3 cells where the header has 2"),
        (b"t,t\n0.0,1.0\n", 1, "`t` twice"),
        (b"t,mode\n0.0,fl\xffight\n", 2, "not UTF-8"),
        (b"ARROW1\x00\x00\xff\xff\xff\xff", 1, "ends inside a row"),
    ],
)
def test_a_bad_csv_is_a_painleve_error_naming_the_file_and_line(tmp_path, content, line, words):
    p = tmp_path / "trace.csv"
    p.write_bytes(content)
    with pytest.raises(painleve.PainleveError) as e:
        painleve.read_csv(p)
    message = str(e.value)
    assert str(p) in message and f"line {line}:" in message and words in message, message
    assert e.value.exit_code == 2
    # load names the file too.
    with pytest.raises(painleve.PainleveError, match="trace.csv"):
        painleve.load(tmp_path)


def test_a_missing_file_or_a_folder_is_file_not_found(tmp_path):
    for read in (painleve.read_csv, painleve.read_arrow):
        with pytest.raises(FileNotFoundError, match="no file"):
            read(tmp_path / "none.csv")
        with pytest.raises(FileNotFoundError, match="not a file"):
            read(tmp_path)
    with pytest.raises(TypeError):
        painleve.read_csv(3)


def test_a_long_file_read_in_chunks_reads_as_one_pass(tmp_path):
    """A file of several MB is typed in chunks of rows on several threads, the
    chunks' columns then joined: columns whose kind changes far into the file
    (an integer column with a float at the end, flags with one empty cell, text
    after numbers, empties only at the start) read as the former reader read them."""
    n = 120_000
    rows = []
    for i in range(n):
        late = i == n - 7
        rows.append(
            ",".join(
                [
                    repr(i * 1e-3),
                    "2.5" if late else str(i),  # int64 until the end: float64
                    "" if late else ("true" if i % 3 else "false"),  # flags, one empty: text
                    "x" if late else repr(i * 0.5),  # numbers, then text: text
                    "" if i < n // 2 else str(i),  # empty, then integers: float64 with NaN
                    "" if i < n - 3 else "sliding",  # empty, then text
                    str(2**63 + i) if i == n // 3 else str(i),  # one above int64: uint64
                    "",  # never a value: NaN
                    ("flight", "sliding", "sticking")[i % 3],
                ]
            )
        )
    p = tmp_path / "long.csv"
    p.write_text("t,a,b,c,d,e,u,none,mode\n" + "\n".join(rows) + "\n")
    assert p.stat().st_size > 4 << 20, "more than a few chunks"
    got = painleve.read_csv(p)
    assert_identical(got, reference_read_csv(p), "long")
    assert [got[c].dtype.kind for c in got.columns] == ["f", "f", "U", "U", "f", "U", "u", "f", "U"]


def test_a_long_file_the_cli_writes_reads_in_chunks_as_the_former_reader(tmp_path):
    """A file of several MB without text after numbers: read in chunks of lines
    on several threads (the reader's fast path), the chunks' columns joined:
    kinds that change between chunks (an integer column with a float at the end,
    empties first, one value above int64, a negative zero in integers that turn
    floats) read as the former reader read them."""
    n = 120_000
    rows = []
    for i in range(n):
        rows.append(
            ",".join(
                [
                    repr(i * 1e-3),
                    str(i),  # int64
                    "2.5" if i == n - 7 else ("-0" if i == 5 else str(i)),  # int64 until the end: float64, -0.0 at row 5
                    "true" if i % 3 else "false",
                    "" if i < n // 2 else repr(i * 0.25),  # empty, then floats: float64 with NaN
                    "" if i < n - 3 else "sliding",  # empty, then text
                    str(2**63 + i) if i == n // 3 else str(i),  # one above int64: uint64
                    "",  # never a value: NaN
                    ("flight", "sliding", "sticking", "")[i % 4],
                ]
            )
        )
    p = tmp_path / "long.csv"
    p.write_text("t,i,late,flag,gap,e,u,none,mode\n" + "\n".join(rows) + "\n")
    assert p.stat().st_size > 4 << 20, "more than a few chunks"
    got = painleve.read_csv(p)
    assert_identical(got, reference_read_csv(p), "long")
    assert [got[c].dtype.kind for c in got.columns] == ["f", "i", "f", "b", "f", "U", "u", "f", "U"]
    assert np.signbit(got["late"][5]) and got["late"][5] == 0.0
