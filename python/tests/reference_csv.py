"""The pure-Python CSV reader ``painleve.read_csv`` was before it read through the
compiled module (issue 44): the standard library's ``csv`` and NumPy, kept here
unchanged as the reference the compiled reader must equal bit for bit."""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

_INT = re.compile(r"^[+-]?\d+$")


def _infer(cells: List[str]) -> np.ndarray:
    nonempty = [c for c in cells if c != ""]
    if not nonempty:
        return np.full(len(cells), np.nan)
    if len(nonempty) == len(cells) and all(c in ("true", "false") for c in cells):
        return np.array([c == "true" for c in cells], dtype=bool)
    if len(nonempty) == len(cells) and all(_INT.match(c) for c in cells):
        try:
            return np.array([int(c) for c in cells], dtype=np.int64)
        except OverflowError:
            return np.array([int(c) for c in cells], dtype=np.uint64)
    try:
        return np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
    except ValueError:
        return np.array(cells, dtype=str)


def reference_read_csv(path: Path) -> Dict[str, Any]:
    """``{column: array}`` as the former ``painleve.read_csv`` read ``path``."""
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        try:
            header = next(reader)
        except StopIteration:
            return {}
        rows = [r for r in reader if r]
    columns: Dict[str, Any] = {}
    for i, name in enumerate(header):
        cells = [r[i] if i < len(r) else "" for r in rows]
        columns[name] = _infer(cells) if rows else np.array([], dtype=np.float64)
    return columns
