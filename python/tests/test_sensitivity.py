"""`painleve.sensitivity` against `sil-host sensitivity --size quick`. The study
takes minutes on 2 cores (twice: the CLI and the package), so it runs only with
PAINLEVE_SLOW_TESTS=1; its bad input and its Ctrl-C are tested in the other files."""

import os

import pytest

import painleve
from conftest import assert_docs_equal, assert_tables_equal, cli


@pytest.mark.skipif(os.environ.get("PAINLEVE_SLOW_TESTS") != "1", reason="minutes long: set PAINLEVE_SLOW_TESTS=1")
def test_sensitivity_equals_the_cli(out):
    mine = painleve.sensitivity(size="quick", progress=False)
    cli("sensitivity", ["--size", "quick"], out)
    theirs = painleve.load(out)
    assert theirs.command == "sensitivity"
    assert_tables_equal(mine["sensitivity"], theirs["sensitivity"])
    assert_docs_equal(mine.summary, theirs.summary, ignore={"wall_s", "files", "threads"})
    assert mine.validity == theirs.validity == mine.summary["study"]["validity"]
