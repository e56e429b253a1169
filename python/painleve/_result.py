"""Results: :class:`Table` (named NumPy columns) and :class:`Result` (a command's
summary document, its tables, its validity counters and how it ended)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, Iterator, List, Mapping, Optional, Union, cast

import numpy as np

from ._painleve import PainleveError, recording_of_run, write_file

__all__ = ["Table", "Result", "PainleveWarning", "describe_violations"]


class PainleveWarning(UserWarning):
    """A call that finished but would make ``sil-host`` exit with code 1: a run
    that failed part way (its results up to then are returned), a belt speed
    that failed, or (only with ``strict=True``, which raises instead) a model
    violation. The message is the CLI's."""


def _column(values: Any) -> np.ndarray:
    """A column as a 1-D NumPy array; text columns (lists of ``str``) become NumPy
    string arrays."""
    if isinstance(values, np.ndarray):
        return values
    if isinstance(values, list) and (not values or isinstance(values[0], str)):
        return np.array(values, dtype=str)
    return np.asarray(values)


class Table(Dict[str, np.ndarray]):
    """One table of a result: ``{column name: NumPy array of shape (n,)}``, every column of
    the same length, in the order of the CSV file the CLI writes for it (the
    table ``trace`` is ``trace.csv``).

    Column types are the table's declaration's, whatever the cells: ``float64``
    for numbers (NaN for an empty cell or an absent optional value; an optional
    count is ``float64`` too), ``int64`` for integer counts, ``bool`` for flags,
    NumPy ``str`` arrays for text and named choices (``""`` for an empty cell).
    A table computed in process, read from the CLI's CSV and from its Arrow file
    has the same columns, types and values.
    Units are SI (s, m, m/s, N, N m, rad, rad/s) unless a column's name says
    otherwise (``theta1_deg``); each function's docstring lists its columns.
    """

    def __init__(self, columns: Optional[Mapping[str, Any]] = None, name: str = "") -> None:
        super().__init__()
        self.name = name
        for key, values in (columns or {}).items():
            self[key] = _column(values)

    @property
    def columns(self) -> List[str]:
        """The column names, in order."""
        return list(self.keys())

    @property
    def nrows(self) -> int:
        """The number of rows (0 for a table without columns)."""
        return len(next(iter(self.values()))) if self else 0

    def to_pandas(self) -> Any:
        """The table as a ``pandas.DataFrame`` (needs pandas installed)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Table.to_pandas needs pandas: pip install pandas") from e
        return pd.DataFrame({k: v for k, v in self.items()})

    def to_polars(self) -> Any:
        """The table as a ``polars.DataFrame`` (needs polars installed)."""
        try:
            import polars as pl
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Table.to_polars needs polars: pip install polars") from e
        return pl.DataFrame({k: v for k, v in self.items()})

    def __repr__(self) -> str:
        cols = ", ".join(self.columns[:8]) + (", ..." if len(self) > 8 else "")
        return f"<Table {self.name!r}: {self.nrows} rows x {len(self)} columns [{cols}]>"

    def _shown_rows(self, limit: int) -> List[Optional[int]]:
        """The row indices a printout shows: all of them up to ``limit``, else the
        first ``limit - 4`` and the last 3 with ``None`` for the elided middle."""
        n = self.nrows
        if n <= limit:
            return list(range(n))
        head = limit - 4
        return list(range(head)) + [None] + list(range(n - 3, n))

    def _cells(self, limit: int) -> List[List[str]]:
        """The shown rows' cells as text (numbers to 6 significant digits)."""
        rows: List[List[str]] = []
        for i in self._shown_rows(limit):
            if i is None:
                rows.append(["..."] * len(self))
            else:
                rows.append([_cell(col[i]) for col in self.values()])
        return rows

    def __str__(self) -> str:
        """The table as aligned text: a title line, the column names, and its rows
        (at most 20: the first 16 and the last 3 of a longer one)."""
        title = f"{self.name or 'table'}: {self.nrows} rows x {len(self)} columns"
        if not self:
            return title
        rows = [self.columns] + self._cells(20)
        widths = [max(len(r[j]) for r in rows) for j in range(len(self))]
        lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in rows]
        return "\n".join([title] + lines)

    def _repr_html_(self) -> str:
        """The table as HTML for notebooks (at most 20 rows, as :meth:`__str__`)."""
        import html

        head = "".join(f"<th>{html.escape(c)}</th>" for c in self.columns)
        body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in self._cells(20))
        title = html.escape(f"{self.name or 'table'}: {self.nrows} rows x {len(self)} columns")
        return f"<p><b>{title}</b></p><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _cell(v: Any) -> str:
    """One cell as text: floats to 6 significant digits, the rest as they are."""
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.6g}"
    return str(v)


_VIOLATION_WORDS = (
    ("energy_gains", "energy-creating impact", "energy-creating impacts"),
    ("cone_violations", "friction-cone violation", "friction-cone violations"),
    ("integrator_failures", "integrator failure", "integrator failures"),
)


def describe_violations(validity: Optional[Mapping[str, Any]]) -> Optional[str]:
    """The model violations of validity counters in words, as ``sil-host`` prints
    them (``"2 friction-cone violations, 1 integrator failure"``); ``None`` when
    there are none (fallbacks and Zeno stops are modelling rules, not
    violations) or no counters."""
    if not validity:
        return None
    parts = []
    for key, one, many in _VIOLATION_WORDS:
        n = int(validity.get(key) or 0)
        if n > 0:
            parts.append(f"{n} {one if n == 1 else many}")
    return ", ".join(parts) or None


def _intervals(doc: Mapping[str, Any]) -> Table:
    """The admissible intervals of ``admissible.json`` as a table (paper Table II)."""
    cols: Dict[str, List[Any]] = {"direction": [], "branch": [], "lo_m": [], "hi_m": []}
    for direction in ("z_r_dot_positive", "z_r_dot_negative"):
        for branch in ("elbow_up", "elbow_down"):
            for lo, hi in (doc.get(direction) or {}).get(branch) or []:
                cols["direction"].append(direction)
                cols["branch"].append(branch)
                cols["lo_m"].append(float(lo))
                cols["hi_m"].append(float(hi))
    return Table(
        {
            "direction": np.array(cols["direction"], dtype=str),
            "branch": np.array(cols["branch"], dtype=str),
            "lo_m": np.array(cols["lo_m"], dtype=np.float64),
            "hi_m": np.array(cols["hi_m"], dtype=np.float64),
        },
        "intervals",
    )


class Result:
    """What a command computed (or, from :func:`painleve.load`, wrote).

    Attributes:
        command: the ``sil-host`` command (``"simulate"``, ``"sweep"``, ...).
        summary: the command's summary document, the dict of its ``summary.json``
            (``admissible.json`` for ``admissible``, the ``--json`` document for
            ``modes``, which writes no summary file); in memory ``files`` is empty.
        tables: ``{name: Table}``, named as the CLI's CSV files without ``.csv``.
        extras: everything else: other JSON documents (``classes`` of
            ``poincare``), curves (``b_zero`` of ``modes``), time histories
            (``limit_traces`` of ``zmax``), the scenario run (``scenario`` of ``run``).
        validity: the validity counters summed over everything simulated
            (``energy_gains``, ``newton_fallbacks``, ``poisson_fallbacks``,
            ``cone_violations``, ``zeno_stops``, ``integrator_failures``), or
            ``None`` for the analyses that simulate nothing (``admissible``, ``modes``).
        violations: the model violations in words, ``None`` when there are none.
        failure: the CLI's error message when it would exit with code 1 after
            writing its files (a run that failed part way, with ``strict`` a
            violation), else ``None``.
        exit_code: the CLI's exit code for this result: 0, or 1 with a failure.
        path: the folder a loaded result was read from (``None`` in memory).
    """

    def __init__(
        self,
        command: str,
        summary: Any,
        tables: Optional[Mapping[str, Mapping[str, Any]]] = None,
        extras: Optional[Mapping[str, Any]] = None,
        validity: Optional[Mapping[str, Any]] = None,
        violations: Optional[str] = None,
        failure: Optional[str] = None,
        exit_code: int = 0,
        path: Optional[str] = None,
    ) -> None:
        self.command = command
        self.summary = summary
        self.tables: Dict[str, Table] = {k: v if isinstance(v, Table) else Table(v, k) for k, v in (tables or {}).items()}
        self.extras: Dict[str, Any] = dict(extras or {})
        self.validity = dict(validity) if validity is not None else None
        self.violations = violations
        self.failure = failure
        self.exit_code = exit_code
        self.path = path
        if command == "admissible" and "intervals" not in self.tables and isinstance(summary, dict):
            self.tables["intervals"] = _intervals(summary)

    @classmethod
    def _from_raw(cls, raw: Mapping[str, Any]) -> "Result":
        extras = dict(raw["extras"])
        if "limit_traces" in extras:
            extras["limit_traces"] = {k: Table(v, k) for k, v in extras["limit_traces"].items()}
        return cls(
            command=raw["command"],
            summary=raw["summary"],
            tables=raw["tables"],
            extras=extras,
            validity=raw["validity"],
            violations=raw["violations"],
            failure=raw["failure"],
            exit_code=int(raw["exit_code"]),
        )

    @property
    def valid(self) -> bool:
        """``True`` when the result has no model violation."""
        return self.violations is None

    def check(self) -> "Result":
        """Raises :class:`painleve.PainleveError` (with ``exit_code`` and this
        result as ``result``) when the CLI would have exited with an error;
        returns the result otherwise."""
        if self.failure is not None:
            err = PainleveError(self.failure)
            err.exit_code = self.exit_code or 1
            err.result = self
            raise err
        return self

    def __getitem__(self, name: str) -> Table:
        return self.tables[name]

    def __getattr__(self, name: str) -> Table:
        tables = self.__dict__.get("tables", {})
        if name in tables:
            return cast(Table, tables[name])
        raise AttributeError(f"{type(self).__name__} of {self.__dict__.get('command')!r} has no attribute or table {name!r}")

    def __iter__(self) -> Iterator[str]:
        return iter(self.tables)

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self.tables))

    def _table(self, table: Optional[str]) -> Table:
        if table is None:
            if not self.tables:
                raise KeyError(f"the {self.command} result has no table")
            return next(iter(self.tables.values()))
        return self.tables[table]

    def to_pandas(self, table: Optional[str] = None) -> Any:
        """A table (by default the first: ``trace``, ``sweep``, ...) as a
        ``pandas.DataFrame``."""
        return self._table(table).to_pandas()

    def to_polars(self, table: Optional[str] = None) -> Any:
        """A table (by default the first) as a ``polars.DataFrame``."""
        return self._table(table).to_polars()

    def _state(self) -> str:
        """``valid``, ``INVALID (...)`` or ``no simulation``."""
        if self.validity is None:
            return "no simulation"
        return "valid" if self.valid else f"INVALID ({self.violations})"

    def __str__(self) -> str:
        """The result as text: the command, its validity (and failure), then each
        table as :meth:`Table.__str__` prints it (``print(painleve.admissible())``
        prints paper Table II)."""
        head = f"painleve.Result {self.command}: {self._state()}" + (f"; failure: {self.failure}" if self.failure else "")
        return "\n\n".join([head] + [str(t) for t in self.tables.values()])

    def page(self) -> Optional[str]:
        """The run's animated page (``trace.html``: the arm on the belt, the trace's
        plots, every event marked; docs/rig.md "The animated page") as HTML text,
        the same text ``sil-host`` writes for the same run: a ``simulate`` or
        ``run`` result's (a ``run_controller`` result's too, its controller named
        as the caller's), or the ``trace.html`` of a loaded folder; ``None`` for
        the other commands."""
        page = self.extras.get("page")
        if page is None and self.path is not None:
            path = Path(self.path) / "trace.html"
            if path.is_file():
                page = path.read_text(encoding="utf-8")
        return page

    def write_page(self, path: Union[str, "os.PathLike[str]"]) -> Path:
        """Writes :meth:`page` to ``path`` (a folder: ``trace.html`` in it), the
        same bytes as the CLI's ``trace.html`` of the same run, and returns the
        file's path. Opens offline in any browser.

        Written as the CLI writes its files: whole or not at all (a temporary
        file in the same folder, renamed to ``path``), and never through a link:
        a symbolic link at ``path`` is replaced by the file, its target left as
        it was (docs/python.md "Files written").

        Raises:
            ValueError: the result has no page (an analysis, not a run).
            OSError: the file cannot be written (``FileNotFoundError`` for a
                missing folder, ``PermissionError``, ...), the message naming
                it; ``path`` is then left as it was.
        """
        page = self.page()
        if page is None:
            raise ValueError(f"a {self.command} result has no page: simulate, run and run_controller results have one")
        out = Path(path)
        if out.is_dir():
            out = out / "trace.html"
        write_file(os.fspath(out), page.encode("utf-8"))
        return out

    def write_mcap(self, path: Union[str, "os.PathLike[str]"]) -> Path:
        """Writes the run's MCAP file to ``path`` (a folder: ``trace.mcap`` in it)
        and returns the file's path: the bytes ``sil-host`` writes as
        ``trace.mcap`` for the same run with ``--format mcap`` (the tables as
        protobuf channels, and the arm in Foxglove's schemas: ``/tf``, ``/scene``,
        ``/log``; docs/rig.md "Foxglove"). Open it in Foxglove, or read it back
        with :func:`painleve.read_mcap`.

        A ``simulate`` result writes its samples and events; a ``run`` or
        ``run_controller`` result its period records. A loaded folder copies its
        ``trace.mcap`` when it has one (nothing is written when ``path`` is that
        file itself); a loaded CSV or Arrow folder of ``run`` or ``pil`` writes it from
        its tables and summary, the bytes ``--format mcap`` writes for the same run.

        Written as the CLI writes its files: whole or not at all (a temporary
        file in the same folder, renamed to ``path``), and never through a link:
        a symbolic link at ``path`` is replaced by the file, its target left as
        it was (docs/python.md "Files written").

        Raises:
            ValueError: the result holds no run (an analysis), or is a loaded
                ``simulate`` folder without a ``trace.mcap`` (run the command again
                with ``format="mcap"``, or call the function again), or a run's
                folder whose tables cannot be read (naming the file).
            OSError: the file cannot be written (``FileNotFoundError`` for a
                missing folder, ``PermissionError``, ...), the message naming
                it; ``path`` is then left as it was.
        """
        out = Path(path)
        if out.is_dir():
            out = out / "trace.mcap"
        recording = self.extras.get("recording")
        if recording is not None:
            recording.write_mcap(str(out))
            return out
        if self.path is not None:
            source = Path(self.path) / "trace.mcap"
            if source.is_file():
                # The same file is not copied onto itself; a link at ``out`` (even
                # one to ``source``) is not followed: it is replaced by a copy.
                if source.resolve() != out.parent.resolve() / out.name:
                    write_file(os.fspath(out), source.read_bytes())
                return out
            if self.command in ("run", "pil"):
                # A CSV or Arrow folder of a closed-loop run: its tables and summary hold
                # every row the file needs (the command line's bytes for the same run).
                recording_of_run(os.fspath(self.path)).write_mcap(os.fspath(out))
                return out
            raise ValueError(
                f"the folder {self.path} has no trace.mcap and its rows are not kept: "
                "write it with format='mcap' (sil-host ... --format mcap), or run the function again"
            )
        raise ValueError(f"a {self.command} result has no run to write: simulate, run and run_controller results have one")

    def _repr_html_(self) -> str:
        """The result as HTML for notebooks: the command, its validity, the run's
        animated page in a frame (runs only: :meth:`page`) and the tables."""
        import html

        head = html.escape(f"painleve.Result {self.command}: {self._state()}" + (f"; failure: {self.failure}" if self.failure else ""))
        page = self.page()
        frame = (
            f'<iframe srcdoc="{html.escape(page, quote=True)}" sandbox="allow-scripts" '
            'style="width: 100%; height: 1020px; border: 1px solid #ddd"></iframe>'
            if page is not None
            else ""
        )
        return f"<p>{head}</p>" + frame + "".join(t._repr_html_() for t in self.tables.values())

    @property
    def law(self) -> Optional[str]:
        """The control law a closed-loop result ran, in words, or ``None`` (an
        open-loop result): ``"hybrid"`` or ``"pid"`` (the paper's laws, the
        firmware's ``controller``); ``"law `impedance` (k_t = 2500)"`` for a law
        of one's own (the scenario's ``[law]`` table and the parameters it sets;
        the others at the law's defaults, ``summary["firmware_announcement"]``);
        ``"Python <name>"`` for :func:`painleve.run_controller`'s callable
        (its ``__qualname__``). On every link: ``summary.json``'s ``law``, written by
        the rig in the words every view uses (issue 84: views called every law
        "hybrid"); ``None`` for a folder written before that field."""
        s = self.summary if isinstance(self.summary, dict) else {}
        law = s.get("law")
        return law if isinstance(law, str) and law else None

    def __repr__(self) -> str:
        tables = ", ".join(f"{k}: {t.nrows}x{len(t)}" for k, t in self.tables.items())
        state = "valid" if self.valid else f"INVALID ({self.violations})"
        if self.validity is None:
            state = "no simulation"
        failed = f", failure: {self.failure!r}" if self.failure else ""
        where = f", from {self.path}" if self.path else ""
        law = self.law
        ran = f" ({law})" if law else ""
        return f"<painleve.Result {self.command}{ran}: tables [{tables}], {state}{failed}{where}>"
