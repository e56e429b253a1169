"""Shared helpers: the CLI binary (``target/release/sil-host``, or
``$PAINLEVE_SIL_HOST``), running it into a temporary folder, and comparing the
package's results with what the CLI wrote, column by column and key by key."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
from pathlib import Path
from typing import Any, Iterable, List, Optional

import numpy as np
import pytest

import painleve

REPO = Path(__file__).resolve().parents[2]

# Keys that measure the machine (wall-clock and CPU time, rates) or name the
# files written: they differ between any two runs, in process or not.
TIMING_KEYS = {
    "wall_s",
    "realtime_factor",
    "periods_per_s",
    "median_point_wall_s",
    "files",
    "timing",
    "cpu_s",
}


def sil_host() -> Path:
    exe = Path(os.environ.get("PAINLEVE_SIL_HOST", REPO / "target" / "release" / "sil-host"))
    if not exe.is_file():
        pytest.fail(f"{exe} is missing: build it first (cargo build --release -p sil-host) or set PAINLEVE_SIL_HOST")
    return exe


def cli(command: str, args: Iterable[str], out: Optional[Path] = None, check: bool = True) -> subprocess.CompletedProcess:
    """Runs ``sil-host <command> <args> [--out out] --json`` from the repository
    root (scenario paths are relative to it)."""
    argv: List[str] = [str(sil_host()), command, *args]
    if out is not None:
        argv += ["--out", str(out)]
    argv.append("--json")
    p = subprocess.run(argv, cwd=REPO, capture_output=True, text=True, timeout=600)
    if check and p.returncode != 0:
        raise AssertionError(f"{' '.join(argv)} exited {p.returncode}:\n{p.stderr}")
    return p


def cli_error(command: str, args: Iterable[str]) -> tuple:
    """The CLI's error for bad input: (message after ``error: ``, exit code). A
    command-line parser's message is its first paragraph (the usage and help
    lines after it name the command line's flags)."""
    p = cli(command, args, check=False)
    assert p.returncode != 0, f"sil-host {command} {' '.join(args)} accepted the input"
    text = p.stderr.rstrip()
    assert text.startswith("error: "), text
    return text[len("error: ") :].split("\n\n")[0].rstrip(), p.returncode


def assert_raises_like_cli(call, command: str, argv: Iterable[str]) -> None:
    """``call()`` fails as ``sil-host command argv`` does: a ``PainleveError`` with
    the CLI's exit code and its message in the call's terms (``--sample-dt`` is
    ``sample_dt``: ``painleve._args.pythonic``), or, for a choice not among an
    option's choices, a ``ValueError`` raised in Python before the experiment runs
    that lists the same choices as the CLI."""
    import painleve
    from painleve._args import pythonic

    message, code = cli_error(command, argv)
    with pytest.raises(ValueError) as e:
        call()
    if isinstance(e.value, painleve.PainleveError):
        assert (str(e.value), e.value.exit_code) == (pythonic(message), code)
        assert "--" not in str(e.value), f"CLI syntax in {e.value}"
        return
    choices = re.search(r"\[possible values: ([^\]]*)\]", message)
    assert code == 2 and choices, f"the CLI refuses it as a choice: {message}"
    for c in choices.group(1).split(", "):
        assert repr(c) in str(e.value), f"{c!r} not in {e.value}"


def assert_columns_equal(a: np.ndarray, b: np.ndarray, where: str) -> None:
    """Exact equality (NaN equal to NaN); a text column against a numeric one
    (a text column whose cells all read as numbers) compares the numbers."""
    assert a.shape == b.shape, f"{where}: {a.shape} != {b.shape}"
    text = (a.dtype.kind in "US", b.dtype.kind in "US")
    if text[0] != text[1]:
        a, b = (a.astype(np.float64), b.astype(np.float64))
    elif not text[0]:
        assert a.dtype.kind == b.dtype.kind, f"{where}: dtype {a.dtype} != {b.dtype}"
    if a.dtype.kind == "f":
        eq = (a == b) | (np.isnan(a) & np.isnan(b))
    else:
        eq = a == b
    if not np.all(eq):
        bad = np.flatnonzero(~eq)
        i = int(bad[0])
        raise AssertionError(f"{where}: {bad.size} rows differ, the first at row {i}: {a[i]!r} != {b[i]!r}")


def assert_tables_equal(mine: painleve.Table, cli_table: painleve.Table, skip: Iterable[str] = ()) -> None:
    """Same columns in the same order, with the same values (``skip``: columns
    measuring time)."""
    assert mine.columns == cli_table.columns, f"{mine.name}: columns {mine.columns} != {cli_table.columns}"
    assert mine.nrows == cli_table.nrows, f"{mine.name}: {mine.nrows} rows != {cli_table.nrows}"
    for c in mine.columns:
        if c in skip:
            continue
        assert_columns_equal(mine[c], cli_table[c], f"{mine.name}.{c}")


def assert_docs_equal(mine: Any, theirs: Any, where: str = "summary", ignore: Iterable[str] = TIMING_KEYS) -> None:
    """Two JSON documents equal, floats exactly (NaN is JSON null on both sides),
    except the keys in ``ignore`` at any depth."""
    ignore = set(ignore)
    if isinstance(mine, dict) and isinstance(theirs, dict):
        a = {k: v for k, v in mine.items() if k not in ignore}
        b = {k: v for k, v in theirs.items() if k not in ignore}
        assert list(a) == list(b), f"{where}: keys {list(a)} != {list(b)}"
        for k in a:
            assert_docs_equal(a[k], b[k], f"{where}.{k}", ignore)
    elif isinstance(mine, list) and isinstance(theirs, list):
        assert len(mine) == len(theirs), f"{where}: {len(mine)} items != {len(theirs)}"
        for i, (x, y) in enumerate(zip(mine, theirs)):
            assert_docs_equal(x, y, f"{where}[{i}]", ignore)
    elif isinstance(mine, float) and isinstance(theirs, float) and math.isnan(mine) and math.isnan(theirs):
        pass
    else:
        assert mine == theirs and type(mine) is type(theirs), f"{where}: {mine!r} != {theirs!r}"


def json_of(p: subprocess.CompletedProcess) -> Any:
    return json.loads(p.stdout)


@pytest.fixture
def out(tmp_path: Path) -> Path:
    """A fresh output folder for the CLI."""
    return tmp_path / "out"
