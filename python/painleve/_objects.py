"""Objects a researcher holds and steps (docs/python.md, "Objects"):
:class:`Scenario`, :class:`Model`, :class:`Plant`, :class:`Firmware`, and :func:`run_controller`,
the closed loop with a Python callable in place of the firmware.

The classes are the compiled module's (``painleve._painleve``, python/src/objects);
this module adds the Python-level entry point :func:`run_controller`, which
returns a :class:`painleve.Result` as :func:`painleve.run` does."""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Mapping, Optional, Sequence, Union

from . import _args, _painleve
from ._painleve import Command, Firmware, Model, Plant, Scenario, Sensed, Step
from ._api import _finish
from ._result import Result

__all__ = ["Scenario", "Model", "Plant", "Step", "Firmware", "Command", "Sensed", "run_controller"]

#: A controller: ``controller(t, sensed) -> (u1, u2)``; ``t`` in s, ``sensed`` a
#: :class:`Sensed`, the torques in N m.
Controller = Callable[[float, Sensed], Union[Sequence[float], Command]]


def run_controller(
    controller: Controller,
    scenario: Union[None, Scenario, str, "os.PathLike[str]", Mapping[str, Any]] = None,
    *,
    duration: Optional[float] = None,
    strict: bool = False,
) -> Result:
    """Closed loop of a scenario with the Python callable ``controller`` in place
    of the firmware: the rig's plant side (``rig::run_loop``, ``rig::PeriodLoop``:
    the sensor models and faults of the scenario, the command taking effect at
    ``t_k + delta`` and held until the next one) over a ``rig::FirmwareLink``
    that calls ``controller`` (python/src/objects/controller_loop.rs).

    Every control period ``k`` (``t_k = k Ts``), ``controller(t_k, sensed)`` is
    called with a :class:`Sensed`: what the firmware would see, decoded to SI
    units (``theta1``, ``theta2`` rad from the 14-bit encoders; ``f_t``, ``f_n``
    N from the 12-bit load cell with its noise; ``v_belt`` m/s; ``theta1_dot``,
    ``theta2_dot`` rad/s from an alpha-beta tracker; ``z_t``, ``z_n`` m from the
    sensed angles). It returns the motor torques ``(u1, u2)`` in N m: a tuple,
    a list, a ``(2,)`` array or a :class:`Command`.

    Differences from the firmware's path (:func:`painleve.run`): none in the
    torques (they go out as the firmware's 12-bit torque codes, saturated at
    5 N m; the trace's ``u1_cmd``, ``u2_cmd`` are the values returned); the
    firmware's checks (bad or stale frames, deadline misses, safe state,
    monitors) do not run; the trace's ``z_t_ref`` is NaN and ``status`` 0; the
    loop holds the GIL on the calling thread (no progress line).

    Args:
        controller: ``controller(t, sensed) -> (u1, u2)``.
        scenario: ``None`` (the embedded default), a :class:`Scenario`, the path
            of a TOML file, or a dict of its tables merged onto the default
            (``{"plant": {"mu": 0.5}}`` changes only ``plant.mu``).
        duration: run length, s (``timing.duration_s``; ``None``: the scenario's).
        strict: raise :class:`PainleveError` when the run fails part way or has
            a model violation (else a :class:`PainleveWarning`).

    Returns:
        :class:`Result` with ``summary`` (the run summary of :func:`painleve.run`,
        ``transport`` ``"python"``), the table ``trace`` (one row per period,
        the columns of :func:`painleve.run`'s; ``u1_cmd``, ``u2_cmd`` the
        controller's torques, N m), ``extras["scenario"]`` and ``validity``.

    Raises:
        TypeError: ``controller`` is not callable, or returned something that is
            not two numbers (the message names the period ``k`` and ``t``).
        ValueError: it returned a NaN or infinite torque (naming the period).
        PainleveError: a bad scenario or duration (``exit_code`` 2); with
            ``strict``, a run that failed part way (``exit_code`` 1).
        KeyboardInterrupt: Ctrl-C (the run stops within its period).
        Exception: whatever ``controller`` raised, unchanged; the run stops there.
    """
    if not isinstance(strict, bool):
        raise TypeError(f"strict: expected a bool, got {type(strict).__name__}")
    if duration is not None and (isinstance(duration, bool) or not isinstance(duration, (int, float))):
        raise TypeError(f"duration: expected a number of seconds or None, got {type(duration).__name__}")
    raw = _painleve.run_controller(controller, _args.scenario_object(scenario), None if duration is None else float(duration))
    return _finish(raw, strict)
