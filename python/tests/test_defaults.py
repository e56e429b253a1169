"""Every keyword argument of the package's functions is a flag of the CLI
command, and its default is the CLI's (from the CLI's own clap definitions)."""

import inspect

import pytest

import painleve
from painleve import _painleve

# Options of the CLI the functions leave out, and why.
NOT_IN_PYTHON = {
    "out": "results are returned, not written",
    "json": "results are returned, not printed",
    "format": "tables are returned as arrays, not written (painleve.load reads either format)",
    "in-process": "run is always in-process",
    "link": "run is always in-process",
    "elf": "the image of --link emulator: run is always in-process",
    "realtime": "needs the firmware process over iceoryx2",
    "attach": "needs the firmware process over iceoryx2",
    "rig": "needs the firmware process over iceoryx2",
    "monitors": "needs the firmware process over iceoryx2",
    "monitor-timeout": "needs the firmware process over iceoryx2",
    "live": "a live Foxglove view of a CLI run; in Python the results are returned (and Foxglove opens trace.mcap)",
    "live-rate": "the pace of --live",
    "live-wait": "the wait of --live for a viewer",
    "live-backlog": "the queue of --live per viewer",
    "no-page": "trace.html is a file of the CLI's output folder; results are returned",
}
# Arguments of the functions that are not flags.
NOT_FLAGS = {"progress"}
# Arguments whose default is None here, so that a value given, even the CLI's default, is
# given as on the command line, where clap refuses it beside the option it conflicts with.
CONFLICTING = {"x0": "x0_deg"}

FUNCTIONS = ["simulate", "admissible", "modes", "poincare", "sweep", "zmax", "run", "sensitivity"]


def parse(v):
    """A default as the CLI parses it: numbers (a list of them for ranges and
    lists), or text."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return [float(v)]
    if isinstance(v, (tuple, list)):
        return [y for x in v for y in parse(x)]
    items = str(v).split(",")
    try:
        return [float(x) for x in items]
    except ValueError:
        return [x.strip() for x in items]


@pytest.mark.parametrize("name", FUNCTIONS)
def test_arguments_are_the_cli_options_with_its_defaults(name):
    cli = _painleve.cli_defaults(name)
    params = inspect.signature(getattr(painleve, name)).parameters
    for p in params.values():
        if p.name in NOT_FLAGS:
            continue
        flag = p.name.replace("_", "-")
        assert flag in cli, f"{name}({p.name}=...) is not an option of sil-host {name}"
        defaults = cli[flag]
        if p.name in CONFLICTING and CONFLICTING[p.name] in params:
            assert p.default is None and defaults, f"{name}: {p.name} defaults to None, left to the CLI's {defaults}"
        elif p.default is None:
            assert defaults == [], f"{name}: {p.name} has no default here but {defaults} in the CLI"
        elif p.default is False:
            assert defaults in ([], ["false"]), f"{name}: {p.name}"
        else:
            expected = [y for d in defaults for y in parse(d)]
            assert parse(p.default) == expected, f"{name}: {p.name}={p.default!r}, the CLI's default is {defaults}"
    missing = set(cli) - {p.name.replace("_", "-") for p in params.values()} - set(NOT_IN_PYTHON)
    assert not missing, f"sil-host {name} options without an argument: {sorted(missing)}"


def test_every_function_has_a_docstring_naming_its_columns():
    for name in FUNCTIONS:
        doc = getattr(painleve, name).__doc__
        assert doc and "Returns:" in doc and "Raises:" in doc, name


def _choices(hint):
    """The ``Literal`` choices in an annotation (through ``Optional``, ``Union``
    and ``Sequence``), or ``None`` when it has none."""
    import typing

    if typing.get_origin(hint) is typing.Literal:
        return list(typing.get_args(hint))
    for a in typing.get_args(hint):
        c = _choices(a)
        if c is not None:
            return c
    return None


@pytest.mark.parametrize("name", FUNCTIONS)
def test_choices_are_the_settings_choices(name):
    # Issue 42, 2: an option that takes one of a fixed set of values is a Literal of
    # exactly those values, in the settings' order (the CLI's possible values).
    import typing

    cli = _painleve.cli_choices(name)
    hints = typing.get_type_hints(getattr(painleve, name))
    for flag, values in cli.items():
        param = flag.replace("-", "_")
        if flag in NOT_IN_PYTHON:
            continue
        assert _choices(hints[param]) == values, f"{name}({param}): {hints[param]} against the CLI's {values}"
    for param, hint in hints.items():
        if _choices(hint) is not None:
            assert param.replace("_", "-") in cli, f"{name}({param}) is a Literal but not a choice of the CLI"


def test_the_installed_package_is_tested_not_the_source_tree():
    # Issue 42, 5: scripts/test.sh builds a wheel (maturin build) and installs it; the
    # package under test is the installed one, with its compiled module beside it.
    from pathlib import Path

    here = Path(painleve.__file__).resolve().parent
    source = Path(__file__).resolve().parents[1] / "painleve"
    assert here != source.resolve(), f"painleve imported from the source tree {here}"
    assert Path(_painleve.__file__).resolve().parent == here, "the compiled module is the installed package's"
    assert (here / "py.typed").exists() and (here / "_painleve.pyi").exists(), "the wheel carries the type information"
