"""An independent reference for ``painleve.read_csv`` on the tables the CLI
writes: the standard library's ``csv`` and NumPy, each column of the type its
declaration gives (``painleve._painleve.declared_tables()``: the same
declarations the compiled reader matches a file's header against), each cell
read by Python (``float`` is correctly rounded: the bits of the shortest
round-trip digits the CLI writes)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from painleve._painleve import declared_tables


def declaration(path: Path) -> Optional[Dict[str, str]]:
    """``{column: kind}`` of the declared table whose header is ``path``'s, or None."""
    with open(path, newline="", encoding="utf-8") as f:
        header = next(csv.reader(f), [])
    for names, kinds in declared_tables():
        if names == header:
            return dict(zip(names, kinds))
    return None


def _column(cells: List[str], kind: str) -> np.ndarray:
    if kind == "f64":
        return np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
    if kind == "int":
        return np.array([int(c) for c in cells], dtype=np.int64)
    if kind == "bool":
        assert all(c in ("true", "false") for c in cells), cells
        return np.array([c == "true" for c in cells], dtype=bool)
    return np.array(cells, dtype=str)


def reference_read_csv(path: Path) -> Dict[str, Any]:
    """``{column: array}`` of the declared table at ``path``, read cell by cell."""
    kinds = declaration(path)
    assert kinds is not None, f"{path}: its header is no declared table"
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        header = next(reader)
        rows: List[List[str]] = [r for r in reader]
    return {name: _column([r[i] for r in rows], kinds[name]) for i, name in enumerate(header)}


def declared_dtypes() -> Dict[Tuple[str, ...], List[str]]:
    """Each declared header and its columns' NumPy dtype kinds (``f``, ``i``, ``b``, ``U``)."""
    kind = {"f64": "f", "int": "i", "bool": "b", "str": "U"}
    return {tuple(names): [kind[k] for k in kinds] for names, kinds in declared_tables()}
