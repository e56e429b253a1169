"""The progress line of a long call (``progress=True``): in a terminal, a line on
``sys.stderr`` rewritten in place (``\\r``, by the compiled module); in a
Jupyter notebook, one display output updated in place (IPython's
``display(..., display_id=True)`` and ``update``), so the saved notebook holds
the last line once, not one stream output per rewrite."""

from __future__ import annotations

import sys
from typing import Any, Optional

__all__ = ["NotebookLine", "in_notebook", "resolve"]


def in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (ipykernel: JupyterLab, Notebook,
    VS Code, nbclient). A terminal IPython is not one. IPython is not imported
    here when it is not loaded already."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    try:
        shell = ipython.get_ipython()
    except Exception:  # pragma: no cover - a broken IPython is no notebook
        return False
    return shell is not None and getattr(shell, "kernel", None) is not None


class NotebookLine:
    """The progress line as one notebook output: the first ``show`` displays the
    line (``text/plain``), each later one replaces it (the compiled module calls
    ``show(text, last)`` at most every 250 ms, from 0.5 s into the call, and once
    at the end with ``last=True``)."""

    def __init__(self) -> None:
        self._handle: Optional[Any] = None

    def show(self, text: str, last: bool) -> None:
        from IPython.display import display

        data = {"text/plain": text}
        if self._handle is None:
            self._handle = display(data, raw=True, display_id=True)
        else:
            self._handle.update(data, raw=True)


def resolve(progress: Any) -> Any:
    """What the compiled module is given for ``progress``: ``True`` under Jupyter
    becomes a :class:`NotebookLine`; anything else is passed as it is."""
    if progress is True and in_notebook():
        return NotebookLine()
    return progress
