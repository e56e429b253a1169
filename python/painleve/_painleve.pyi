"""Type stubs of the compiled module ``painleve._painleve`` (python/src/lib.rs).

Each command function takes the keyword arguments given (``{"mu": 0.6, ...}``,
those ``painleve``'s Python layer found not ``None`` nor at their defaults; laid
over the settings' defaults in the compiled module) and returns the raw result dict
that ``painleve.Result`` wraps: ``command``, ``summary``, ``tables`` (``{name:
{column: numpy array or list of str}}``), ``extras``, ``validity``,
``violations``, ``failure``, ``exit_code``. Call the functions of ``painleve``
instead.
"""

from os import PathLike
from typing import Any, Callable, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

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

class Recording:
    """A run's rows kept for its MCAP file (``Result.extras["recording"]``)."""

    def write_mcap(self, path: str) -> None:
        """Writes ``sil-host``'s ``trace.mcap`` of the same run at ``path`` (whole or not at all, a link there replaced, not followed); ``OSError`` when it cannot."""

def write_file(path: str, data: bytes) -> None:
    """Writes ``data`` as the file ``path`` as the CLI writes its files: a temporary file in the same folder renamed to ``path`` (a link there replaced, its target left as it was); ``OSError`` naming the file when it cannot."""

def simulate(given: Dict[str, Any], progress: _Progress = None) -> _Raw: ...
def admissible(given: Dict[str, Any]) -> _Raw: ...
def modes(given: Dict[str, Any]) -> _Raw: ...
def poincare(given: Dict[str, Any], progress: _Progress = None) -> _Raw: ...
def sweep(given: Dict[str, Any], progress: _Progress = None) -> _Raw: ...
def zmax(given: Dict[str, Any], progress: _Progress = None) -> _Raw: ...
def run(given: Dict[str, Any], progress: _Progress = None) -> _Raw: ...
def sensitivity(given: Dict[str, Any], progress: _Progress = None) -> _Raw: ...
def replay(folder: str, set: List[str], all: bool, link: str, progress: _Progress = None) -> _Raw: ...
def cli_defaults(command: str) -> Dict[str, List[str]]:
    """``{long option: [default values as the CLI shows them]}`` of a command."""
def default_scenario_toml() -> str:
    """The embedded default scenario's TOML text."""
def declared_tables() -> List[Tuple[List[str], List[str]]]:
    """The declarations of the tables the CLI writes as CSV: ``(names, kinds)`` each, kinds ``f64``, ``int``, ``bool``, ``str``."""
def read_arrow(path: str) -> Dict[str, Any]:
    """An Arrow IPC file (or one cut before its footer, or a stream) as ``{column: array}``, each column of the file's type (text as in :func:`read_csv`)."""
def read_mcap(path: str) -> List[Tuple[str, Dict[str, Any]]]:
    """The tables of an MCAP file the CLI wrote as ``[(name, {column: array})]``, columns as in :func:`read_csv`; a cut file gives its whole chunks."""
def read_text(path: str, kind: str) -> str:
    """A file of a command's folder as text, a regular file within the bound of ``kind`` (``"document"``, a JSON
    document: 64 MiB; ``"log"``: 1 GiB, bytes not UTF-8 replaced); else ``PainleveError`` naming the bound."""
def read_csv(path: str) -> Dict[str, Any]:
    """A CSV table as ``{column: array}`` in the file's order, of its declaration's types (a table the CLI
    writes; else arrow-csv's inferred types): float64, int64 or bool arrays of shape ``(nrows,)``, a text
    column as ``(values, codes)`` (its distinct cells, a list of ``str``, and a uint32 array of each row's
    index into them). Raises ``PainleveError`` (exit code 2) naming the file and line for a file the CLI did
    not write whole."""
def toml_to_json(text: str) -> str:
    """A TOML document as JSON text."""
def json_to_toml(text: str) -> str:
    """A JSON object as TOML text."""

# --- Objects (python/src/objects; docs/python.md "Objects") --------------------

_F64 = npt.NDArray[np.float64]
# N numbers: a sequence, or an array of shape (N,) (a shape error names the argument).
_Numbers = Union[Sequence[float], npt.NDArray[np.float64]]
_Torques = Union[Tuple[float, float], Sequence[float], _F64]

class Scenario:
    """A closed-loop scenario (``rig::Scenario``): plant, controller, timing,
    sensors, faults. Always valid: every change is validated by the rig.

    ``Scenario()`` / ``Scenario.default()``: the embedded default
    (``scenarios/default.toml``); ``Scenario(text)``: TOML text;
    ``Scenario(path)``: a TOML file.

    Raises:
        PainleveError: invalid TOML or values (``exit_code`` 2), naming the key.
    """

    def __init__(self, source: Union[None, str, PathLike[str]] = None) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    @staticmethod
    def default() -> Scenario:
        """The embedded default scenario (``scenarios/default.toml``)."""
    @staticmethod
    def from_toml(text: str) -> Scenario:
        """A scenario from TOML text. Raises PainleveError (exit code 2)."""
    @staticmethod
    def load(path: Union[str, PathLike[str]]) -> Scenario:
        """A scenario from a TOML file. Raises PainleveError (exit code 2)."""
    def set(self, key: str, value: Any) -> Scenario:
        """Sets dotted key ``key`` (the CLI's ``--set`` keys: ``"plant.mu"``,
        ``"controller.pid.kp"``) to ``value`` (bool, int, float, str, list, dict)
        and validates; returns ``self``. Raises PainleveError (exit code 2) for
        a bad key or value (the scenario is then unchanged), TypeError for a
        value TOML cannot hold."""
    def update(self, values: Dict[str, Any]) -> Scenario:
        """Sets several dotted keys at once, validated together; returns ``self``."""
    def validate(self) -> None:
        """Validates again (``rig::Scenario::validate``)."""
    def to_toml(self) -> str:
        """The scenario as TOML text (every key written)."""
    def to_dict(self) -> Dict[str, Any]:
        """The scenario as a dict of its tables."""
    def get(self, key: str) -> Any:
        """The value at dotted key ``key``. Raises KeyError."""
    def __getitem__(self, key: str) -> Any: ...
    def copy(self) -> Scenario: ...
    @property
    def name(self) -> str: ...
    @property
    def periods(self) -> int:
        """Control periods in the run."""

class Step:
    """What :meth:`Plant.advance` reports about its interval."""

    @property
    def t(self) -> float:
        """Time at the end, s."""
    @property
    def mode(self) -> Literal["flight", "sliding", "sticking"]: ...
    @property
    def state(self) -> _F64:
        """``(4,)``: theta1 rad, theta1_dot rad/s, theta2 rad, theta2_dot rad/s."""
    @property
    def tip(self) -> _F64:
        """``(2,)``: ``[z_t, z_n]``, m."""
    @property
    def force(self) -> _F64:
        """``(2,)``: contact force ``[f_t, f_n]`` at the end, N."""
    @property
    def events(self) -> List[Dict[str, Any]]:
        """The interval's events: ``t`` (s), ``kind``, ``mode_after``, velocities
        before and after (m/s), ``impulse`` (N s), ``energy_change``,
        ``contact_work`` (J), ``resolution``."""

class Model:
    """The arm's model at one parameter set (paper eqs. 1 to 7): states ``(4,)``
    ``[theta1, theta1_dot, theta2, theta2_dot]``, configurations ``(2,)``, torques ``(2,)`` N m.

    Raises:
        ValueError: (every method) a NaN or infinite angle, rate, torque or
            position, naming the argument and the element (``theta[1] = nan``);
            an argument of the wrong length or shape, naming it (``theta:
            expected 2 numbers (a sequence, or an array of shape (2,)), got an
            array of shape (2, 2)``).
        TypeError: an argument that is not a sequence of numbers, naming it.
    """
    def __init__(self, scenario: Any = None, **params: float) -> None: ...
    @property
    def params(self) -> Dict[str, float]: ...
    def tip(self, theta: _Numbers) -> _F64:
        """The tip ``[z_t, z_n]`` (m), shape ``(2,)``, of configuration ``theta`` (rad)."""
    def inverse_kinematics(self, z: _Numbers, branch: str = "down") -> _F64:
        """The configuration ``[theta1, theta2]`` (rad), shape ``(2,)``, with its tip at ``z`` (m) on ``branch``."""
    def jacobian(self, theta: _Numbers) -> _F64:
        """The tip's Jacobian (m/rad), shape ``(2, 2)``."""
    def jdot_qdot(self, state: _Numbers) -> _F64:
        """``J_dot q_dot`` (m/s^2), shape ``(2,)``: the tip's acceleration with no joint acceleration."""
    def mass_matrix(self, theta: _Numbers) -> _F64:
        """``M(theta)`` (kg m^2), shape ``(2, 2)``."""
    def q_matrix(self, theta: _Numbers) -> _F64:
        """``Q = J M^-1 J^T`` (1/kg), shape ``(2, 2)``."""
    def bias(self, state: _Numbers) -> _F64:
        """The free arm's generalised forces ``w + c`` (gravity, spring, damping, velocity terms; N m), shape ``(2,)`` (paper eq. 1)."""
    def generalised_torque(self, torques: _Numbers) -> _F64:
        """The generalised torque ``[u1 - u2, u2]`` (N m), shape ``(2,)``, of motor torques ``[u1, u2]``."""
    def p(self, theta: _Numbers, direction: str = "negative") -> float: ...
    def b(self, state: _Numbers, torques: Optional[_Numbers] = None) -> float: ...
    def painleve(self, theta: _Numbers, direction: str = "negative") -> bool: ...
    def contact_mode(self, state: _Numbers, torques: Optional[_Numbers] = None, v_stick: float = 1e-9) -> str: ...
    def energy(self, state: _Numbers) -> float: ...

class Plant:
    """The hybrid plant (``plant::Plant``), advanced under held torques.

    ``Plant(scenario=None, *, state=None, **params)``: the plant of
    ``scenario``'s ``[plant]`` (``None``: the default scenario's, paper Table I,
    ``mu = 0.6``, ``v_belt = -0.4`` m/s, from ``x0 = "a"`` as
    :func:`painleve.simulate`), the keys of ``[plant]`` given as keywords
    replacing its values, and ``state`` ``(4,)`` (rad, rad/s) replacing the
    paper's initial condition.

    Raises:
        PainleveError: bad parameters or initial state (``exit_code`` 2).
        TypeError: an unknown keyword.
    """

    def __init__(
        self,
        scenario: Union[None, Scenario, str, PathLike[str]] = None,
        *,
        state: Optional[Sequence[float]] = None,
        mu: float = ...,
        v_belt: float = ...,
        x0: Literal["a", "d", "u"] = ...,
        impact_law: Literal["newton", "poisson", "energetic"] = ...,
        e_n: float = ...,
        iwc: Literal["restitution", "plastic"] = ...,
        singular: Literal["leave", "slide"] = ...,
        rtol: float = ...,
        atol: float = ...,
        max_step: float = ...,
        m: float = ...,
        l: float = ...,
        sigma: float = ...,
        k: float = ...,
        h: float = ...,
        alpha0: float = ...,
        g: float = ...,
    ) -> None: ...
    def advance(self, dt: float, torques: _Torques = (0.0, 0.0)) -> Step:
        """Advances ``dt`` s (>= 0) with ``torques = (u1, u2)`` N m held.
        Raises PainleveError: bad ``dt`` or torques (exit code 2), a failure of
        the plant (exit code 1; the plant is left at the failure time)."""
    def advance_to(self, t: float, torques: _Torques = (0.0, 0.0)) -> Step:
        """Advances to time ``t`` s (>= :attr:`time`)."""
    def reset(self, state: Optional[Sequence[float]] = None, t: Optional[float] = None) -> None:
        """Back to time 0, counters cleared; with ``state`` ``(4,)``, to that state at time ``t`` (refused below the belt)."""
    def copy(self) -> Plant: ...
    def contact_force(self, torques: _Torques = (0.0, 0.0)) -> _F64:
        """``(2,)``: ``[f_t, f_n]`` N in the current mode under ``torques``."""
    @property
    def time(self) -> float:
        """s."""
    @property
    def state(self) -> _F64:
        """``(4,)``: theta1 rad, theta1_dot rad/s, theta2 rad, theta2_dot rad/s."""
    @state.setter
    def state(self, value: Sequence[float]) -> None: ...
    @property
    def tip(self) -> _F64:
        """``(2,)``: ``[z_t, z_n]``, m."""
    @property
    def tip_velocity(self) -> _F64:
        """``(2,)``: ``[z_t_dot, z_n_dot]``, m/s."""
    @property
    def mode(self) -> Literal["flight", "sliding", "sticking"]: ...
    @property
    def energy(self) -> float:
        """Mechanical energy, J."""
    @property
    def counters(self) -> Dict[str, Union[int, float]]:
        """Event counts since creation (``plant::Counters`` as ``summary.json`` writes them: ``lift_offs`` every departure from the belt, ``lift_offs_from_contact`` those without the bounces)."""
    @property
    def validity(self) -> Dict[str, int]:
        """Validity counters (``plant::Validity``)."""
    @property
    def ledger(self) -> Dict[str, Union[int, float]]:
        """The energy ledger since creation (``plant::Ledger``), J: ``energy_change_j``,
        ``motors_j``, ``damping_j``, ``belt_j``, ``slip_j``, ``projections_j``, ``residual_j``, ..."""
    @property
    def startup_events(self) -> List[Dict[str, Any]]: ...
    @property
    def params(self) -> Dict[str, float]:
        """``m, l, sigma, k, h, alpha0, g, mu, v_belt`` (SI, rad)."""
    @property
    def scenario(self) -> Scenario: ...

class Sensed:
    """One sensor frame decoded to SI units, as the firmware decodes it."""

    @property
    def k(self) -> int:
        """Period index."""
    @property
    def t(self) -> float:
        """Sample time ``k Ts``, s."""
    @property
    def theta1(self) -> float:
        """rad (14-bit encoder), NaN in an invalid frame."""
    @property
    def theta2(self) -> float:
        """rad (theta1 + the elbow encoder's angle)."""
    @property
    def theta1_dot(self) -> float:
        """rad/s, alpha-beta tracker estimate (0 at period 0)."""
    @property
    def theta2_dot(self) -> float:
        """rad/s, as theta1_dot."""
    @property
    def f_t(self) -> float:
        """N (12-bit load cell, noisy)."""
    @property
    def f_n(self) -> float:
        """N (12-bit load cell, noisy)."""
    @property
    def v_belt(self) -> float:
        """m/s (belt encoder, 1 mm/s)."""
    @property
    def z_t(self) -> float:
        """m, from the sensed angles."""
    @property
    def z_n(self) -> float:
        """m, from the sensed angles (the belt at -H)."""
    @property
    def state(self) -> _F64:
        """``(4,)``: theta1, theta1_dot, theta2, theta2_dot (rad, rad/s)."""
    @property
    def valid(self) -> bool: ...
    @property
    def fault(self) -> Optional[str]: ...
    @property
    def frame(self) -> Dict[str, int]:
        """The raw ``SensorFrame`` (counts and codes)."""

class Command:
    """The firmware's answer to a frame, decoded; ``u1, u2 = command``."""

    @property
    def u1(self) -> float:
        """N m."""
    @property
    def u2(self) -> float:
        """N m."""
    @property
    def torques(self) -> _F64:
        """``(2,)``: ``[u1, u2]``, N m."""
    @property
    def seq(self) -> int: ...
    @property
    def status(self) -> int:
        """Status word (``shared::wire::status`` bits)."""
    @property
    def status_text(self) -> str: ...
    @property
    def lift_off(self) -> bool: ...
    @property
    def safe_state(self) -> Optional[str]: ...
    @property
    def t_sent(self) -> float:
        """s."""
    @property
    def raw(self) -> Dict[str, int]: ...
    @property
    def telemetry(self) -> Dict[str, Any]: ...
    def __len__(self) -> int: ...
    def __getitem__(self, i: int) -> float: ...

class Firmware:
    """The firmware's control step of a scenario (``rig::firmware_side``).

    Raises:
        PainleveError: an invalid firmware configuration (``exit_code`` 2).
    """

    def __init__(self, scenario: Union[None, Scenario, str, PathLike[str]] = None) -> None: ...
    def step(self, frame: Union[Sensed, Dict[str, float]]) -> Command:
        """Answers a :class:`Sensed` or a dict ``theta1``, ``theta2`` (rad),
        ``f_t``, ``f_n`` (N), optional ``v_belt`` (m/s), ``k``. Raises KeyError
        (missing key), TypeError (wrong type)."""
    def reset(self) -> None: ...
    @property
    def k(self) -> int: ...
    @property
    def period(self) -> float:
        """Ts, s."""
    @property
    def safe_state(self) -> Optional[str]: ...
    @property
    def scenario(self) -> Scenario: ...

def run_controller(
    controller: Callable[[float, Sensed], Any], scenario: Optional[Scenario] = None, duration: Optional[float] = None
) -> _Raw:
    """The closed loop with ``controller`` as the firmware; call
    :func:`painleve.run_controller` instead."""
