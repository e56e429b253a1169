"""The package's functions: one per ``sil-host`` command that computes, with the
command's arguments and defaults as keyword arguments (``--v-belt`` is
``v_belt``), computed in this process by the workspace's libraries, returning a
:class:`painleve.Result`. See docs/python.md."""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Callable, Dict, Literal, Mapping, Optional, Sequence, Tuple, Union, cast

from . import _args, _painleve, _progress
from ._result import PainleveWarning, Result

__all__ = [
    "simulate",
    "admissible",
    "modes",
    "poincare",
    "sweep",
    "zmax",
    "run",
    "sensitivity",
    "replay",
    "default_scenario",
    "scenario_toml",
]

Number = Union[int, float]
Range = Union[str, Number, Tuple[Number, Number], Sequence[Number]]
Progress = Union[bool, None, Callable[[int, int], Any]]
Scenario = Union[None, str, "os.PathLike[str]", Mapping[str, Any], "_painleve.Scenario"]

# The choices of the settings (the same as the CLI's: python/tests/test_defaults.py).
PaperX0 = Literal["a", "d", "u"]
"""The paper's initial conditions (Table I): ``x0a``, ``x0d``, ``x0u``."""
ImpactLaw = Literal["newton", "poisson", "energetic"]
"""Impact law at touchdown and for impacts without collision."""
IwcRule = Literal["restitution", "plastic"]
"""Impact-without-collision rule."""
SingularRule = Literal["leave", "slide"]
"""Rule at the singular point ``p = b = 0`` (docs/plant.md)."""
ElbowBranch = Literal["up", "down"]
"""Elbow branch of the arm's configuration."""
Theta2Sign = Literal["auto", "plus", "minus"]
"""Which root of ``theta2`` a mode map follows."""
Controller = Literal["pid", "hybrid"]
"""The firmware's controller."""
SweepController = Literal["none", "hybrid", "pid"]
"""A sweep's controller: ``none`` is the open loop."""
StudySize = Literal["quick", "paper"]
"""The sensitivity study's size."""


def _finish(raw: Mapping[str, Any], strict: bool) -> Result:
    """The result, raising with ``strict`` and warning otherwise when the CLI
    would have exited with an error after writing."""
    result = Result._from_raw(raw)
    if result.failure is not None:
        if strict:
            result.check()
        warnings.warn(f"{result.command}: {result.failure}", PainleveWarning, stacklevel=3)
    return result


def simulate(
    *,
    x0: Optional[PaperX0] = None,
    x0_deg: Optional[Union[str, Sequence[Number]]] = None,
    mu: float = 0.6,
    v_belt: float = -0.4,
    impact_law: ImpactLaw = "newton",
    e_n: float = 0.2,
    duration: float = 10.0,
    sample_dt: float = 1e-3,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    max_step: Optional[float] = None,
    iwc: IwcRule = "restitution",
    singular: SingularRule = "leave",
    set: _args.Overrides = None,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """Open-loop simulation (``u = 0``) of the arm on the belt: ``sil-host simulate``.

    Args:
        x0: the paper's initial condition ``"a"``, ``"d"`` or ``"u"`` (projected
            onto the belt); ``None``: ``"a"``, the CLI's default. Given with
            ``x0_deg``, even as ``"a"``, the pair is refused as the CLI refuses
            ``--x0`` with ``--x0-deg``.
        x0_deg: instead, ``(theta1, theta1_dot, theta2, theta2_dot)`` in degrees
            and deg/s (a tip up to 1 mm inside the belt is projected onto it).
        mu: friction coefficient (>= 0).
        v_belt: belt speed, m/s.
        impact_law: ``"newton"``, ``"poisson"`` or ``"energetic"``.
        e_n: restitution coefficient in [0, 1].
        duration: simulated time, s.
        sample_dt: sampling period of the trace, s (events at their exact times).
        rtol, atol: the integrator's tolerances.
        max_step: the largest integrator step, s (``None``: the tolerances and the
            samples set the steps; a cap gives a reference run whose steps differ).
        iwc: impact-without-collision rule, ``"restitution"`` (the tip is
            thrown off the belt) or ``"plastic"`` (left on it, ``v_n = 0``): a
            Moreau-Jean time-stepper such as Siconos leaves the tip on the belt,
            so compare with one under ``"plastic"``; docs/plant.md.
        singular: the rule where a slide reaches ``p = 0`` and ``b = 0`` with a
            finite force, ``"leave"`` (the tip leaves the belt) or ``"slide"``
            (it slides on through the indeterminate region); docs/plant.md.
        set: the arm's parameters (paper Table I, SI, radians): ``{"plant.m":
            0.24}`` or ``["plant.m=0.24"]``; keys ``plant.m``, ``plant.l``,
            ``plant.sigma``, ``plant.k``, ``plant.h``, ``plant.alpha0``, ``plant.g``.
        strict: raise :class:`PainleveError` (exit code 1) on a model violation.
        progress: ``True`` a progress line (on stderr, rewritten in place; in
            a Jupyter notebook one output updated in place), ``False`` none,
            or a callable ``f(done, total)`` (samples).

    Returns:
        :class:`Result` with ``summary`` (``summary.json``: parameters,
        initial condition (``used_deg`` the state before any impulse at
        ``t = 0``, ``after_startup_deg`` after them), ``lift_offs`` (every
        departure from the belt, as in every result), ``counters``,
        ``validity``, final state) and tables:

        Every table is ``{column: array}``, each column a NumPy array of shape
        ``(n,)`` (float64, int64, bool, or str for text), ``n`` its rows.

        ``trace`` (one row per sample, ``n = round(duration / sample_dt) + 1``
        with the row of ``t = 0``; fewer when the run failed part way): ``t`` s, ``theta1`` rad, ``theta1_dot``
        rad/s, ``theta2`` rad, ``theta2_dot`` rad/s, ``z_t`` m, ``z_n`` m,
        ``z_t_dot`` m/s, ``z_n_dot`` m/s, ``z_r_dot`` m/s (``z_t_dot - v_belt``),
        ``f_t`` N, ``f_n`` N, ``mode`` (``flight``, ``sliding``, ``sticking``),
        ``energy`` J.

        ``events`` (every event at its located time): ``t`` s, ``kind``,
        ``mode_after``, ``v_n_before``, ``v_n_after``, ``v_r_before``,
        ``v_r_after`` m/s, ``impulse_t``, ``impulse_n`` N s, ``energy_change``,
        ``contact_work`` J, ``resolution``.

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
        KeyboardInterrupt: Ctrl-C (the simulation stops within its chunk of 1024 samples).

    A simulation that fails part way returns what it computed up to then, with
    ``failure`` set and a :class:`PainleveWarning` (``strict=True`` raises).
    """
    return _finish(_args.call("simulate", simulate, dict(locals()), progress), strict)


def admissible(*, mu: float = 0.6, set: _args.Overrides = None) -> Result:
    """Admissible configurations (paper Table II): the ranges of ``z_t`` on the
    belt where ``p > 0``, per elbow branch and slip direction: ``sil-host admissible``.

    Args:
        mu: friction coefficient (>= 0).
        set: ``plant.l`` and ``plant.h`` (m), the only parameters that move the ranges.

    Returns:
        :class:`Result` with ``summary`` = ``admissible.json``:
        ``z_r_dot_positive`` (the paper's case) and ``z_r_dot_negative``, each
        ``{"elbow_up": [[lo, hi], ...], "elbow_down": [...]}`` in m; ``reach_m``,
        ``mirror_check``, ``params``; and the table ``intervals`` (one row per
        interval, each column a NumPy array of shape ``(n,)``): ``direction``
        (``z_r_dot_positive``/``z_r_dot_negative``), ``branch`` (``elbow_up``/
        ``elbow_down``), ``lo_m``, ``hi_m``. No simulation: ``validity`` is ``None``.

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
    """
    return _finish(_args.call("admissible", admissible, dict(locals())), False)


def modes(
    *,
    mu: float = 0.6,
    v_belt: float = -0.4,
    branch: ElbowBranch = "down",
    theta1_deg: Range = (-90.0, 90.0),
    theta1_dot: Range = (-10.0, 10.0),
    grid: int = 400,
    theta2_sign: Theta2Sign = "plus",
    set: _args.Overrides = None,
) -> Result:
    """Mode map (paper Fig. 2): the contact mode over a grid of ``(theta1,
    theta1_dot)`` with the tip on the belt: ``sil-host modes``.

    Args:
        mu: friction coefficient (>= 0).
        v_belt: belt speed, m/s (sets the sign of ``z_r_dot``).
        branch: elbow branch ``"down"`` or ``"up"`` (with ``theta2_sign="auto"``).
        theta1_deg: ``(min, max)`` of ``theta1``, degrees.
        theta1_dot: ``(min, max)`` of ``theta1_dot``, rad/s.
        grid: points per axis (2 to 1000).
        theta2_sign: ``"plus"``, ``"minus"`` or ``"auto"`` (see ``sil-host modes --help``).
        set: the arm's parameters (paper Table I), as for :func:`simulate`.

    Returns:
        :class:`Result` with ``summary`` (the ``--json`` document: counts per
        mode, ``p_zero``, ranges) and the table ``modes`` (``n = grid**2`` rows,
        ``theta1`` outer; each column a NumPy array of shape ``(n,)``): ``theta1_rad``, ``theta1_deg``, ``theta1_dot`` rad/s,
        ``theta2_rad``, ``b`` m/s^2, ``p`` 1/kg, ``z_r_dot`` m/s, ``mode``
        (``sliding``, ``flight``, ``indeterminate``, ``inconsistent``,
        ``unreachable``, ``singular``), ``theta2_dot`` rad/s, ``branch``;
        NaN where a quantity does not exist. ``extras``: ``theta1_deg`` and
        ``theta1_dot`` (the axes), ``b_zero`` and ``zr_zero`` (curves ``b = 0``
        and ``z_r_dot = 0``, lists of ``(n, 2)`` arrays of ``(theta1 deg,
        theta1_dot rad/s)``). No simulation: ``validity`` is ``None``.

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
    """
    return _finish(_args.call("modes", modes, dict(locals())), False)


def poincare(
    *,
    mu: float = 0.6,
    x0: Optional[PaperX0] = None,
    x0_deg: Optional[Union[str, Sequence[Number]]] = None,
    v_belt: Range = (-0.9, -0.3),
    v_step: float = 0.002,
    transient: float = 250.0,
    record: float = 50.0,
    tol: float = 1e-4,
    max_period: int = 32,
    section_depth: float = 1e-6,
    chaos_threshold: float = 0.01,
    lyap_iterations: int = 200,
    lyap_skip: int = 20,
    lyap_d0: float = 1e-7,
    impact_law: ImpactLaw = "newton",
    e_n: float = 0.2,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    threads: Optional[int] = None,
    iwc: IwcRule = "restitution",
    singular: SingularRule = "leave",
    set: _args.Overrides = None,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """One-parameter bifurcation diagram (paper Fig. 4): ``theta1`` at the upward
    crossings of ``theta1_dot = 0`` over a grid of belt speeds, each classified:
    ``sil-host poincare``. Runs in parallel (``threads``, one per core by default).

    Args:
        v_belt: ``(min, max)`` (both ends included) or one speed, m/s.
        v_step: grid step, m/s.
        transient, record: discarded transient and record window, s.
        tol, max_period: the period test on section points (rad).
        section_depth: hysteresis of the section, rad/s.
        chaos_threshold, lyap_iterations, lyap_skip, lyap_d0: the Lyapunov estimate.
        The others as for :func:`simulate`.

    Returns:
        :class:`Result` with ``summary`` (``summary.json``: counts, bands,
        ``validity``) and tables (each column a NumPy array of shape ``(n,)``, ``n``
        the table's rows):

        ``section`` (one row per crossing of the section, all belt speeds): ``v_belt`` m/s, ``t`` s, ``theta1`` rad, ``theta1_deg``,
        ``theta1_dot`` rad/s, ``theta2`` rad, ``theta2_dot`` rad/s, ``kind``
        (``smooth``/``jump``), ``mode``.

        ``classes`` (per belt speed): ``v_belt``, ``class``, ``period``,
        ``n_crossings``, ``distinct_points``, ``lyapunov_per_crossing``,
        ``lyapunov_per_s`` 1/s, ``lyapunov_std_error``, ``lyapunov_iterations``,
        ``lyapunov_collapsed``, ``final_mode``, ``final_theta1`` rad,
        ``lift_offs``, ``touchdowns``, ``error``, ``wall_s``, and the validity
        counters ``energy_gains``, ``newton_fallbacks``, ``poisson_fallbacks``,
        ``cone_violations``, ``zeno_stops``, ``integrator_failures``.

        ``extras["classes"]``: ``classes.json`` (per speed, with its crossings).

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
        KeyboardInterrupt: Ctrl-C (stops before the next belt speed).
    """
    return _finish(_args.call("poincare", poincare, dict(locals()), progress), strict)


def sweep(
    *,
    mu: Range = (0.1, 1.0),
    mu_step: float = 0.1,
    v_belt: Range = (-1.0, -0.1),
    v_belt_step: float = 0.005,
    ics: Union[str, Sequence[str]] = ("a", "d"),
    random_ics: int = 0,
    seed: int = 1,
    seeds: int = 1,
    jitter_mu: float = 0.0,
    jitter_start: float = 0.0,
    jitter_f_n_ref: float = 0.0,
    jitter_delay: float = 0.0,
    transient: float = 250.0,
    record: float = 50.0,
    controller: SweepController = "none",
    ideal: bool = False,
    scenario: Scenario = None,
    impact_law: Union[ImpactLaw, Sequence[ImpactLaw]] = ("newton",),
    e_n: Union[float, Sequence[float]] = (0.2,),
    iwc: Union[IwcRule, Sequence[IwcRule]] = ("restitution",),
    singular: SingularRule = "leave",
    threshold: float = 1e-6,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    set: _args.Overrides = None,
    shard: Optional[str] = None,
    limit: Optional[int] = None,
    threads: Optional[int] = None,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """Two-parameter brute-force bifurcation diagram (paper Figs. 3 and 9): a grid
    in ``(mu, v_belt)`` (and impact law, ``e_n``, IWC rule), each run a transient
    then a record window: ``sil-host sweep``, in memory (no folder, no journal:
    nothing to resume). Runs in parallel (``threads``, all cores by default).

    Args:
        mu: ``(min, max)`` or one value, spaced by ``mu_step``.
        v_belt: ``(min, max)`` or one value, m/s, spaced by ``v_belt_step``.
        ics: the paper's initial conditions (``"a"``, ``"d"``, ``"u"``), or ``"none"``.
        random_ics, seed: random initial conditions in contact, and their seed
            (also the seed of the jitter's draws).
        seeds: runs per grid point (``sil-host sweep --seeds``): seed 0 the
            nominal run, seeds 1.. the sensor noise's next seeds and the
            jitter's draws; each cell then a fraction with its Wilson 95 %
            interval (the ``cells`` table). The open loop and ``ideal=True``
            have no noise: there ``seeds > 1`` needs ``jitter_mu`` or
            ``jitter_start``.
        jitter_mu, jitter_start, jitter_f_n_ref, jitter_delay: half-widths of
            the uniform jitter of seeds 1.. of ``mu``, the start's ``z_t`` (m),
            ``f_n*`` (N, sampled closed loop) and the command delay (s, sampled
            closed loop).
        transient, record: the windows, s.
        controller: ``"none"`` (open loop), ``"hybrid"`` or ``"pid"`` (the
            firmware in-process, sampled), with ``ideal=True`` the paper's
            continuous-time law.
        scenario: closed loop: a scenario path or dict (:func:`run`).
        impact_law, e_n, iwc: sweep dimensions (lists).
        singular: the singular-point rule, ``"leave"`` or ``"slide"`` (one for all runs).
        threshold: bouncing when ``max theta1_dot`` over the record exceeds it, rad/s.
        set: open loop: the arm's parameters; closed loop: any scenario key but
            those the sweep sets.
        shard: ``"K/N"``, this shard's runs only; limit: at most this many runs.

    Returns:
        :class:`Result` with ``summary`` (``summary.json``: ``spec``,
        ``results`` with the critical ``mu``, the bands, outcome counts and
        ``validity``, ``timing``) and the table ``sweep`` (one row per run, by
        index, ``sweep.csv``'s rows; each column a NumPy array of shape ``(n,)``,
        ``n`` the runs): ``index``, ``impact_law``, ``e_n``, ``iwc``,
        ``mu``, ``v_belt`` m/s, ``ic``, ``outcome``, ``bouncing``,
        ``theta1_dot_max`` rad/s, ``t_theta1_dot_max`` s, ``lift_offs``,
        ``touchdowns``, ``impacts_without_collision``, ``z_n_max`` m,
        ``tip_height_max`` m, ``final_mode``, ``target_error_m`` m (closed
        loop), ``lift_offs_transient``, ``rhs_evaluations``, the validity
        counters ``energy_gains``, ``newton_fallbacks``, ``poisson_fallbacks``,
        ``cone_violations``, ``zeno_stops``, ``jams``, ``integrator_failures``,
        and ``error``; and the table ``cells`` (one row per grid point and
        initial condition over its seeds, ``cells.csv``'s rows when ``seeds >
        1``): ``runs``, the counts ``lift_off``, ``safe_state``, ``contact``,
        ``other``, each fraction with its Wilson 95 % interval
        (``lift_off_fraction``, ``lift_off_lo``, ``lift_off_hi``, ...),
        ``undecided`` (an interval holds one half) and ``boundary`` (the seeds
        disagree). ``summary["samples"]`` says what each cell is drawn from,
        ``summary["ensemble"]`` (``seeds > 1``) the fractions per ``mu``.

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
        KeyboardInterrupt: Ctrl-C (every run stops within 10 s of simulated time).
    """
    return _finish(_args.call("sweep", sweep, dict(locals()), progress, scenario), strict)


def zmax(
    *,
    controller: Controller = "hybrid",
    x0: PaperX0 = "d",
    ideal: bool = False,
    all: bool = False,
    tol: float = 1e-3,
    bracket: Optional[Range] = None,
    duration: float = 10.0,
    reach_tol: float = 5e-3,
    settle_tol: float = 1e-3,
    settle_window: float = 1.0,
    iwc: Optional[IwcRule] = None,
    lift_off_gap: float = 0.0,
    scenario: Scenario = None,
    set: _args.Overrides = None,
    seeds: int = 1,
    jitter_mu: float = 0.0,
    jitter_start: float = 0.0,
    jitter_f_n_ref: float = 0.0,
    jitter_delay: float = 0.0,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """``Z_t,sliding`` by bisection (experiments 5 and 6): the largest target the
    tip slides to with no lift-off, and the tracking limit: ``sil-host zmax``.

    Args:
        controller: ``"pid"`` or ``"hybrid"``; x0: ``"d"`` or ``"u"``;
            ideal: the paper's ideal law instead of the sampled firmware;
            all: the eight cases, in parallel.
        tol: bisection tolerance, m; bracket: ``(lo, hi)`` targets, m.
        duration: trial length, s; reach_tol, settle_tol: m; settle_window: s.
        iwc: the base scenario's IWC rule; lift_off_gap: lift-off criterion, m.
        scenario: base scenario (path or dict); set: its overrides.
        seeds: one bisection per sensor-noise seed for the sampled cases
            (``sil-host zmax --seeds``); jitter_f_n_ref (N), jitter_delay (s):
            the uniform jitter of seeds 1.. (jitter_mu and jitter_start are
            refused: they are for sweeps).

    Returns:
        :class:`Result` with ``summary`` (``summary.json``: ``results``,
        ``trials``, ``criteria``, ``validity``, gains) and tables (each column a
        NumPy array of shape ``(n,)``, ``n`` the table's rows):

        ``zmax`` (one row per case): ``controller``, ``x0``, ``setting``,
        ``outcome``, ``z_t_sliding_m``, ``error_at_limit_m``,
        ``first_failing_m``, ``stop_failing``, ``why_failing``,
        ``paper_z_t_sliding_m``, ``tracking_outcome``, ``z_t_tracking_m``,
        ``tracking_first_failing_m``, ``tracking_stop_failing``,
        ``tracking_why_failing``, ``bracket_lo_m``, ``bracket_hi_m``,
        ``p_zero_end_m``, ``theta1_fold_m`` (all m), ``trials``,
        ``invalid_trials``, ``wall_s``.

        ``trials`` (every trial): ``controller``, ``x0``, ``setting``,
        ``target_z_t_m``, ``stop``, ``slides_to_target``, ``tracked``,
        ``lift_offs``, ``impacts_without_collision``, ``first_lift_off_s``,
        ``settle_error_m``, ``failure``, ``simulated_s``, ``wall_s`` and the
        validity counters.

        ``zmax_seeds`` (``seeds > 1``: each sampled case's search per seed):
        ``controller``, ``x0``, ``setting``, ``seed``, ``outcome``,
        ``z_t_sliding_m``, ``error_at_limit_m``, ``first_failing_m``,
        ``stop_failing``, ``z_t_tracking_m``, ``trials``; their spread
        (median, quartiles, range) in ``summary["distributions"]``.

        ``extras["limit_traces"]``: ``{case: Table}``, the run at the limit
        (``t`` s, ``z_t``, ``z_t_ref`` m, ``f_n`` N, torques N m, ``mode``).

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
        KeyboardInterrupt: Ctrl-C (each search stops before its next trial).
    """
    return _finish(_args.call("zmax", zmax, dict(locals()), progress, scenario), strict)


def run(
    scenario: Scenario = None,
    *,
    controller: Optional[Controller] = None,
    x0: Optional[PaperX0] = None,
    target_zt: Optional[float] = None,
    duration: Optional[float] = None,
    seed: Optional[int] = None,
    iwc: Optional[IwcRule] = None,
    set: _args.Overrides = None,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """Closed-loop SIL run of a scenario with the firmware step linked into this
    process, in lockstep: ``sil-host run --in-process`` (the same trace, bit for
    bit, as the iceoryx2 run of the same scenario and seed).

    Args:
        scenario: ``None`` (the embedded default: hybrid from ``x0d``, ``mu =
            0.6``, ``v_belt = -0.4 m/s``, ``z_t* = 0.10 m``, 10 s at 1 kHz), the
            path of a TOML file (``scenarios/pid-x0u.toml``), or a dict of its
            tables (:func:`default_scenario` gives one to change).
        controller, x0, target_zt (m), duration (s), seed, iwc: override the
            scenario (``--controller``, ...).
        set: scenario keys, ``{"plant.m": 0.24, "controller.pid.kp": [150, 0]}``
            or ``["plant.m=0.24"]`` (a key set by a flag too is refused).

    Returns:
        :class:`Result` with ``summary`` (``summary.json``: lift-off
        statistics, deadline misses, tracking error, ``validity``, the
        firmware's announcement), the table ``trace`` (one row per period, ``n =
        duration x rate`` rows, fewer when the run stopped early; each column a
        NumPy array of shape ``(n,)``):
        ``t`` s, ``theta1`` rad, ``theta1_dot`` rad/s, ``theta2`` rad,
        ``theta2_dot`` rad/s, ``z_t``, ``z_n``, ``z_t_ref`` m, ``f_t``, ``f_n``
        N, ``mode``, ``u1_cmd``, ``u2_cmd``, ``u1_applied``, ``u2_applied`` N m,
        ``lift_off_true``, ``lift_off_detected``, ``deadline_miss``,
        ``firmware_deadline_miss``, ``overruns``, ``status`` (the firmware's
        status word), and ``extras["scenario"]``, the scenario as run.

    Raises:
        PainleveError: bad scenario or overrides, with the CLI's message
            (``exit_code`` 2).
        KeyboardInterrupt: Ctrl-C (the run stops within its period).

    A run that stops early (safe state, plant failure) returns its periods up to
    then, with ``failure`` set and a :class:`PainleveWarning`.
    """
    return _finish(_args.call("run", run, dict(locals()), progress, scenario), strict)


def replay(
    folder: Union[str, "os.PathLike[str]"],
    *,
    link: Literal["in-process"] = "in-process",
    set: _args.Overrides = None,
    all: bool = False,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """Replays a recorded run through the firmware: ``sil-host replay FOLDER
    --link in-process``. Every recorded frame goes to the firmware step linked
    into this process, configured from the run's own scenario (``summary.json``'s
    ``scenario_used``, after ``set``), and every answer (the command's codes,
    status and overruns, the telemetry's ten 32-bit floats) is compared with
    the recorded one bit for bit. The other links (iceoryx2, the board twin, the
    emulated board, PIL) are ``sil-host replay --link ...``'s.

    Args:
        folder: the ``--out`` folder of ``sil-host run`` or ``pil`` (its
            ``summary.json`` and ``frames.csv``, ``frames.arrow`` or
            ``trace.mcap``).
        link: ``"in-process"`` (the only link in this process).
        set: scenario keys changed before the replay, as :func:`run`'s ``set``
            (``{"controller.hybrid.kp": 2001}``): a changed gain shows where the
            commands first move.
        all: compare every period (``divergent_periods`` counts them all)
            rather than stop at the first divergence.
        strict: raise :class:`PainleveError` (``exit_code`` 1) at a divergence
            instead of warning.

    Returns:
        :class:`Result` whose ``summary`` is ``sil-host replay --json``'s
        document: ``identical`` (bool), ``periods_recorded``,
        ``periods_replayed``, ``divergent_periods``, ``first_divergence``
        (``period``, ``t`` s, ``signal``, ``recorded``, ``replayed``, or
        ``None``), ``link``, ``signals`` (what is compared), ``wall_s``. A
        divergence sets ``failure`` (the verdict) and ``exit_code`` 1, with a
        :class:`PainleveWarning`.

    Raises:
        PainleveError: ``exit_code`` 2 for a folder that is not a run's, a
            recording cut off or of another scenario than the one replayed
            (naming the setting), a bad ``set``, another ``link``.
    """
    native = _painleve.replay
    try:
        raw = native(os.fspath(folder), _args.overrides(set), bool(all), str(link), _progress.resolve(progress))
    except _painleve.PainleveError as e:
        e.args = (_args.pythonic(str(e)),)
        raise
    return _finish(raw, strict)


def sensitivity(
    *,
    size: StudySize = "quick",
    scenario: Scenario = None,
    set: _args.Overrides = None,
    threads: Optional[int] = None,
    seeds: int = 1,
    strict: bool = False,
    progress: Progress = True,
) -> Result:
    """The headline results under each open modelling and firmware choice, one at
    a time: ``sil-host sensitivity`` (``size="quick"``: about a minute on 2
    cores; ``"paper"``: hours). ``seeds``: runs per belt speed of the hybrid
    closed loop's sweeps (sensor-noise seeds; its results then fractions with
    Wilson 95 % intervals).

    Returns:
        :class:`Result` with ``summary`` (``summary.json``: ``study`` with
        per choice its results and ``validity``, ``base_scenario``) and the
        table ``sensitivity`` (one row per choice and result; each column a NumPy
        array of shape ``(n,)``): ``choice``, ``value``, ``is_default``,
        ``result``, ``outcome``.

    Raises:
        PainleveError: bad input, with the CLI's message (``exit_code`` 2).
        KeyboardInterrupt: Ctrl-C (stops within the running jobs).
    """
    return _finish(_args.call("sensitivity", sensitivity, dict(locals()), progress, scenario), strict)


def default_scenario() -> Dict[str, Any]:
    """The embedded default scenario (``scenarios/default.toml``) as a dict of its
    TOML tables, to change and pass to :func:`run` (or ``scenario=`` of
    :func:`sweep`, :func:`zmax`, :func:`sensitivity`)."""
    return cast(Dict[str, Any], json.loads(_painleve.toml_to_json(_painleve.default_scenario_toml())))


def scenario_toml(scenario: Mapping[str, Any]) -> str:
    """A scenario dict as the TOML text of a scenario file."""
    return _args.scenario_toml(scenario)
