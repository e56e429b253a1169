"""Type stubs of the compiled module ``painleve._painleve`` (python/src/lib.rs).

Each command function takes the CLI tokens of its arguments (``["--mu=0.6",
...]``, built by ``painleve``'s Python layer) and returns the raw result dict
that ``painleve.Result`` wraps: ``command``, ``summary``, ``tables`` (``{name:
{column: numpy array or list of str}}``), ``extras``, ``validity``,
``violations``, ``failure``, ``exit_code``. Call the functions of ``painleve``
instead.
"""

from typing import Any, Callable, Dict, List, Optional, Union

__version__: str

class PainleveError(ValueError):
    """Bad input or a failure, with the CLI's message; ``exit_code``: the CLI's
    exit code (2 bad input, 1 a run that failed); ``result``: the
    :class:`painleve.Result` of a run that failed part way (``strict=True``, or
    :meth:`painleve.Result.check`), ``None`` for bad input."""

    exit_code: int
    result: Any

_Progress = Union[bool, None, Callable[[int, int], Any]]
_Raw = Dict[str, Any]

def simulate(tokens: List[str], progress: _Progress = None) -> _Raw: ...
def admissible(tokens: List[str]) -> _Raw: ...
def modes(tokens: List[str]) -> _Raw: ...
def poincare(tokens: List[str], progress: _Progress = None) -> _Raw: ...
def sweep(tokens: List[str], progress: _Progress = None) -> _Raw: ...
def zmax(tokens: List[str], progress: _Progress = None) -> _Raw: ...
def run(tokens: List[str], progress: _Progress = None) -> _Raw: ...
def sensitivity(tokens: List[str], progress: _Progress = None) -> _Raw: ...
def cli_defaults(command: str) -> Dict[str, List[str]]:
    """``{long option: [default values as the CLI shows them]}`` of a command."""
def default_scenario_toml() -> str:
    """The embedded default scenario's TOML text."""
def read_arrow(path: str) -> Dict[str, Any]:
    """An Arrow IPC table as ``{column: array}`` (lists of ``str`` for text)."""
def toml_to_json(text: str) -> str:
    """A TOML document as JSON text."""
def json_to_toml(text: str) -> str:
    """A JSON object as TOML text."""
