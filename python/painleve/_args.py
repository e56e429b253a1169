"""Keyword arguments into the tokens of ``sil-host``'s command line.

Each public function's keyword ``name`` is the CLI's ``--name`` (``_`` for
``-``): ``v_belt=-0.4`` is ``--v-belt=-0.4``. The tokens are parsed by the CLI's
own parser in the compiled module, so the values, defaults and error messages
are the CLI's. Values:

- ``True`` gives the flag (``strict=True``: ``--strict``), ``False`` nothing;
- ``None`` gives nothing (the CLI's default, or its absence);
- numbers are written exactly (``repr`` of a float: the shortest text that
  reads back to the same double);
- sequences are comma-joined (``mu=(0.1, 1.0)``: ``--mu=0.1,1.0``;
  ``ics=["a", "d"]``: ``--ics=a,d``);
- paths and strings are passed as they are.

An argument equal to its default is left out, so that, as on the command
line, an option not given never conflicts with another (``x0`` and ``x0_deg``).
"""

from __future__ import annotations

import contextlib
import inspect
import json
import numbers
import os
import tempfile
import typing
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Sequence, Union

from . import _painleve

Overrides = Union[None, str, Mapping[str, Any], Sequence[str]]


def number(v: Any) -> str:
    """A number as exact text."""
    if isinstance(v, bool):
        raise TypeError(f"expected a number, got {v!r}")
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, numbers.Real):
        return repr(float(v))
    raise TypeError(f"expected a number, got {type(v).__name__} {v!r}")


def value(v: Any) -> str:
    """A value as the text of ``--flag=TEXT``."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (numbers.Real,)):
        return number(v)
    if isinstance(v, os.PathLike):
        return str(os.fspath(v))
    if isinstance(v, str):
        return v
    if hasattr(v, "__iter__"):
        return ",".join(value(x) for x in v)
    raise TypeError(f"cannot pass {type(v).__name__} {v!r} as an option")


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


def tokens(fn: Callable[..., Any], given: Mapping[str, Any], skip: Sequence[str] = ()) -> List[str]:
    """The tokens of the arguments ``given`` to ``fn`` (its locals), less
    ``skip`` and ``progress``, less those equal to their defaults."""
    defaults = {
        name: p.default for name, p in inspect.signature(fn).parameters.items() if p.default is not inspect.Parameter.empty
    }
    out: List[str] = []
    for name, v in given.items():
        if name in skip or name == "progress":
            continue
        if name == "set":
            out += [f"--set={item}" for item in overrides(v)]
            continue
        if v is None or (name in defaults and _same(v, defaults[name])):
            continue
        flag = "--" + name.replace("_", "-")
        if isinstance(v, bool):
            if v:
                out.append(flag)
            continue
        out.append(f"{flag}={value(v)}")
    return out


def scenario_toml(scenario: Mapping[str, Any]) -> str:
    """A scenario dict (the TOML file's tables, e.g. from
    :func:`painleve.default_scenario`) as TOML text."""
    try:
        text = json.dumps(scenario, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise TypeError(f"a scenario dict must hold TOML values (str, bool, int, finite float, list, dict): {e}") from None
    return _painleve.json_to_toml(text)


@contextlib.contextmanager
def scenario_file(scenario: Any) -> Iterator[Optional[str]]:
    """``scenario=`` as the path of a TOML file: ``None`` (the embedded default),
    a path (given as it is, read by the CLI's code), or a dict (written to a
    temporary file for the call)."""
    if scenario is None or isinstance(scenario, (str, os.PathLike)):
        yield None if scenario is None else os.fspath(scenario)
        return
    if not isinstance(scenario, Mapping):
        raise TypeError(f"scenario= takes a path or a dict, got {type(scenario).__name__}")
    text = scenario_toml(scenario)
    with tempfile.TemporaryDirectory(prefix="painleve-") as d:
        path = os.path.join(d, "scenario.toml")
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        yield path


_WORDS = {float: "a number", int: "an integer", str: "a string", bool: "True or False"}


def _matches(v: Any, hint: Any) -> Optional[bool]:
    """Whether ``v`` is of the annotated type ``hint``: ``True``/``False``, or
    ``None`` where the annotation is not one this check reads (callables,
    mappings, paths: the CLI's own checks cover them)."""
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
    """An annotation in words: ``a number``, ``a number or None``, ``a list of numbers``."""
    if hint in _WORDS:
        return _WORDS[hint]
    if hint is type(None):
        return "None"
    origin = typing.get_origin(hint)
    if origin is Union:
        return " or ".join(dict.fromkeys(_describe(h) for h in typing.get_args(hint)))
    if origin in (list, tuple, Sequence, typing.get_origin(Sequence[int])):
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        return "a list of " + (_describe(args[0]).removeprefix("a ").removeprefix("an ") + "s" if args else "values")
    return str(hint)


def check_types(fn: Callable[..., Any], given: Mapping[str, Any]) -> None:
    """Checks each argument ``given`` to ``fn`` against its annotation, at the
    Python boundary: ``TypeError`` naming the parameter, what it takes and what it
    got (``mu: expected a number, got list [1, 2]``). ``None`` passes only where
    the annotation says ``Optional``; ``True`` is not a number."""
    hints = typing.get_type_hints(fn)
    for name, v in given.items():
        hint = hints.get(name)
        if hint is None or name in ("set", "progress", "scenario"):
            continue
        if _matches(v, hint) is False:
            raise TypeError(f"{name}: expected {_describe(hint)}, got {type(v).__name__} {v!r}")


def call(name: str, fn: Callable[..., Any], given: Dict[str, Any], progress: Any = None, scenario: Any = None) -> Any:
    """Calls the compiled ``name`` with the tokens of ``given`` (and the
    scenario, as ``--scenario``)."""
    native = getattr(_painleve, name)
    check_types(fn, given)
    with scenario_file(scenario) as path:
        toks = tokens(fn, given, skip=("scenario",))
        if path is not None:
            toks.insert(0, f"--scenario={path}")
        if name in ("admissible", "modes"):
            return native(toks)
        return native(toks, progress)
