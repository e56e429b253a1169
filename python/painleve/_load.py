"""``painleve.load``: any output folder ``sil-host`` writes, read back: its
tables (CSV, Arrow and MCAP) by the compiled module's readers (Rust, without
the GIL; no pandas, pyarrow or mcap package needed), and JSON and text files by
the standard library."""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path
from typing import Any, Dict, List, Optional, Set, Union

import numpy as np

from ._painleve import read_arrow as _read_arrow
from ._painleve import read_csv as _read_csv
from ._painleve import read_mcap as _read_mcap
from ._painleve import read_text as _read_text
from ._result import Result, Table, describe_violations

__all__ = ["load", "read_arrow", "read_csv", "read_mcap"]


def _table(columns: Dict[str, Any], name: str) -> Table:
    """A table from the compiled readers: a text column comes as ``(values,
    codes)``, its distinct values and each row's index into them."""
    for key, col in columns.items():
        if isinstance(col, tuple):
            values, codes = col
            columns[key] = np.array(values, dtype=str)[codes]
    return Table(columns, name)


def _file(path: Union[str, "os.PathLike[str]"]) -> Path:
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"no file {p}" if not p.exists() else f"{p} is not a file")
    return p


def read_csv(path: Union[str, "os.PathLike[str]"]) -> Table:
    """One CSV table the CLI wrote (``trace.csv``, ``events.csv``, ``sweep.csv``,
    ...), as a :class:`Table` of NumPy arrays of shape ``(nrows,)``, in the
    file's column order, units as the CLI writes them (SI; see each function's
    docstring for its columns).

    Each column has the type the CLI declares for it (the file's header names its
    table; :func:`painleve._painleve.declared_tables` lists them): ``float64`` for
    a float (an empty cell, an absent optional value, is NaN; an optional count
    such as ``classes.csv``'s ``period`` is ``float64`` too), ``int64`` for an
    integer, ``bool`` for a flag, and text (a NumPy ``str`` array, ``""`` for an
    empty cell) for text and named choices. Every float has the exact bits of its
    shortest round-trip digits. The same table read from its Arrow file
    (:func:`read_arrow`) has the same columns, types and values.

    A file whose header is no table of the CLI is read with the types arrow-csv
    infers (``int64``, ``float64``, ``bool``, text; a column without a value is
    ``float64`` NaN, an integer column with an empty cell ``float64``, a flag
    column with an empty cell text). An empty file is a table without columns.

    Reading is done in Rust (the ``tables`` crate, with arrow-csv, without the
    GIL); the float and integer arrays share the reader's Arrow memory (no copy).

    Raises:
        FileNotFoundError: ``path`` is not a file.
        PainleveError: the file is not a table the CLI writes: not UTF-8, ends
            inside a row (a file cut off while it was written), has a row with
            another number of cells than its header, a cell not of its column's
            type, or names a column twice. The message names the file and the line.
    """
    p = _file(path)
    return _table(_read_csv(os.fspath(p)), p.stem)


def read_arrow(path: Union[str, "os.PathLike[str]"]) -> Table:
    """One Arrow IPC file the CLI wrote (``--format arrow``: ``simulate``'s
    ``trace.arrow`` and ``events.arrow``, ``run``'s and ``pil``'s ``trace.arrow``;
    the whole batches of a killed run's file, cut off before its footer; an
    Arrow IPC stream too), as a :class:`Table` of NumPy arrays of shape ``(nrows,)``,
    each column of the file's own type: ``Float64`` as ``float64`` (its exact
    bits), ``Int64`` as ``int64``, ``Boolean`` as ``bool``, ``Utf8`` as text
    (a null as NaN or ``""``). For a table the CLI wrote these are the types
    :func:`read_csv` gives its CSV. The float and integer arrays share the
    reader's Arrow memory, not copied. pandas (``pandas.read_feather``, with
    pyarrow) and polars (``polars.read_ipc``) read the same files directly.

    Raises:
        FileNotFoundError: ``path`` is not a file.
        PainleveError: the file cannot be read, is not an Arrow IPC file (or was
            cut off before its footer), or holds a column of another type than
            Float64, Int64, Boolean or Utf8 (or a null integer or flag).
    """
    p = _file(path)
    return _table(_read_arrow(os.fspath(p)), p.stem)


def read_mcap(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Table]:
    """The tables of an MCAP file the CLI wrote (``--format mcap``:
    ``trace.mcap``; ``simulate``: tables ``trace`` and ``events``, ``run`` and
    ``pil``: ``trace``), as ``{name: Table}`` with the columns, types and values
    :func:`read_csv` gives for the same tables as CSV: floats with their exact
    bits (the messages' protobuf ``double`` fields carry them, NaN and
    infinities too), integers as
    ``int64``, flags as ``bool``, text as ``str`` (the types of the tables'
    declarations, which the file's metadata records carry). Row ``k`` is the ``k``-th
    message of each of the table's channels; the columns' order comes from the
    file's ``painleve.table.<name>`` metadata records. A file cut off (a run
    killed while writing) gives its whole chunks, and of each table the rows
    whose every message is there. Read by the package's own Rust reader (the
    ``tables`` crate's, chunk by chunk; no ``mcap`` Python package needed);
    Foxglove opens the file directly.

    Raises:
        FileNotFoundError: ``path`` is not a file.
        PainleveError: the file cannot be read, is not MCAP, holds no table
            of sil-host, a table's channel is not protobuf (a file written
            before issue 55, whose tables were JSON), or a message is not the
            one its channel's schema describes.
    """
    p = _file(path)
    return {name: _table(cols, name) for name, cols in _read_mcap(os.fspath(p))}


# Where each command's summary keeps the validity counters summed over its runs.
_VALIDITY_AT = {
    "simulate": ("validity",),
    "run": ("validity",),
    "pil": ("validity",),
    "poincare": ("validity",),
    "zmax": ("validity",),
    "sweep": ("results", "validity"),
    "sensitivity": ("study", "validity"),
}


def _detect(files: Set[str], summary: Any, tables: Optional[Dict[str, Table]] = None) -> str:
    """The command that wrote a folder, from its files (and the tables of an MCAP file)."""
    if isinstance(summary, dict) and "periods_replayed" in summary:
        # `sil-host replay --out`: the replayed answers (frames) and the comparison.
        return "replay"
    if "report.json" in files:
        return "report"
    if "admissible.json" in files:
        return "admissible"
    if "modes.csv" in files:
        return "modes"
    if "sweep.csv" in files or "sweep.json" in files:
        return "sweep"
    if "section.csv" in files or "classes.csv" in files:
        return "poincare"
    if "zmax.csv" in files:
        return "zmax"
    if "sensitivity.csv" in files:
        return "sensitivity"
    if "events.csv" in files or "events.arrow" in files or ("trace.mcap" in files and "events" in (tables or {})):
        return "simulate"
    if "trace.csv" in files or "trace.arrow" in files or "trace.mcap" in files:
        return "pil" if isinstance(summary, dict) and summary.get("pil") else "run"
    return "unknown"


def _validity(command: str, summary: Any) -> Optional[Dict[str, Any]]:
    node = summary
    for key in _VALIDITY_AT.get(command, ()):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node if command in _VALIDITY_AT and isinstance(node, dict) else None


def _failure(command: str, summary: Any) -> Optional[str]:
    """What a folder's summary says about a failure (the CLI exited with 1)."""
    if not isinstance(summary, dict):
        return None
    status = summary.get("status")
    if status in ("failed", "interrupted"):
        return summary.get("error") or f"{command} {status}"
    return None


def _check_partial(root: Path, files: Set[str]) -> None:
    """Raises (nothing finished) or warns (finished results beside them) about a
    killed run's ``NAME.partial`` files in ``root``."""
    partial = sorted(f for f in files if f.endswith(".partial"))
    if not partial:
        return
    finished = [f for f in files if not f.endswith(".partial") and Path(f).suffix in (".csv", ".arrow", ".mcap", ".json")]
    how = (
        "read them with painleve.read_csv / read_arrow / read_mcap "
        "(a cut file reads as its whole rows), or run the command again"
    )
    if not finished:
        raise ValueError(
            f"{root}: the folder of a run that was killed before it finished: only partial files "
            f"({', '.join(partial)}), no summary; {how}"
        )
    warnings.warn(
        f"{root}: partial files of a killed run left out: {', '.join(partial)}; {how}",
        stacklevel=3,
    )


def load(path: Union[str, "os.PathLike[str]"]) -> Result:
    """Reads an output folder of ``sil-host`` (any command's ``--out DIR``).

    Every ``*.csv`` (and ``*.arrow``, :func:`read_arrow`) becomes a :class:`Table`
    named as the file without its extension, every table of a ``*.mcap``
    (:func:`read_mcap`) one named as in the file
    (``trace``, ``events``, ``sweep``, ``runs``, ``section``, ``classes``,
    ``zmax``, ``trials``, ``modes``, ``sensitivity``), ``summary.json`` the
    result's ``summary`` (``admissible.json`` for ``admissible``,
    ``report.json`` for ``report``), every other ``*.json`` an entry of
    ``extras`` (``classes`` of ``poincare``, ``sweep`` of a sweep's spec), and
    text files (``defmt.log``, ``report.md``) entries of ``extras`` as strings.
    A report's experiment folders are loaded too, into ``extras["experiments"]``
    (``{id: Result}``). SVG figures are listed in ``extras["figures"]`` (paths); each has its PDF beside it.

    The command is recognised from the files; the validity counters come from the
    summary where the command keeps them (``validity``, ``results.validity`` of a
    sweep, ``study.validity`` of a sensitivity study), ``violations`` in the
    CLI's words, and ``failure`` from a summary whose ``status`` is ``failed``
    or ``interrupted``.

    A killed run (SIGKILL, a power cut) leaves its streamed tables as
    ``NAME.partial`` (``trace.csv.partial``, ``trace.mcap.partial``: the rows
    flushed before it died) and no summary: ``load`` then raises, naming them
    and how to read them; a folder that also holds finished results loads, with
    a warning naming the partial files it leaves out.

    Raises:
        FileNotFoundError: ``path`` is not a folder.
        ValueError: the folder holds only a killed run's partial files (the
            message names them).
        PainleveError: a table cannot be read (:func:`read_csv`,
            :func:`read_arrow`; the message names the file), or a JSON
            document or a log is over its bound (64 MiB, 1 GiB; issue 80).
        ValueError: a JSON file does not parse (the message names it).
    """
    root = Path(path)
    if not root.is_dir():
        raise FileNotFoundError(f"no output folder {root}")
    entries = sorted(p for p in root.iterdir() if not p.name.startswith("."))
    files = {p.name for p in entries if p.is_file()}
    _check_partial(root, files)
    tables: Dict[str, Table] = {}
    docs: Dict[str, Any] = {}
    extras: Dict[str, Any] = {}
    figures: List[str] = []
    for p in entries:
        if not p.is_file():
            continue
        if p.suffix == ".csv":
            tables[p.stem] = read_csv(p)
        elif p.suffix == ".arrow":
            tables[p.stem] = read_arrow(p)
        elif p.suffix == ".mcap":
            tables.update(read_mcap(p))
        elif p.suffix == ".json":
            try:
                # Bounded (issue 80): a regular file of at most 64 MiB.
                docs[p.stem] = json.loads(_read_text(os.fspath(p), "document"))
            except json.JSONDecodeError as e:
                raise ValueError(f"{p}: not JSON: {e}") from e
        elif p.suffix == ".svg":
            figures.append(str(p))
        elif p.suffix in (".log", ".md", ".txt"):
            extras[p.stem] = _read_text(os.fspath(p), "log")
    # The run's own table first (the default of ``to_pandas()`` and friends):
    # ``trace`` before ``frames`` (a closed-loop run's wire record), which sorts first by name.
    tables = dict(sorted(tables.items(), key=lambda kv: kv[0] == "frames"))
    main = "summary"
    if "summary" not in docs:
        main = "admissible" if "admissible" in docs else "report" if "report" in docs else main
    summary = docs.pop(main, None)
    command = _detect(files, summary, tables)
    if command == "report":
        summary = docs.pop("report", summary)
        extras["experiments"] = {p.name: load(p) for p in entries if p.is_dir() and any(q.is_file() for q in p.iterdir())}
    extras.update(docs)
    if figures:
        extras["figures"] = figures
    validity = _validity(command, summary)
    failure = _failure(command, summary)
    return Result(
        command=command,
        summary=summary,
        tables=tables,
        extras=extras,
        validity=validity,
        violations=describe_violations(validity),
        failure=failure,
        exit_code=1 if failure else 0,
        path=str(root),
    )
