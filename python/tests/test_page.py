"""Issue 69 (2): a run's result shows itself: its animated page (``trace.html``,
every event marked) written by ``Result.write_page`` is the CLI's file for the same
run, byte for byte; a loaded folder's page is its file; a notebook shows the page."""

import pytest

import painleve

from conftest import cli


@pytest.mark.parametrize(
    "command, kwargs, argv",
    [
        ("simulate", {"x0": "a", "duration": 2.0}, ["--x0", "a", "--duration", "2"]),
        ("run", {"duration": 0.5}, ["--in-process", "--duration", "0.5"]),
    ],
)
def test_a_results_page_is_the_clis_byte_for_byte(tmp_path, command, kwargs, argv):
    cli(command, argv, tmp_path / "cli")
    r = getattr(painleve, command)(progress=False, **kwargs)
    written = r.write_page(tmp_path)
    assert written == tmp_path / "trace.html"
    assert written.read_bytes() == (tmp_path / "cli" / "trace.html").read_bytes()
    # In a notebook: the page in a frame, before the tables.
    shown = r._repr_html_()
    assert shown.index("<iframe srcdoc=") < shown.index("<table")
    # A loaded folder's page is its file.
    assert painleve.load(tmp_path / "cli").page() == (tmp_path / "cli" / "trace.html").read_text(encoding="utf-8")


def test_the_bounce_is_in_the_page_python_writes(tmp_path):
    r = painleve.simulate(x0="a", progress=False)
    page = r.page()
    touchdowns = int((r.events["kind"] == "touchdown").sum())
    assert touchdowns >= 20 and page.count('"touchdown"') >= 1
    assert f"{touchdowns} touchdown" in page, "the page's note counts them"


def test_an_analysis_has_no_page():
    r = painleve.admissible()
    assert r.page() is None
    with pytest.raises(ValueError, match="no page"):
        r.write_page("anywhere.html")
    assert "<iframe" not in r._repr_html_()


def test_a_python_controllers_run_has_its_page(tmp_path):
    # The paper's PID as a Python function would do; here a constant torque, 0.1 s.
    r = painleve.run_controller(lambda t, sensed: (0.0, 0.0), duration=0.1)
    page = r.page()
    assert page is not None and "painleve.run_controller" in page
    assert r.write_page(tmp_path / "p.html").read_text(encoding="utf-8") == page
    assert '"t":[' in page.replace(" ", "")
