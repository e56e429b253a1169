"""Keyword arguments into the settings of ``sil-host``'s experiments.

Each public function's keyword ``name`` is a field of its experiment's settings
(the CLI's ``--name``, ``_`` for ``-``). The arguments given are checked against
the annotations here (:func:`check_types`), then passed as a dict to the
compiled module, which lays them over the settings' defaults (clap's, the CLI's)
and builds the typed settings (``python/src/cli.rs``): the values, defaults and
error messages are the CLI's, and no command-line text is made. Values are
passed as they are (numbers exactly, sequences as lists, paths as paths); ``set``
as ``KEY=VALUE`` items (:func:`overrides`).

An argument that is ``None`` or equal to its default is left out, so that, as on
the command line, an option not given never conflicts with another. An argument
that can conflict (``x0``, with ``x0_deg``) defaults to ``None`` (the CLI's default
then applies), so that a value given, even the CLI's default, is refused beside the
other as the command line refuses it (python/tests/test_defaults.py ``CONFLICTING``).
"""

from __future__ import annotations

import contextlib
import inspect
import json
import numbers
import os
import re
import tempfile
import typing
from typing import Any, Callable, Dict, Iterator, List, Literal, Mapping, Optional, Sequence, Union

from . import _painleve, _progress

Overrides = Union[None, str, Mapping[str, Any], Sequence[str]]


def number(v: Any) -> str:
    """A number as exact text (``repr`` of a float: the shortest text that reads
    back to the same double), for a TOML value of ``set``."""
    if isinstance(v, bool):
        raise TypeError(f"expected a number, got {v!r}")
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, numbers.Real):
        return repr(float(v))
    raise TypeError(f"expected a number, got {type(v).__name__} {v!r}")


def toml_value(v: Any) -> str:
    """A Python value as a TOML value for ``--set KEY=VALUE``: bools, numbers,
    lists (``[150, 0]``) and dicts (inline tables) are written as TOML; a string
    is passed as it is (a bare word such as ``pid`` is a string, as on the
    command line; quote it yourself for text with spaces)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, numbers.Real):
        return number(v)
    if isinstance(v, str):
        return v
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    if hasattr(v, "__iter__"):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} {v!r} as a TOML value")


def overrides(set_: Overrides) -> List[str]:
    """``set=`` as ``KEY=VALUE`` items: a dict ``{"plant.m": 0.24}``, a list of
    ``"KEY=VALUE"`` strings, or one such string."""
    if set_ is None:
        return []
    if isinstance(set_, str):
        return [set_]
    if isinstance(set_, Mapping):
        return [f"{k}={toml_value(v)}" for k, v in set_.items()]
    items = list(set_)
    for item in items:
        if not isinstance(item, str):
            raise TypeError(f"set= takes a dict or KEY=VALUE strings, got {item!r}")
    return items


def _same(a: Any, b: Any) -> bool:
    """Whether an argument equals its default (then it is left out)."""
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, numbers.Real) and isinstance(b, numbers.Real):
        return float(a) == float(b)
    if isinstance(a, str) and isinstance(b, str):
        return a == b
    return False


def given(fn: Callable[..., Any], args: Mapping[str, Any], skip: Sequence[str] = ()) -> Dict[str, Any]:
    """The arguments ``args`` to ``fn`` (its locals) the call gives: less ``skip``
    and ``progress``, less those ``None`` or equal to their defaults; ``set`` as
    its ``KEY=VALUE`` items, a path as its text."""
    defaults = {
        name: p.default for name, p in inspect.signature(fn).parameters.items() if p.default is not inspect.Parameter.empty
    }
    out: Dict[str, Any] = {}
    for name, v in args.items():
        if name in skip or name == "progress":
            continue
        if name == "set":
            items = overrides(v)
            if items:
                out["set"] = items
            continue
        if v is None or (name in defaults and _same(v, defaults[name])):
            continue
        out[name] = os.fspath(v) if isinstance(v, os.PathLike) else v
    return out


def scenario_toml(scenario: Mapping[str, Any]) -> str:
    """A scenario dict (the TOML file's tables, e.g. from
    :func:`painleve.default_scenario`) as TOML text."""
    try:
        text = json.dumps(scenario, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise TypeError(f"a scenario dict must hold TOML values (str, bool, int, finite float, list, dict): {e}") from None
    return _painleve.json_to_toml(text)


def dotted(tables: Mapping[str, Any], prefix: str = "") -> Dict[str, Any]:
    """A nested dict of scenario tables as ``{dotted key: value}`` (its leaves)."""
    out: Dict[str, Any] = {}
    for key, v in tables.items():
        if not isinstance(key, str):
            raise TypeError(f"scenario: keys must be str, got {type(key).__name__} {key!r}")
        if isinstance(v, Mapping) and v:
            out.update(dotted(v, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = v
    return out


def scenario_object(scenario: Any) -> "_painleve.Scenario":
    """``scenario=`` as a :class:`painleve.Scenario`: ``None`` the embedded
    default, a ``Scenario`` itself, a path read from its file, a dict of tables
    merged onto the default key by key (``{"timing": {"duration_s": 1.0}}``
    changes only ``timing.duration_s``; a bad key or value raises
    ``PainleveError`` naming it)."""
    if scenario is None:
        return _painleve.Scenario.default()
    if isinstance(scenario, _painleve.Scenario):
        return scenario
    if isinstance(scenario, (str, os.PathLike)):
        return _painleve.Scenario.load(os.fspath(scenario))
    if isinstance(scenario, Mapping):
        return _painleve.Scenario.default().update(dotted(scenario))
    raise TypeError(f"scenario: expected a painleve.Scenario, the path of a TOML file, a dict or None, got {type(scenario).__name__}")


@contextlib.contextmanager
def scenario_file(scenario: Any) -> Iterator[Optional[str]]:
    """``scenario=`` as the path of a TOML file: ``None`` (the embedded default),
    a path (given as it is, read by the experiment's own code), or a
    ``Scenario`` or a dict (merged onto the default, :func:`scenario_object`),
    written to a temporary file for the call."""
    if scenario is None or isinstance(scenario, (str, os.PathLike)):
        yield None if scenario is None else os.fspath(scenario)
        return
    text = scenario_object(scenario).to_toml()
    with tempfile.TemporaryDirectory(prefix="painleve-") as d:
        path = os.path.join(d, "scenario.toml")
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        yield path


_WORDS = {float: "a number", int: "an integer", str: "a string", bool: "True or False"}


def _matches(v: Any, hint: Any) -> Optional[bool]:
    """Whether ``v`` is of the annotated type ``hint``: ``True``/``False``, or
    ``None`` where the annotation is not one this check reads (callables,
    mappings, paths: the experiment's own checks cover them). A ``Literal``
    matches one of its values."""
    if typing.get_origin(hint) is Literal:
        return isinstance(v, str) and v in typing.get_args(hint)
    if hint is float:
        return isinstance(v, numbers.Real) and not isinstance(v, bool)
    if hint is int:
        return isinstance(v, numbers.Integral) and not isinstance(v, bool)
    if hint is str:
        return isinstance(v, str)
    if hint is bool:
        return isinstance(v, bool)
    if hint is type(None):
        return v is None
    origin = typing.get_origin(hint)
    if origin is Union:
        answers = [_matches(v, h) for h in typing.get_args(hint)]
        if any(a is True for a in answers):
            return True
        return None if any(a is None for a in answers) else False
    if origin in (list, tuple, Sequence, typing.get_origin(Sequence[int])):
        if isinstance(v, (str, bytes)) or not isinstance(v, (list, tuple)) and not hasattr(v, "__array__"):
            return False
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        if not args:
            return True
        return all(_matches(x, args[0]) is not False for x in v)
    return None


def _describe(hint: Any) -> str:
    """An annotation in words: ``a number``, ``a number or None``, ``a list of
    numbers``, ``'newton', 'poisson' or 'energetic'``."""
    if typing.get_origin(hint) is Literal:
        choices = [repr(c) for c in typing.get_args(hint)]
        return ", ".join(choices[:-1]) + " or " + choices[-1] if len(choices) > 1 else choices[0]
    if hint in _WORDS:
        return _WORDS[hint]
    if hint is type(None):
        return "None"
    origin = typing.get_origin(hint)
    if origin is Union:
        return " or ".join(dict.fromkeys(_describe(h) for h in typing.get_args(hint)))
    if origin in (list, tuple, Sequence, typing.get_origin(Sequence[int])):
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        if args and typing.get_origin(args[0]) is Literal:
            return "a list of " + _describe(args[0])
        return "a list of " + (_describe(args[0]).removeprefix("a ").removeprefix("an ") + "s" if args else "values")
    return str(hint)


def _loosened(hint: Any) -> Any:
    """``hint`` with each ``Literal`` of strings read as ``str``: the type the
    value must have, whatever its value."""
    if typing.get_origin(hint) is Literal:
        return str
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is Union:
        return Union[tuple(_loosened(a) for a in args)]
    if origin in (list, tuple, Sequence, typing.get_origin(Sequence[int])) and args:
        return Sequence[_loosened(args[0])]  # type: ignore[index]
    return hint


def check_types(fn: Callable[..., Any], given: Mapping[str, Any]) -> None:
    """Checks each argument ``given`` to ``fn`` against its annotation, at the
    Python boundary: ``TypeError`` naming the parameter, what it takes and what it
    got (``mu: expected a number, got list [1, 2]``); ``ValueError`` for a string
    that is not one of a ``Literal``'s choices (``impact_law: expected 'newton',
    'poisson' or 'energetic', got 'bogus'``). ``None`` passes only where the
    annotation says ``Optional``; ``True`` is not a number."""
    hints = typing.get_type_hints(fn)
    for name, v in given.items():
        hint = hints.get(name)
        if hint is None or name in ("set", "progress", "scenario"):
            continue
        if _matches(v, hint) is False:
            message = f"{name}: expected {_describe(hint)}, got {type(v).__name__} {v!r}"
            if _matches(v, _loosened(hint)) is not False:
                raise ValueError(message)
            raise TypeError(message)


_FLAG = re.compile(r"'?--([a-z][a-z0-9-]*)(?: <[^>]*>)?'?")


def pythonic(message: str) -> str:
    """An experiment's message with its command-line syntax written as the Python
    call's: a flag ``--sample-dt`` (or clap's ``'--x0 <X0>'``) is the parameter
    ``sample_dt``, ``--set KEY=VALUE`` is ``set KEY=VALUE``."""
    return _FLAG.sub(lambda m: m.group(1).replace("-", "_"), message)


def call(name: str, fn: Callable[..., Any], args: Dict[str, Any], progress: Any = None, scenario: Any = None) -> Any:
    """Calls the compiled ``name`` with the arguments ``args`` gives (:func:`given`)
    and the scenario's path."""
    native = getattr(_painleve, name)
    check_types(fn, args)
    with scenario_file(scenario) as path:
        settings = given(fn, args, skip=("scenario",))
        if path is not None:
            settings["scenario"] = path
        try:
            if name in ("admissible", "modes"):
                return native(settings)
            return native(settings, _progress.resolve(progress))
        except _painleve.PainleveError as e:
            # The message in the call's terms (parameters, not flags); the
            # attributes (exit_code, result) kept.
            e.args = (pythonic(str(e)),)
            raise
