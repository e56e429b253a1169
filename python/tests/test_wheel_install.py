"""The tests run against the manylinux wheel, installed without Rust (issue 55): when
scripts/python-tests.sh runs them (it sets PAINLEVE_WHEEL_VENV to the fresh environment
it made), no Rust toolchain is on PATH and `painleve` is that wheel's, installed from the
file scripts/build-wheel.sh built. Elsewhere (a developer's `pip install ./python`) skipped."""

from __future__ import annotations

import json
import os
import shutil
import sys
from importlib import metadata
from pathlib import Path

import pytest

import painleve

VENV = os.environ.get("PAINLEVE_WHEEL_VENV")
pytestmark = pytest.mark.skipif(not VENV, reason="not the wheel's environment (scripts/python-tests.sh sets PAINLEVE_WHEEL_VENV)")


def test_no_rust_toolchain_is_reachable():
    for tool in ("cargo", "rustc", "rustup"):
        assert shutil.which(tool) is None, f"{tool} is on PATH at {shutil.which(tool)}: {os.environ['PATH']}"


def test_painleve_is_the_manylinux2014_abi3_wheel_installed_in_the_fresh_environment():
    venv = Path(VENV).resolve()
    assert Path(sys.prefix).resolve() == venv, f"pytest runs in {sys.prefix}, not {venv}"
    assert venv in Path(painleve.__file__).resolve().parents
    dist = metadata.distribution("painleve")
    tags = [line.split(": ", 1)[1] for line in dist.read_text("WHEEL").splitlines() if line.startswith("Tag: ")]
    assert tags == ["cp39-abi3-manylinux_2_17_x86_64", "cp39-abi3-manylinux2014_x86_64"], tags
    # pip records where it installed from (PEP 610): the wheel file, not a source tree.
    url = json.loads(dist.read_text("direct_url.json"))["url"]
    assert url.startswith("file://") and url.endswith("manylinux_2_17_x86_64.manylinux2014_x86_64.whl"), url
    assert "dir_info" not in json.loads(dist.read_text("direct_url.json"))
