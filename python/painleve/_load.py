"""``painleve.load``: any output folder ``sil-host`` writes, read back: its
tables (CSV and Arrow) by the compiled module's readers (Rust, without the GIL;
no pandas or pyarrow needed), the tables of ``--format mcap`` with the ``mcap``
package, if installed, and JSON and text files by the standard library."""

from __future__ import annotations

import json
import os
import struct
import warnings
from pathlib import Path
from typing import Any, Dict, List, Optional, Set, Union

import numpy as np

from ._painleve import read_arrow as _read_arrow
from ._painleve import read_csv as _read_csv
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

    Each column is typed from its cells (the typing rule, the same for Arrow):

    - ``bool`` when every cell is ``true`` or ``false``;
    - ``int64`` when every cell is an integer (``uint64`` when one is above
      2**63 - 1 and none is negative);
    - ``float64`` when every cell is a number or empty, an empty cell NaN (so an
      integer column with an empty cell is ``float64``); every float has the
      exact bits of its shortest round-trip digits (what Python's ``float`` reads);
    - ``float64`` NaN when no cell holds a value: a column of empty cells, text
      columns included, and every column of a file with a header and no rows
      (a CSV cell carries no type);
    - text (a NumPy ``str`` array, ``""`` for an empty cell) otherwise.

    These are ``pandas.read_csv``'s types for the CLI's files. Reading is done in
    Rust (``tables::read``, in chunks of lines read and typed on
    several threads, without the GIL; the float, integer and flag arrays are the
    reader's memory, not copied): 40 to 60 times as fast as the former pure-Python
    reader, and faster than ``pandas.read_csv`` on the CLI's traces (1.15 to 1.7
    times its speed on a 300 000-row, 66 MB trace, 1.5 times on a 62 000-row one;
    docs/python.md, "Reading tables"). An empty file is a table without columns;
    blank lines are skipped.

    Raises:
        FileNotFoundError: ``path`` is not a file.
        PainleveError: the file is not a table the CLI writes: not UTF-8, ends
            inside a row (a file cut off while it was written), has a row with
            another number of cells than its header, or names a column twice.
            The message names the file and the line.
    """
    p = _file(path)
    return _table(_read_csv(os.fspath(p)), p.stem)


def read_arrow(path: Union[str, "os.PathLike[str]"]) -> Table:
    """One Arrow IPC table the CLI wrote (``simulate --format arrow``:
    ``trace.arrow``, ``events.arrow``, Arrow IPC files; ``run`` and ``pil``
    ``--format arrow``: ``trace.arrow``, an Arrow IPC stream, whole batches of
    one cut off), as a :class:`Table` of NumPy arrays of shape ``(nrows,)``
    with the columns, types and values :func:`read_csv` gives for the same table
    as CSV (floats with their exact bits; a text column is typed by
    :func:`read_csv`'s rule, so one of empty strings is ``float64`` NaN, and
    every column of a table without rows is an empty ``float64`` array). pandas
    (``pandas.read_feather``, with pyarrow) and polars (``polars.read_ipc``;
    ``polars.read_ipc_stream`` for a stream) read the same files directly, with
    the file's own types.

    Raises:
        FileNotFoundError: ``path`` is not a file.
        PainleveError: the file cannot be read, is not an Arrow IPC file (or was
            cut off before its footer), or holds a column of another type than
            Float64, Int64, Boolean or Utf8.
    """
    p = _file(path)
    return _table(_read_arrow(os.fspath(p)), p.stem)


_MCAP_PACKAGE = "mcap==1.6.0"

# MCAP's framing (the MCAP specification, "Records"): 8 magic bytes, then records of a
# 1-byte opcode, a little-endian u64 body length and the body; the Footer (opcode 0x02)
# is followed by the magic again.
_MCAP_MAGIC_LEN = 8
_MCAP_RECORD_HEAD = struct.Struct("<BQ")
_MCAP_FOOTER = 0x02


def _mcap_whole_records_end(f: Any) -> int:
    """The byte offset where the last whole record of the MCAP file ``f`` (open
    for reading, binary) ends: its size when the file is complete, else the end
    of the last record whose 9-byte head and body are both in the file (a file
    cut off while its run was killed ends anywhere, inside a record's head or
    body). Reads only the records' heads; leaves ``f`` at offset 0."""
    size = os.fstat(f.fileno()).st_size
    pos = _MCAP_MAGIC_LEN
    while pos + _MCAP_RECORD_HEAD.size <= size:
        f.seek(pos)
        opcode, length = _MCAP_RECORD_HEAD.unpack(f.read(_MCAP_RECORD_HEAD.size))
        end = pos + _MCAP_RECORD_HEAD.size + length
        if end > size:
            break
        pos = end
        if opcode == _MCAP_FOOTER and pos + _MCAP_MAGIC_LEN <= size:
            pos += _MCAP_MAGIC_LEN  # the closing magic, when it is whole
            break
    f.seek(0)
    return min(pos, size)


class _Prefix:
    """The first ``end`` bytes of the binary file ``f`` as a stream with
    ``read(n)``: what the ``mcap`` package's StreamReader is given, so that a
    cut-off file ends, for it, at a record boundary (its ``EndOfFile``) rather
    than inside a record (a ``struct.error`` or a zstd error)."""

    def __init__(self, f: Any, end: int) -> None:
        self._f = f
        self._left = end

    def read(self, n: int = -1) -> bytes:
        n = self._left if n is None or n < 0 else min(n, self._left)
        data = self._f.read(n)
        self._left -= len(data)
        return data


def read_mcap(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Table]:
    """The tables of an MCAP file the CLI wrote (``--format mcap``:
    ``trace.mcap``; ``simulate``: tables ``trace`` and ``events``, ``run`` and
    ``pil``: ``trace``), as ``{name: Table}`` with the columns, types and values
    :func:`read_csv` gives for the same tables as CSV: floats with their exact
    bits (the file's JSON numbers are the CSV's shortest round-trip digits; a
    JSON ``null``, written for NaN and infinities, reads as NaN), integers as
    ``int64``, flags as ``bool``, text as ``str`` (a text column whose cells are
    all empty as NaN, as :func:`read_csv` reads it). Row ``k`` is the ``k``-th
    message of each of the table's channels; the columns' order comes from the
    file's ``painleve.table.<name>`` metadata records. A file cut off (a run
    killed while writing) gives its whole chunks, and of each table the rows
    whose every message is there. Needs the ``mcap`` package (``pip install
    mcap``); Foxglove opens the file directly.

    Raises:
        ImportError: the ``mcap`` package is not installed (the message names
            it and the other ways to read the trace).
        PainleveError: the file cannot be read, is not MCAP, holds no table
            of sil-host, or a message is not the JSON object its table describes.
    """
    from ._painleve import PainleveError

    path = Path(path)
    try:
        from mcap.exceptions import EndOfFile, McapError
        from mcap.records import Channel, Message, Metadata
        from mcap.stream_reader import StreamReader
    except ImportError as e:
        raise ImportError(
            f"{path}: reading an MCAP trace needs the Python package `mcap` (pip install {_MCAP_PACKAGE}; "
            "it brings zstandard for the zstd chunks); or open it in Foxglove, or write the tables "
            "with --format csv or --format arrow, which painleve.load reads without it"
        ) from e
    specs: Dict[str, Dict[str, List[str]]] = {}
    topics: Dict[int, str] = {}
    messages: Dict[str, List[bytes]] = {}
    try:
        with open(path, "rb") as f:
            try:
                for record in StreamReader(_Prefix(f, _mcap_whole_records_end(f))).records:
                    if isinstance(record, Metadata) and record.name.startswith("painleve.table."):
                        spec = {k: v.split(",") if v else [] for k, v in record.metadata.items()}
                        specs[record.name[len("painleve.table.") :]] = spec
                    elif isinstance(record, Channel):
                        topics[record.id] = record.topic
                    elif isinstance(record, Message):
                        topic = topics.get(record.channel_id, "")
                        got = messages.setdefault(topic, [])
                        if record.sequence != len(got):
                            raise PainleveError(f"{path}: {topic}: message {len(got)} has sequence number {record.sequence}")
                        got.append(record.data)
            except EndOfFile:
                pass  # cut off while writing: the records up to the cut
    except OSError as e:
        raise PainleveError(f"{path}: {e}") from e
    except (McapError, struct.error) as e:
        raise PainleveError(f"{path}: not an MCAP file: {e!r}") from e
    if not specs:
        raise PainleveError(f"{path}: no table in it (no painleve.table.* metadata record): not written by sil-host --format mcap")
    tables: Dict[str, Table] = {}
    for name, spec in specs.items():
        columns, kinds, chans = spec.get("columns", []), spec.get("kinds", []), spec.get("topics", [])
        if len(columns) != len(kinds):
            raise PainleveError(f"{path}: table {name}: {len(columns)} columns but {len(kinds)} kinds")
        n = min((len(messages.get(t, [])) for t in chans), default=0)
        try:
            objects = [[json.loads(m) for m in messages.get(t, [])[:n]] for t in chans]
        except ValueError as e:
            raise PainleveError(f"{path}: table {name}: a message is not JSON: {e}") from e
        out: Dict[str, Any] = {}
        for col, kind in zip(columns, kinds):
            source = next((o for o in objects if o and col in o[0]), None)
            try:
                cells = [o[col] for o in source] if source is not None else []
                if kind == "f64":
                    out[col] = np.array([np.nan if c is None else float(c) for c in cells], dtype=np.float64)
                elif kind == "int":
                    out[col] = np.array([int(c) for c in cells], dtype=np.int64)
                elif kind == "bool":
                    out[col] = np.array([bool(c) for c in cells], dtype=bool)
                elif cells and all(c == "" for c in cells):
                    out[col] = np.full(len(cells), np.nan)
                else:
                    out[col] = np.array([str(c) for c in cells], dtype=str)
            except (KeyError, TypeError, ValueError) as e:
                raise PainleveError(f"{path}: table {name}: column `{col}` is not {kind} in every message: {e!r}") from e
            if len(out[col]) != n:
                raise PainleveError(f"{path}: table {name}: column `{col}` is in no message of {', '.join(chans)}")
        tables[name] = Table(out, name)
    return tables


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
    if "trace.csv" in files or "trace.mcap" in files:
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
    (:func:`read_mcap`, with the ``mcap`` package) one named as in the file
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
            :func:`read_arrow`; the message names the file).
        ValueError: a JSON file does not parse (the message names it).
        ImportError: the folder has an MCAP trace and the ``mcap`` package is
            not installed (:func:`read_mcap`).
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
                docs[p.stem] = json.loads(p.read_text(encoding="utf-8"))
            except json.JSONDecodeError as e:
                raise ValueError(f"{p}: not JSON: {e}") from e
        elif p.suffix == ".svg":
            figures.append(str(p))
        elif p.suffix in (".log", ".md", ".txt"):
            extras[p.stem] = p.read_text(encoding="utf-8", errors="replace")
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
