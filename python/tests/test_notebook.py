"""examples/python/paper.ipynb executes cleanly (nbclient, a fresh kernel of this
interpreter) and shows the paper's numbers."""

import time

import pytest

from conftest import REPO

NOTEBOOK = REPO / "examples" / "python" / "paper.ipynb"


def test_paper_notebook_executes():
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    pytest.importorskip("matplotlib")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    started = time.monotonic()
    # Raises CellExecutionError, with the cell and its traceback, on any error.
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
    print(f"paper.ipynb executed in {time.monotonic() - started:.1f} s")
    text = "\n".join(
        o.get("text", "") if o.get("output_type") == "stream" else str(o.get("data", {}).get("text/plain", ""))
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.get("outputs", [])
    )
    assert "elbow_up" in text and "elbow_down" in text, "Table II printed"
    assert "x0a: critical mu = 0.4" in text, "Fig. 3's critical mu (the paper's 0.4)"
    assert "x0d ever bounces: False" in text, "the paper: x0d never bounces"
    assert "lift-offs 0" in text, "the hybrid closed loop from x0d does not lift off"
    images = sum(1 for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if "image/png" in o.get("data", {}))
    assert images == 3, f"{images} figures"
