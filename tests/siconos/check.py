#!/usr/bin/python3
"""Siconos 4.4 as an independent implementation of the arm on the belt (issue 67).

Builds the paper's arm (docs/model.md, paper eqs. 1 to 7, Table I) in Siconos
(Debian bookworm's python3-siconos 4.4: LagrangianDS, LagrangianRheonomousR,
NewtonImpactFrictionNSL, MoreauJeanOSI, TimeStepping, FrictionContact 2D Lemke) and checks
`sil-host simulate --iwc plastic` against it:

1. both start from the same projected x0a and x0d;
2. from x0a (e_n 0.2, v_belt -0.5 m/s) mu 0.365 slides and mu 0.366 bounces, in both;
3. at mu 0.6 the bounce's lift-offs per 50 s and its largest gap agree within the step-size
   convergence Siconos itself shows (h 1e-4 s against 2e-5 s);
4. from x0d at mu 0.6 the tip slides to the same z_t;
5. at v_belt -0.4 m/s the bounce from x0a at mu 0.6 is locked (49 lift-offs every 10 s): its
   lift-offs in 30 s agree within the same convergence (Siconos at h 1e-4 and 5e-5 s), which a
   link 4 % heavier or lighter fails;
6. the singular point p = b = 0 on issue 53's arm, both regimes (Siconos at h 1e-5 and 1e-6 s):
   at mu 0.43 the slide is attracted into it and the slip is arrested there; at mu 0.44, from
   0.5 mm further along the belt, the force vanishes first and the tip lifts off with its slip;
and prints the run-time ratio Siconos / sil-host on the same case, measured in this run.
`--perturb-mass F` gives sil-host links F times as heavy as Siconos' (Siconos keeps the paper's):
with 1.04 or 0.96 the check must fail.

Run with Debian's system Python (python3-siconos installs there, not in a venv):

    /usr/bin/python3 tests/siconos/check.py --sil-host target/release/sil-host

Exit codes: 0 every check passed, 1 a check failed, 2 Siconos (or gcc, or sil-host) missing or
another setup error. tests/siconos/README.md says what each tolerance is and why.
"""

import argparse
import csv
import json
import math
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

# One thread per process: the Siconos runs go two at a time on a 2-core machine.
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

PASS, FAIL, SETUP = 0, 1, 2


class SetupError(Exception):
    """Something this check needs is missing or broken (exit 2): gcc, the plugin, Siconos."""


class SilHostError(Exception):
    """sil-host itself failed on a valid command (exit 1: the implementation under test)."""


# Paper Table I (docs/model.md "Parameters"), SI units; alpha0 in radians.
TABLE_I = {"m": 0.12, "l": 0.21, "sigma": 0.005, "k": 1.3, "h": 0.3775, "alpha0": math.radians(13.72), "g": 9.81}
V_BELT = -0.5  # belt speed, m/s
E_N = 0.2  # Newton's restitution coefficient
THETA = 0.5  # Moreau-Jean's theta (theta 1 damps the bounce: its largest gap 4.49 cm against 4.75 at h 1e-4)
X0A_DEG = (32.0, 18.27)  # docs/model.md x0a: theta1, theta2 in degrees (velocities 0)
X0D_DEG = (-11.4, -35.1)  # docs/model.md x0d
H_COARSE, H_FINE = 1e-4, 2e-5  # Siconos' two time steps, s
BOUNCE_T, BOUNCE_WINDOW = 60.0, (10.0, 60.0)  # mu 0.6: simulated s, and the 50 s counted
BOUNCE_SUBWINDOWS = 5  # the window's parts whose spread sizes the count's sampling term
EDGE_T, EDGE_WINDOW = 6.0, (3.0, 6.0)  # mu 0.365 / 0.366: simulated s, and the window classified
SLIDE_T = 8.0  # x0d: simulated s (the slide settles to 1e-8 m by 7 s)
ON_BELT_M = 1e-5  # a tip within 10 um of the belt is on it (Siconos leaves it < 0.2 um inside)
BOUNCE_MIN_LIFT_OFFS, BOUNCE_MIN_GAP_M = 5, 1e-3  # a bounce: this many lift-offs, this high
ZT_FLOOR_M = 1e-7  # the z_t tolerance's floor: two equal Siconos runs do not ask for bit equality
PROJECTION_TOL_DEG = 1e-6  # both start from the same projected state
LOCKED_V_BELT = -0.4  # x0a, mu 0.6 at this belt speed: the bounce locks onto 49 lift-offs per 10 s
LOCKED_T, LOCKED_WINDOW, LOCKED_SUBWINDOWS = 40.0, (10.0, 40.0), 3  # simulated s, the 30 s counted, its parts
LOCKED_H = (1e-4, 5e-5)  # its Siconos steps, s (2e-5 counts the same 147; 5e-5 runs beside the 2e-5 bounce)
EDGE_COUNT = 1  # a count's floor: two sequences of equal rate and other phases differ by 1 in a window

# The singular point (issue 81): issue 53's arm (paper Table I moved: docs/plant.md "The corner
# search on the corner"), e_n 0.2, v_belt -0.5 m/s, open loop, from rest on the belt.
ISSUE53 = {"m": 0.15, "l": 0.23, "sigma": 0.008, "k": 1.0, "h": 0.40, "alpha0": 0.20, "g": 9.81}
CORNER_H = (1e-5, 1e-6)  # Siconos' two steps at the corner, s (at 1e-4 the arrest comes 1 ms late)
CORNERS = {  # name: mu, start (theta1, theta2 in deg, at rest: projected onto the belt), simulated s, regime
    "attracted": (0.43, (34.53531701873741, 23.744016380660902), 0.006, "arrested"),
    "force first": (0.44, (33.7646, 24.7966), 0.014, "lifted off"),
}
STOP_FRACTION = 0.01  # Siconos arrests the slip: |v_r| falls below 1 % of its value one step earlier
GAP_LEFT_M = 1e-6  # Siconos' tip has left the belt: a stretch of steps without impulse lifts it 1 um


def project(theta1_deg, theta2_deg, params=TABLE_I):
    """The initial condition put on the belt, in radians (docs/model.md "Initial conditions").

    Keeps the tip's z_t = l (sin theta1 + sin theta2) (m) and the elbow branch (down when
    theta2 < theta1), and solves the inverse kinematics of the two equal links for the tip at
    z = [z_t, -H] (docs/model.md "Geometry and state"). Returns (theta1, theta2) in rad.
    """
    l, h = params["l"], params["h"]
    th1, th2 = math.radians(theta1_deg), math.radians(theta2_deg)
    z_t = l * (math.sin(th1) + math.sin(th2))
    reach = math.hypot(z_t, h)  # base to tip, m
    heading = math.atan2(z_t, h)  # of the base-to-tip line, from the downward vertical, rad
    half = math.acos(reach / (2.0 * l))  # half the angle between the links, rad
    return (heading + half, heading - half) if th2 < th1 else (heading - half, heading + half)


def build_plugin(source, folder, params=TABLE_I, v_belt=V_BELT, name="arm_plugin"):
    """Compiles arm_plugin.c with gcc into `folder`/`name`.so, the parameters as -D macros.

    `params`: paper Table I in SI units (docs/model.md "Parameters"); `v_belt` in m/s; `name`
    tells the arms apart (one file per arm). Returns the plugin's path without `.so`: Siconos
    appends it (notes: "plugin names are given without .so"). Raises SetupError when no C
    compiler is found or the compile fails.
    """
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise SetupError("no C compiler (gcc): apt-get install -y gcc")
    defs = {"ARM_M": params["m"], "ARM_L": params["l"], "ARM_SIGMA": params["sigma"], "ARM_K": params["k"],
            "ARM_H": params["h"], "ARM_ALPHA0": params["alpha0"], "ARM_G": params["g"], "ARM_VBELT": v_belt}
    stem = os.path.join(folder, name)
    cmd = [cc, "-O2", "-fPIC", "-shared", "-Wall", "-Wno-unused-parameter", "-o", stem + ".so", source, "-lm"]
    cmd[1:1] = [f"-D{k}={v!r}" for k, v in defs.items()]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SetupError(f"compiling {source} failed:\n{done.stderr}")
    return stem


def siconos_run(plugin, q0, mu, h, duration, e_n=E_N, theta=THETA):
    """Simulates the arm in Siconos from rest at q0 (rad) for `duration` s with time step `h` s.

    The model (Siconos kernel docs: LagrangianDS.hpp, LagrangianRheonomousR.hpp): a LagrangianDS
    M(q) v' + F_gyr + F_int = p with M, F_int = w and F_gyr = c (docs/model.md eq. 1) and their
    Jacobians from the C plugin; a LagrangianRheonomousR h(q, t) = [z_n + H, z_t - v_belt t]
    with G0 = dh/dq and hDot = [0, -v_belt]; NewtonImpactFrictionNSL(e_n, 0, mu, 2); MoreauJeanOSI
    (theta); TimeStepping; FrictionContact(2, SICONOS_FRICTION_2D_LEMKE). Returns a dict of
    per-step arrays: `t` (s), `th1`, `th2` (rad), `th1_dot`, `th2_dot` (rad/s), `p_n`, `p_t` (the
    step's normal and tangential impulse, N s), the first step's impulse `p0` = (P_t, P_n) (N s),
    and `wall_s`, `cpu_s`.
    """
    import numpy as np
    import siconos.kernel as sk
    import siconos.numerics as sn

    wall0, cpu0 = time.perf_counter(), time.process_time()
    ds = sk.LagrangianDS(np.array(q0, dtype=float), np.zeros(2), plugin + ":arm_mass")
    ds.setComputeFIntFunction(plugin, "arm_fint")
    ds.setComputeJacobianFIntqFunction(plugin, "arm_fint_q")
    ds.setComputeJacobianFIntqDotFunction(plugin, "arm_fint_v")
    ds.setComputeFGyrFunction(plugin, "arm_fgyr")
    ds.setComputeJacobianFGyrqFunction(plugin, "arm_fgyr_q")
    ds.setComputeJacobianFGyrqDotFunction(plugin, "arm_fgyr_v")
    relation = sk.LagrangianRheonomousR(plugin + ":arm_h", plugin + ":arm_g0", plugin + ":arm_hdot")
    contact = sk.Interaction(sk.NewtonImpactFrictionNSL(e_n, 0.0, mu, 2), relation)
    nsds = sk.NonSmoothDynamicalSystem(0.0, duration)
    nsds.insertDynamicalSystem(ds)
    nsds.link(contact, ds)
    sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.MoreauJeanOSI(theta),
                          sk.FrictionContact(2, sn.SICONOS_FRICTION_2D_LEMKE))
    n = int(round(duration / h))
    t, th1, th2, th1_dot, th2_dot, p_n, p_t = (np.zeros(n) for _ in range(7))
    p0 = (0.0, 0.0)
    k = 0
    while sim.hasNextEvent() and k < n:
        sim.computeOneStep()
        q, v, impulse = ds.q(), ds.velocity(), contact.lambda_(1)  # impulse = [P_n, P_t]
        t[k], th1[k], th2[k], th1_dot[k], th2_dot[k] = sim.nextTime(), q[0], q[1], v[0], v[1]
        p_n[k], p_t[k] = impulse[0], impulse[1]
        if k == 0:
            p0 = (float(impulse[1]), float(impulse[0]))
        sim.nextStep()
        k += 1
    return {"t": t[:k], "th1": th1[:k], "th2": th2[:k], "th1_dot": th1_dot[:k], "th2_dot": th2_dot[:k],
            "p_n": p_n[:k], "p_t": p_t[:k], "p0": p0,
            "wall_s": time.perf_counter() - wall0, "cpu_s": time.process_time() - cpu0}


def siconos_digest(run, window, subwindows=1, params=TABLE_I):
    """What the checks read from a Siconos run, over `window` = (t0, t1) in s.

    The gap z_n + H = H - l (cos theta1 + cos theta2) (m) comes from q (docs/model.md "Geometry and
    state"). A lift-off is a step with no normal impulse after one with an impulse (P_n > 0: the
    tip touched the belt, by an impact or in contact), the tip leaving the belt. Returns lift-off
    `lift_offs` and `flight_steps` in the window, `max_gap` (m), `max_abs_gap` (m), the lift-offs
    of each of `subwindows` equal parts, the first three touchdowns (s), the final `z_t` (m) and
    `z_t` one second earlier, the final theta1 (deg), the first step's impulse and the timing.
    """
    import numpy as np

    l, hh = params["l"], params["h"]
    t, p_n = run["t"], run["p_n"]
    gap = hh - l * (np.cos(run["th1"]) + np.cos(run["th2"]))
    z_t = l * (np.sin(run["th1"]) + np.sin(run["th2"]))
    on = p_n > 0.0
    lift = t[1:][on[:-1] & ~on[1:]]
    touch = t[1:][~on[:-1] & on[1:]]
    t0, t1 = window
    inside = (t > t0) & (t <= t1 + 1e-12)
    edges = np.linspace(t0, t1, subwindows + 1)
    parts = [int(((lift > a) & (lift <= b + 1e-12)).sum()) for a, b in zip(edges[:-1], edges[1:])]
    earlier = int(np.searchsorted(t, t[-1] - 1.0))
    return {"lift_offs": int(((lift > t0) & (lift <= t1 + 1e-12)).sum()), "parts": parts,
            "flight_steps": int((~on[inside]).sum()), "max_gap": float(gap[inside].max()),
            "max_abs_gap": float(np.abs(gap[inside]).max()), "touchdowns": [float(x) for x in touch[:3]],
            "z_t": float(z_t[-1]), "z_t_1s_before": float(z_t[earlier]), "theta1_deg": math.degrees(run["th1"][-1]),
            "final_gap": float(gap[-1]), "p0": run["p0"], "t_end": float(t[-1]),
            "wall_s": run["wall_s"], "cpu_s": run["cpu_s"]}


def siconos_case(plugin, x0_deg, mu, h, duration, window, subwindows=1):
    """One Siconos case from docs/model.md's `x0_deg` (theta1, theta2 in deg, at rest), digested.

    `mu` Coulomb's coefficient, `h` the time step (s), `duration` (s), `window` (s, s); see
    siconos_run and siconos_digest. Runs in a worker process; returns the digest (a dict).
    """
    run = siconos_run(plugin, project(*x0_deg), mu, h, duration)
    return siconos_digest(run, window, subwindows)


def p_ratio(th1, th2, mu, s, params):
    """`p / Q_22` at the angles (rad) for a slip of sign `s`: `p = Q_22 - mu s Q_21` (paper eqs. 6,
    7; docs/plant.md "The singular point"), with `Q = J M^-1 J^T` the tip's inverse inertia in
    (tangential, normal) coordinates, J the tip's Jacobian and M the arm's mass matrix
    (docs/model.md eq. 1). Dimensionless: the slide's force is `f_n = -b / p`."""
    import numpy as np

    m, l = params["m"], params["l"]
    off = 0.5 * m * l * l * math.cos(th2 - th1)
    mass = np.array([[4.0 / 3.0 * m * l * l, off], [off, m * l * l / 3.0]])
    jac = np.array([[l * math.cos(th1), l * math.cos(th2)], [l * math.sin(th1), l * math.sin(th2)]])
    q = jac @ np.linalg.solve(mass, jac.T)
    return (q[1, 1] - mu * s * q[1, 0]) / q[1, 1]


def siconos_corner(plugin, params, x0_deg, mu, h, duration, v_belt=V_BELT):
    """A slide towards the singular point in Siconos, from rest at `x0_deg` (theta1, theta2 in deg,
    projected onto the belt), and what it does first (issue 81).

    Per step: the slip v_r = z_t_dot - v_belt (m/s), the gap z_n + H (m) and the impulse (P_n, P_t)
    (N s). The slip is **arrested** in the first step with a normal impulse whose |v_r| is below
    STOP_FRACTION of the step before; the tip **lifts off** at the first step without impulse after
    one with (its start, t_k - h, is the lift-off's time) that begins a stretch without impulse in
    which the gap exceeds GAP_LEFT_M. Siconos' steps with no impulse inside the belt (one at the
    start, one just before the crossing: its contact problem prefers P = 0 where that solves it) are
    neither. Returns `regime` ("arrested", "lifted off" or "neither": whichever comes first), its
    time `t` (s: the arrest step's end, or the lift-off's), the slip before and after it (m/s), the
    arrest's impulse (P_t, P_n) (N s) and `smooth_impulse`, the last step's P_n before it (N s: the
    smooth forces' share of a step), `p / Q_22` at the lift-off, `plain_lift_offs` before the event
    in the sense of siconos_digest (a step without impulse after one with), the projected start
    `start_deg`, `max_gap` (m) and `wall_s`.
    """
    import numpy as np

    run = siconos_run(plugin, project(*x0_deg, params=params), mu, h, duration)
    l, hh = params["l"], params["h"]
    t, th1, th2 = run["t"], run["th1"], run["th2"]
    v_r = l * (np.cos(th1) * run["th1_dot"] + np.cos(th2) * run["th2_dot"]) - v_belt
    gap = hh - l * (np.cos(th1) + np.cos(th2))
    on = run["p_n"] > 0.0
    stops = np.nonzero(on[1:] & (np.abs(v_r[1:]) <= STOP_FRACTION * np.abs(v_r[:-1])))[0] + 1
    arrest = int(stops[0]) if len(stops) else None
    lift, k, n = None, 1, len(t)
    while k < n:
        if on[k - 1] and not on[k]:
            j = k
            while j < n and not on[j]:
                j += 1
            if gap[k:j].max() > GAP_LEFT_M:
                lift = k
                break
            k = j
        else:
            k += 1
    out = {"regime": "neither", "t": float("nan"), "v_r_before": float("nan"), "v_r_after": float("nan"),
           "impulse": (float("nan"), float("nan")), "smooth_impulse": 0.0, "p_ratio": float("nan"), "h": h,
           "wall_s": run["wall_s"],
           "start_deg": [math.degrees(a) for a in project(*x0_deg, params=params)], "max_gap": float(gap.max())}
    if arrest is not None and (lift is None or arrest < lift):
        before = np.nonzero(on[:arrest])[0]
        out.update(regime="arrested", t=float(t[arrest]), v_r_before=float(v_r[arrest - 1]),
                   v_r_after=float(v_r[arrest]), impulse=(float(run["p_t"][arrest]), float(run["p_n"][arrest])),
                   smooth_impulse=float(run["p_n"][before[-1]]) if len(before) else 0.0)
        event = arrest
    elif lift is not None:
        out.update(regime="lifted off", t=float(t[lift] - h), v_r_before=float(v_r[lift - 1]),
                   v_r_after=float(v_r[lift]),
                   p_ratio=float(p_ratio(th1[lift - 1], th2[lift - 1], mu, np.sign(v_r[lift - 1]), params)))
        event = lift
    else:
        event = n
    out["plain_lift_offs"] = int((on[:event - 1] & ~on[1:event]).sum()) if event > 1 else 0
    return out


def sil_host_run(exe, x0, mu, duration, folder, v_belt=V_BELT, params=None, mass_factor=1.0, sample_dt=None):
    """Runs `sil-host simulate --iwc plastic` (open loop, Newton e_n 0.2, v_belt -0.5 m/s).

    `x0` is `a` or `d` (docs/model.md's x0a, x0d, which sil-host projects onto the belt) or
    (theta1, theta1_dot, theta2, theta2_dot) in deg and deg/s (`--x0-deg`), `mu` Coulomb's
    coefficient, `duration` in s, `v_belt` in m/s; `params` an arm other than Table I (`--set
    plant.KEY=VALUE`, SI units), whose mass `mass_factor` multiplies (the check's
    `--perturb-mass`: sil-host's link that much heavier than Siconos'); `sample_dt` the trace's
    period (s, default 1 ms). The outputs (summary.json, events.csv, trace.csv: docs/plant.md
    "From the command line") go to `folder`. Returns (summary dict, wall s, CPU s of the
    process). Raises SilHostError when sil-host fails.
    """
    x0_args = ["--x0", x0] if isinstance(x0, str) else ["--x0-deg", ",".join(repr(float(a)) for a in x0)]
    cmd = [exe, "simulate", *x0_args, "--mu", repr(mu), "--v-belt", repr(v_belt), "--impact-law", "newton",
           "--e-n", repr(E_N), "--iwc", "plastic", "--duration", repr(duration), "--no-page", "--json",
           "--out", folder]
    arm = dict(params or {})
    if mass_factor != 1.0:
        arm["m"] = arm.get("m", TABLE_I["m"]) * mass_factor
    for key, value in arm.items():
        cmd += ["--set", f"plant.{key}={value!r}"]
    if sample_dt is not None:
        cmd += ["--sample-dt", repr(sample_dt)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - wall0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SilHostError(f"{' '.join(cmd)} exited {done.returncode}:\n{done.stderr}")
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return summary, wall, cpu


def sil_host_digest(folder, summary, window, params=TABLE_I):
    """What the checks read from a sil-host run's folder, over `window` = (t0, t1) in s.

    Lift-offs (docs/plant.md "Discrete transitions"): the `lift_off` events and the touchdowns
    after which the tip flies off again (a bounce: `mode_after` flight), from events.csv at
    their exact times. The gap z_n + H (m) from trace.csv (every 1 ms). Returns the same keys
    as siconos_digest where they apply, plus `final_mode` and the projected start (deg).
    """
    import numpy as np

    lift, touch = [], []
    with open(os.path.join(folder, "events.csv")) as f:
        for row in csv.DictReader(f):
            if row["kind"] == "lift_off" or (row["kind"] == "touchdown" and row["mode_after"] == "flight"):
                lift.append(float(row["t"]))
            if row["kind"] == "touchdown":
                touch.append(float(row["t"]))
    lift = np.array(lift)
    trace = np.genfromtxt(os.path.join(folder, "trace.csv"), delimiter=",", names=True, usecols=(0, 1, 5, 6))
    t, gap, z_t = trace["t"], trace["z_n"] + params["h"], trace["z_t"]
    t0, t1 = window
    inside = (t > t0) & (t <= t1 + 1e-12)
    earlier = int(np.searchsorted(t, t[-1] - 1.0))
    used = summary["initial_condition"]["used_deg"]
    return {"lift_offs": int(((lift > t0) & (lift <= t1 + 1e-12)).sum()), "max_gap": float(gap[inside].max()),
            "max_abs_gap": float(np.abs(gap[inside]).max()), "touchdowns": touch[:3],
            "z_t": float(summary["final_tip"][0]), "z_t_1s_before": float(z_t[earlier]),
            "theta1_deg": math.degrees(summary["final_state"][0]), "final_mode": summary["final_mode"],
            "start_deg": (used[0], used[2])}


def sil_host_corner(folder, summary, mu, params):
    """What sil-host's run towards the singular point does first (events.csv, docs/plant.md "At the
    point itself"): `regime` "arrested" when its first events are `p_zero` and the impact without
    collision at it (resolution `iwc_at_p_zero`) that stops the slip, "lifted off" when the first is
    a `lift_off` with the slip unchanged, else "neither"; the time `t` (s), the slip before and after
    (m/s), the arrest's impulse (P_t, P_n) (N s), `p / Q_22` at the lift-off (from trace.csv's
    angles, interpolated to the event: run it with a fine `--sample-dt`), the first `kinds` and
    the start it used (deg)."""
    import numpy as np

    with open(os.path.join(folder, "events.csv")) as f:
        events = list(csv.DictReader(f))
    used = summary["initial_condition"]["used_deg"]
    out = {"regime": "neither", "t": float("nan"), "v_r_before": float("nan"), "v_r_after": float("nan"),
           "impulse": (float("nan"), float("nan")), "p_ratio": float("nan"), "kinds": [e["kind"] for e in events[:3]],
           "start_deg": (used[0], used[2])}
    if not events:
        return out
    first = events[0]
    if (first["kind"] == "p_zero" and len(events) > 1 and events[1]["kind"] == "impact_without_collision"
            and events[1]["resolution"] == "iwc_at_p_zero" and float(events[1]["t"]) == float(first["t"])):
        e = events[1]
        out.update(regime="arrested", t=float(e["t"]), v_r_before=float(e["v_r_before"]),
                   v_r_after=float(e["v_r_after"]), impulse=(float(e["impulse_t"]), float(e["impulse_n"])))
        if abs(out["v_r_after"]) > STOP_FRACTION * abs(out["v_r_before"]):
            out["regime"] = "neither"
    elif first["kind"] == "lift_off" and float(first["v_r_after"]) == float(first["v_r_before"]):
        out.update(regime="lifted off", t=float(first["t"]), v_r_before=float(first["v_r_before"]),
                   v_r_after=float(first["v_r_after"]))
        trace = np.genfromtxt(os.path.join(folder, "trace.csv"), delimiter=",", names=True, usecols=(0, 1, 3))
        i = min(max(int(np.searchsorted(trace["t"], out["t"])), 1), len(trace) - 1)
        s = 1.0 if out["v_r_before"] > 0 else -1.0
        a, b = (p_ratio(trace["theta1"][j], trace["theta2"][j], mu, s, params) for j in (i - 1, i))
        t0, t1 = trace["t"][i - 1], trace["t"][i]
        out["p_ratio"] = float(a + (b - a) * (out["t"] - t0) / (t1 - t0))
    return out


def classify(d, sil_host):
    """`slides`, `bounces` or `neither` for a digest over its window (the checks' definitions).

    Slides: the tip stays on the belt (|gap| <= 10 um, Siconos: every step with a normal
    impulse; sil-host: no lift-off and a sliding final mode). Bounces: at least 5 lift-offs and
    a gap of at least 1 mm.
    """
    if d["lift_offs"] >= BOUNCE_MIN_LIFT_OFFS and d["max_gap"] >= BOUNCE_MIN_GAP_M:
        return "bounces"
    stays = d["lift_offs"] == 0 and d["max_abs_gap"] <= ON_BELT_M
    stays = stays and (d["final_mode"] == "sliding" if sil_host else d["flight_steps"] == 0)
    return "slides" if stays else "neither"


def count_tolerance(coarse, fine, h_coarse, h_fine, edge=0):
    """A lift-off count's tolerance from Siconos' runs at two steps: the step term and
    the count's limit (`convergence_tolerance`), the sampling spread of the fine run's
    count (sqrt(parts) x the standard deviation of its per-part counts) and the total,
    step term + twice the spread + `edge` (lift-offs the window's edges may move)."""
    tol, limit = convergence_tolerance(coarse["lift_offs"], fine["lift_offs"], h_coarse, h_fine)
    spread = math.sqrt(len(fine["parts"])) * statistics.stdev(fine["parts"])
    return tol, limit, spread, tol + 2.0 * spread + edge


def convergence_tolerance(coarse, fine, h_coarse=H_COARSE, h_fine=H_FINE):
    """The step-size tolerance for a statistic X from Siconos at two steps (units of X).

    Moreau-Jean, like every event-capturing scheme, is at most first-order accurate through
    impacts (V. Acary, "Higher order event capturing time-stepping schemes for nonsmooth
    multibody systems with unilateral constraints and impacts", Appl. Numer. Math. 62, 2012):
    X(h) ~ X0 + C h. Two runs give C = (X(h1) - X(h2)) / (h1 - h2), so the coarse run's own error
    is h1 |C| = |X(h1) - X(h2)| h1 / (h1 - h2). sil-host (X0 to its tolerances) must lie that
    close to the fine run: as close as the coarse run lies to the limit. Returns (tolerance,
    Richardson's estimate of X0).
    """
    slope = (coarse - fine) / (h_coarse - h_fine)
    return abs(slope) * h_coarse, fine - slope * h_fine


class Report:
    """Collects pass/fail lines; `failed` is set by any failed check."""

    def __init__(self):
        """An empty report."""
        self.failed = False

    def check(self, ok, text):
        """Prints `PASS text` or `FAIL text` and remembers a failure."""
        print(("PASS " if ok else "FAIL ") + text, flush=True)
        self.failed |= not ok


def main(argv=None):
    """Runs every check; returns the exit code (0 pass, 1 a check failed, 2 setup error)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sil-host", default="target/release/sil-host", help="the sil-host binary to check")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1), help="Siconos runs at once")
    parser.add_argument("--keep", metavar="DIR", help="keep the plugin and sil-host's outputs in DIR")
    parser.add_argument("--record", metavar="FILE",
                        help="write the comparison as a Markdown section's body to FILE (tests/siconos/results.md, "
                             "which `sil-host report` puts in docs/results.md as \"Against Siconos\")")
    parser.add_argument("--perturb-mass", type=float, default=1.0, metavar="F",
                        help="give sil-host links F times as heavy as Siconos' (which keeps the paper's): with "
                             "1.04 or 0.96 the locked bounce's lift-off count fails, and the check exits 1")
    args = parser.parse_args(argv)
    if not args.perturb_mass > 0.0:
        parser.error("--perturb-mass must be positive")
    if args.record and args.perturb_mass != 1.0:
        parser.error("--record writes the true model's comparison: not with --perturb-mass")
    started = time.perf_counter()

    try:
        import numpy  # noqa: F401  (Debian's python3-numpy, a dependency of python3-siconos)
        import siconos.kernel  # noqa: F401
        import siconos.numerics  # noqa: F401
    except ImportError as e:
        print(f"SETUP Siconos is missing ({e}): apt-get install -y python3-siconos (Debian bookworm's 4.4), "
              f"and run this with Debian's system Python, /usr/bin/python3 (this is {sys.executable})", flush=True)
        return SETUP
    exe = os.path.abspath(args.sil_host)
    if not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
        print(f"SETUP no sil-host at {exe}: cargo build --release -p sil-host", flush=True)
        return SETUP
    work = args.keep or tempfile.mkdtemp(prefix="siconos-check-")
    os.makedirs(work, exist_ok=True)
    try:
        return run_checks(exe, work, args.jobs, started, args.record, args.perturb_mass)
    except SilHostError as e:
        print(f"FAIL {e}", flush=True)
        return FAIL
    except SetupError as e:
        print(f"SETUP {e}", flush=True)
        return SETUP
    except Exception as e:  # Siconos raises a bare Exception (std::exception) on a plugin it cannot load
        import traceback

        traceback.print_exc()
        print(f"SETUP the Siconos model could not be built or run: {type(e).__name__}: {e}", flush=True)
        return SETUP
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


def run_checks(exe, work, jobs, started, record=None, mass_factor=1.0):
    """The checks themselves (see the module's docstring); returns the exit code. With
    `record`, a path: the comparison written there as Markdown (`write_record`); `mass_factor`
    multiplies sil-host's link mass (`--perturb-mass`), not Siconos'."""
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing

    here = os.path.dirname(os.path.abspath(__file__))
    source = os.path.join(here, "arm_plugin.c")
    plugin = build_plugin(source, work)
    plugin_locked = build_plugin(source, work, TABLE_I, LOCKED_V_BELT, "arm_locked")
    plugin_53 = build_plugin(source, work, ISSUE53, V_BELT, "arm_issue53")
    pkg = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"], capture_output=True, text=True)
    print(f"Siconos: python3-siconos {pkg.stdout.strip() or '?'} on {sys.executable}; sil-host: {exe}")
    print(f"model: docs/model.md's arm, e_n {E_N}, v_belt {V_BELT} m/s, Moreau-Jean theta {THETA}, "
          f"h {H_COARSE:g} and {H_FINE:g} s (at the singular point {CORNER_H[0]:g} and {CORNER_H[1]:g} s); "
          f"sil-host simulate --iwc plastic")
    if mass_factor != 1.0:
        print(f"--perturb-mass {mass_factor:g}: sil-host's links are {mass_factor:g} times as heavy as Siconos' "
              f"(m {TABLE_I['m'] * mass_factor:.6g} kg against {TABLE_I['m']:g}; issue 53's arm "
              f"{ISSUE53['m'] * mass_factor:.6g} against {ISSUE53['m']:g}): the check must fail")

    # sil-host, each case; the bounce three times more for its run time.
    sil = {}
    cases = {"bounce": ("a", 0.6, BOUNCE_T, BOUNCE_WINDOW, V_BELT), "mu0.365": ("a", 0.365, EDGE_T, EDGE_WINDOW, V_BELT),
             "mu0.366": ("a", 0.366, EDGE_T, EDGE_WINDOW, V_BELT),
             "x0d": ("d", 0.6, SLIDE_T, (SLIDE_T - 2.0, SLIDE_T), V_BELT),
             "locked": ("a", 0.6, LOCKED_T, LOCKED_WINDOW, LOCKED_V_BELT)}
    sil_times = []
    for name, (x0, mu, duration, window, v_belt) in cases.items():
        folder = os.path.join(work, f"sil-{name}")
        summary, wall, cpu = sil_host_run(exe, x0, mu, duration, folder, v_belt, mass_factor=mass_factor)
        if name == "bounce":
            sil_times.append((wall, cpu, summary["wall_s"]))
            for _ in range(2):
                again, wall, cpu = sil_host_run(exe, x0, mu, duration, folder + "-again", mass_factor=mass_factor)
                sil_times.append((wall, cpu, again["wall_s"]))
        sil[name] = sil_host_digest(folder, summary, window)
    sil_corner = {}
    for name, (mu, x0_deg, duration, _) in CORNERS.items():
        folder = os.path.join(work, "sil-corner-" + name.replace(" ", "-"))
        th1, th2 = (math.degrees(a) for a in project(*x0_deg, params=ISSUE53))
        summary, _, _ = sil_host_run(exe, (th1, 0.0, th2, 0.0), mu, duration, folder, params=ISSUE53,
                                     mass_factor=mass_factor, sample_dt=1e-5)
        sil_corner[name] = sil_host_corner(folder, summary, mu, ISSUE53)

    # Siconos: the bounce at the coarse step alone (its run time), then the rest two at a time,
    # the longest first.
    sic = {("bounce", H_COARSE): siconos_case(plugin, X0A_DEG, 0.6, H_COARSE, BOUNCE_T, BOUNCE_WINDOW,
                                              BOUNCE_SUBWINDOWS)}
    todo = [(("bounce", H_FINE), siconos_case, (plugin, X0A_DEG, 0.6, H_FINE, BOUNCE_T, BOUNCE_WINDOW,
                                                 BOUNCE_SUBWINDOWS))]
    for h in reversed(LOCKED_H):
        todo.append((("locked", h), siconos_case, (plugin_locked, X0A_DEG, 0.6, h, LOCKED_T, LOCKED_WINDOW,
                                                    LOCKED_SUBWINDOWS)))
    for h in (H_FINE, H_COARSE):
        todo += [(("x0d", h), siconos_case, (plugin, X0D_DEG, 0.6, h, SLIDE_T, (SLIDE_T - 2.0, SLIDE_T), 1)),
                 (("mu0.365", h), siconos_case, (plugin, X0A_DEG, 0.365, h, EDGE_T, EDGE_WINDOW, 1)),
                 (("mu0.366", h), siconos_case, (plugin, X0A_DEG, 0.366, h, EDGE_T, EDGE_WINDOW, 1))]
    for name, (mu, x0_deg, duration, _) in CORNERS.items():
        for h in CORNER_H:
            todo.append(((name, h), siconos_corner, (plugin_53, ISSUE53, x0_deg, mu, h, duration)))
    with ProcessPoolExecutor(max_workers=max(1, jobs), mp_context=multiprocessing.get_context("fork")) as pool:
        futures = {key: pool.submit(fn, *fn_args) for key, fn, fn_args in todo}
        for key, future in futures.items():
            sic[key] = future.result()

    report = Report()
    hc, hf = H_COARSE, H_FINE
    rows = []  # the record's table: check, Siconos at hc, at hf, h -> 0, sil-host, tolerance, result

    # 1. The same start.
    for name, x0_deg in (("bounce", X0A_DEG), ("x0d", X0D_DEG)):
        mine = [math.degrees(a) for a in project(*x0_deg)]
        theirs = sil[name]["start_deg"]
        err = max(abs(a - b) for a, b in zip(mine, theirs))
        report.check(err <= PROJECTION_TOL_DEG,
                     f"start {'x0a' if name == 'bounce' else 'x0d'} projected onto the belt: this test "
                     f"[{mine[0]:.6f}, 0, {mine[1]:.6f}, 0] deg, sil-host [{theirs[0]:.6f}, 0, {theirs[1]:.6f}, 0] deg "
                     f"(differ by {err:.1e} deg, tolerance {PROJECTION_TOL_DEG:g})")

    # 2. The edge of the bounce: 0.365 slides, 0.366 bounces.
    for name, want in (("mu0.365", "slides"), ("mu0.366", "bounces")):
        got = {"sil-host": classify(sil[name], True)}
        for h in (hc, hf):
            got[f"Siconos h {h:g}"] = classify(sic[(name, h)], False)
        detail = "; ".join(
            f"{who}: {what} ({d['lift_offs']} lift-offs, "
            + (f"max |gap| {d['max_abs_gap'] * 1e6:.2g} um" if what == "slides" else f"max gap {d['max_gap'] * 100:.3f} cm")
            + f", final theta1 {d['theta1_deg']:.4f} deg)"
            for (who, what), d in zip(got.items(), (sil[name], sic[(name, hc)], sic[(name, hf)])))
        def said(what, d):
            return (f"{what}, theta1 {d['theta1_deg']:.4f} deg" if what == "slides"
                    else f"{what}: {d['lift_offs']} lift-offs, gap up to {d['max_gap'] * 100:.2f} cm")
        ok = all(v == want for v in got.values())
        rows.append((f"x0a, mu = {name[2:]}, t in ({EDGE_WINDOW[0]:g}, {EDGE_WINDOW[1]:g}] s",
                     said(got[f"Siconos h {hc:g}"], sic[(name, hc)]), said(got[f"Siconos h {hf:g}"], sic[(name, hf)]), "",
                     said(got["sil-host"], sil[name]), "class", "pass" if ok else "**fail**"))
        report.check(ok,
                     f"x0a, mu {name[2:]}: {want} in both, over t in ({EDGE_WINDOW[0]:g}, {EDGE_WINDOW[1]:g}] s: {detail}")

    # 3. The bounce at mu 0.6: lift-offs per 50 s and the largest gap.
    s, c, f = sil["bounce"], sic[("bounce", hc)], sic[("bounce", hf)]
    span = BOUNCE_WINDOW[1] - BOUNCE_WINDOW[0]
    print(f"x0a, mu 0.6, first touchdowns (s): sil-host {fmt(s['touchdowns'])}; Siconos h {hc:g} "
          f"{fmt(c['touchdowns'])}; h {hf:g} {fmt(f['touchdowns'])}")
    print(f"x0a, mu 0.6, the impact without collision at t = 0, Siconos' first-step impulse (P_t, P_n): "
          f"h {hc:g} ({c['p0'][0]:.4f}, {c['p0'][1]:.4f}) N s; h {hf:g} ({f['p0'][0]:.4f}, {f['p0'][1]:.4f}) N s")
    tol, limit, spread, tol_n = count_tolerance(c, f, hc, hf)
    dev = abs(s["lift_offs"] - f["lift_offs"])
    rows.append((f"x0a, mu = 0.6: lift-offs in t in ({BOUNCE_WINDOW[0]:g}, {BOUNCE_WINDOW[1]:g}] s", c["lift_offs"],
                 f["lift_offs"], f"{limit:.1f}", s["lift_offs"], f"{tol_n:.1f}",
                 f"pass ({dev})" if dev <= tol_n else f"**fail** ({dev})"))
    report.check(dev <= tol_n,
                 f"x0a, mu 0.6, lift-offs in t in ({BOUNCE_WINDOW[0]:g}, {BOUNCE_WINDOW[1]:g}] s ({span:g} s): sil-host "
                 f"{s['lift_offs']}, Siconos h {hc:g} {c['lift_offs']}, h {hf:g} {f['lift_offs']} (h -> 0: {limit:.1f}); "
                 f"|sil-host - Siconos h {hf:g}| = {dev} <= {tol_n:.1f} = step term {tol:.1f} "
                 f"(|{c['lift_offs']} - {f['lift_offs']}| x {hc / (hc - hf):g}) + 2 x sampling spread {spread:.1f} "
                 f"(sqrt({len(f['parts'])}) x stdev of {f['parts']})")
    tol_g, limit_g = convergence_tolerance(c["max_gap"], f["max_gap"])
    dev_g = abs(s["max_gap"] - f["max_gap"])
    rows.append((f"x0a, mu = 0.6: largest gap in t in ({BOUNCE_WINDOW[0]:g}, {BOUNCE_WINDOW[1]:g}] s",
                 f"{c['max_gap'] * 100:.3f} cm", f"{f['max_gap'] * 100:.3f} cm", f"{limit_g * 100:.3f} cm",
                 f"{s['max_gap'] * 100:.3f} cm", f"{tol_g * 100:.3f} cm",
                 f"{'pass' if dev_g <= tol_g else '**fail**'} ({dev_g * 100:.3f} cm)"))
    rows.append(("x0a, mu = 0.6: first touchdowns", ", ".join(f"{v:.4f}" for v in c["touchdowns"]) + " s",
                 ", ".join(f"{v:.5f}" for v in f["touchdowns"]) + " s", "",
                 ", ".join(f"{v:.6f}" for v in s["touchdowns"]) + " s", "printed only", ""))
    report.check(dev_g <= tol_g,
                 f"x0a, mu 0.6, max gap in the window: sil-host {s['max_gap'] * 100:.3f} cm, Siconos h {hc:g} "
                 f"{c['max_gap'] * 100:.3f} cm, h {hf:g} {f['max_gap'] * 100:.3f} cm (h -> 0: {limit_g * 100:.3f} cm); "
                 f"|sil-host - Siconos h {hf:g}| = {dev_g * 100:.3f} cm <= {tol_g * 100:.3f} cm "
                 f"(|{c['max_gap'] * 100:.3f} - {f['max_gap'] * 100:.3f}| x {hc / (hc - hf):g})")

    # 4. x0d at mu 0.6 slides to the same z_t.
    s, c, f = sil["x0d"], sic[("x0d", hc)], sic[("x0d", hf)]
    tol_z, limit_z = convergence_tolerance(c["z_t"], f["z_t"])
    settle = abs(f["z_t"] - f["z_t_1s_before"]) + abs(s["z_t"] - s["z_t_1s_before"])
    tol_zt = max(tol_z, ZT_FLOOR_M) + settle
    dev_z = abs(s["z_t"] - f["z_t"])
    slides = classify(s, True) == "slides" and all(classify(d, False) == "slides" for d in (c, f))
    rows.append((f"x0d, mu = 0.6: z_t at t = {SLIDE_T:g} s", f"{c['z_t']:.8f} m", f"{f['z_t']:.8f} m",
                 f"{limit_z:.8f} m", f"{s['z_t']:.8f} m", f"{tol_zt:.1e} m",
                 f"{'pass' if slides and dev_z <= tol_zt else '**fail**'} ({dev_z:.1e} m)"))
    report.check(slides and dev_z <= tol_zt,
                 f"x0d, mu 0.6, slides to z_t at t = {SLIDE_T:g} s: sil-host {s['z_t']:.8f} m, Siconos h {hc:g} "
                 f"{c['z_t']:.8f} m (gap {c['final_gap']:.1e} m), h {hf:g} {f['z_t']:.8f} m (gap {f['final_gap']:.1e} m; "
                 f"h -> 0: {limit_z:.8f}); |sil-host - Siconos h {hf:g}| = {dev_z:.1e} m <= {tol_zt:.1e} m = "
                 f"max(step term {tol_z:.1e}, floor {ZT_FLOOR_M:g}) + not yet settled {settle:.1e} "
                 f"(|z_t(T) - z_t(T - 1 s)|, both); slides in all three: {slides}")

    # 5. The locked bounce at v_belt -0.4: lift-offs in 30 s.
    lc, lf = LOCKED_H
    s, c, f = sil["locked"], sic[("locked", lc)], sic[("locked", lf)]
    tol, limit, spread, tol_n = count_tolerance(c, f, lc, lf, EDGE_COUNT)
    dev = abs(s["lift_offs"] - f["lift_offs"])
    w = f"t in ({LOCKED_WINDOW[0]:g}, {LOCKED_WINDOW[1]:g}] s"
    rows.append((f"x0a, mu = 0.6, v_belt = {LOCKED_V_BELT:g} m/s (locked): lift-offs in {w} (Siconos at h = "
                 f"{lc:g} and {lf:g} s)", c["lift_offs"],
                 f["lift_offs"], f"{limit:.1f}", s["lift_offs"], f"{tol_n:.1f}",
                 f"pass ({dev})" if dev <= tol_n else f"**fail** ({dev})"))
    report.check(dev <= tol_n,
                 f"x0a, mu 0.6, v_belt {LOCKED_V_BELT:g} m/s (the locked bounce), lift-offs in {w}: sil-host "
                 f"{s['lift_offs']}, Siconos h {lc:g} {c['lift_offs']} {c['parts']}, h {lf:g} {f['lift_offs']} "
                 f"{f['parts']} (per 10 s); |sil-host - Siconos h {lf:g}| = {dev} <= {tol_n:.1f} = step term {tol:.1f} "
                 f"(|{c['lift_offs']} - {f['lift_offs']}| x {lc / (lc - lf):g}) + 2 x sampling spread {spread:.1f} "
                 f"+ {EDGE_COUNT} (the window's edges)")

    # 6. The singular point on issue 53's arm: the slip arrested (attracted), or kept (force first).
    ch, fh = CORNER_H
    for name, (mu, x0_deg, duration, want) in CORNERS.items():
        s, c, f = sil_corner[name], sic[(name, ch)], sic[(name, fh)]
        start_err = max(abs(a - b) for a, b in zip(s["start_deg"], f["start_deg"]))
        tol_t, limit_t = convergence_tolerance(c["t"], f["t"], ch, fh)
        tol_t += fh  # the fine run's own resolution: the event lies within one of its steps
        dev_t = abs(s["t"] - f["t"])
        regimes = [d["regime"] for d in (s, c, f)]
        ok = regimes == [want] * 3 and dev_t <= tol_t and start_err <= PROJECTION_TOL_DEG
        what = "arrest" if want == "arrested" else "lift-off"
        if want == "arrested":
            tol_p, _ = convergence_tolerance(c["impulse"][1], f["impulse"][1], ch, fh)
            dev_p = abs(s["impulse"][1] - f["impulse"][1])
            ok = ok and dev_p <= tol_p + f["smooth_impulse"]
            extra = (f"the arrest's impulse (P_t, P_n): sil-host ({s['impulse'][0]:.5f}, {s['impulse'][1]:.5f}) N s, "
                     f"Siconos h {ch:g} ({c['impulse'][0]:.5f}, {c['impulse'][1]:.5f}), h {fh:g} "
                     f"({f['impulse'][0]:.5f}, {f['impulse'][1]:.5f}); |P_n sil-host - h {fh:g}| = {dev_p:.1e} <= "
                     f"{tol_p + f['smooth_impulse']:.1e} = step term {tol_p:.1e} + the step's smooth share "
                     f"{f['smooth_impulse']:.1e}")
        else:
            extra = (f"p / Q_22 at the lift-off: sil-host {s['p_ratio']:.1e}, Siconos h {fh:g} {f['p_ratio']:.1e} "
                     f"(an ordinary lift-off: 0.1 to 1); Siconos' max gap {f['max_gap'] * 1e6:.1f} um")
        slips = "; ".join(f"{who} {d['regime']} at {d['t'] * 1e3:.5f} ms, v_r {d['v_r_before']:.5f} -> "
                          f"{d['v_r_after']:.5f} m/s" for who, d in (("sil-host", s), (f"Siconos h {ch:g}", c),
                                                                 (f"Siconos h {fh:g}", f)))
        rows.append((f"issue 53's arm, mu = {mu:g}: {what} at the singular point ({name}; Siconos at h = {ch:g} "
                     f"and {fh:g} s)",
                     f"{c['regime']}, {c['t'] * 1e3:.4f} ms", f"{f['regime']}, {f['t'] * 1e3:.4f} ms",
                     f"{limit_t * 1e3:.4f} ms", f"{s['regime']}, {s['t'] * 1e3:.5f} ms", f"{tol_t * 1e3:.4f} ms",
                     f"{'pass' if ok else '**fail**'} ({dev_t * 1e3:.4f} ms)"))
        report.check(ok,
                     f"singular point, {name}: issue 53's arm at mu {mu:g} from rest at "
                     f"[{s['start_deg'][0]:.6f}, 0, {s['start_deg'][1]:.6f}, 0] deg, {want} in all three: {slips}; "
                     f"|t sil-host - Siconos h {fh:g}| = {dev_t * 1e6:.2f} us <= {tol_t * 1e6:.2f} us = step term "
                     f"{(tol_t - fh) * 1e6:.2f} (|{c['t'] * 1e3:.5f} - {f['t'] * 1e3:.5f}| ms x {ch / (ch - fh):.3g}) + "
                     f"h {fh:g} (h -> 0: {limit_t * 1e3:.5f} ms); {extra}; Siconos' steps without impulse inside "
                     f"the belt before it: {c['plain_lift_offs']} and {f['plain_lift_offs']}; sil-host's first events "
                     f"{', '.join(s['kinds'])}")

    # Run time, the same case (x0a, mu 0.6, v_belt -0.5, 60 s) in this run.
    walls = sorted(x[0] for x in sil_times)
    cpus = sorted(x[1] for x in sil_times)
    sims = sorted(x[2] for x in sil_times)
    sw, sc, ss = walls[len(walls) // 2], cpus[len(cpus) // 2], sims[len(sims) // 2]
    c = sic[("bounce", hc)]
    print(f"run time, x0a mu 0.6 for {BOUNCE_T:g} s: Siconos h {hc:g} (Python stepping loop, model built and "
          f"stepped) {c['wall_s']:.2f} s wall, {c['cpu_s']:.2f} s CPU; sil-host simulate (whole process, files "
          f"written; median of {len(walls)}) {sw:.3f} s wall, {sc:.3f} s CPU ({ss:.3f} s of it simulating); "
          f"ratio Siconos / sil-host: {c['wall_s'] / sw:.0f} x wall, {c['cpu_s'] / max(sc, 1e-3):.0f} x CPU, "
          f"{c['wall_s'] / ss:.0f} x against sil-host's simulation alone; Siconos h {hf:g}: "
          f"{sic[('bounce', hf)]['wall_s']:.1f} s wall ({max(1, jobs)} runs at once)")
    verdict = "FAILED" if report.failed else "passed"
    total = time.perf_counter() - started
    print(f"Siconos check {verdict} in {total:.1f} s wall")
    if record:
        times = {"siconos_wall": c["wall_s"], "siconos_cpu": c["cpu_s"], "sil_wall": sw, "sil_cpu": sc, "sil_sim": ss,
                 "runs": len(walls), "total": total, "load": os.getloadavg()[0], "jobs": max(1, jobs)}
        write_record(record, rows, times, exe, pkg.stdout.strip())
        print(f"wrote {record}")
    return FAIL if report.failed else PASS


def write_record(path, rows, times, exe, version):
    """Writes the comparison's Markdown (the body of docs/results.md's "Against Siconos",
    which `sil-host report` includes from tests/siconos/results.md): how it was made, the
    table of `rows`, the run times `times` (s)."""
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip() or "?"
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    t = times
    lines = [
        "```",
        "python3 tests/siconos/check.py --sil-host target/release/sil-host --record tests/siconos/results.md",
        "```",
        "",
        f"Debian's system Python with `python3-siconos` {version} (apt); `scripts/test.sh` runs the check, CI requires it. "
        "The arm of docs/model.md built in Siconos: a `LagrangianDS` (`M`, `w`, `c` and their Jacobians from a C plugin "
        "compiled at test time), a `LagrangianRheonomousR` with `h(q, t) = [z_n + H, z_t - v_belt t]`, "
        f"`NewtonImpactFrictionNSL(e_n, 0, mu, 2)`, Moreau-Jean (theta {THETA}) time-stepping with a 2D Lemke "
        "friction-contact solver at every step; against `sil-host simulate --iwc plastic` (the impact without collision "
        "leaves `v_n = 0`, as Moreau-Jean does). From x0a and x0d projected onto the belt (both codes project them "
        f"alike), `e_n = {E_N}`, `v_belt = {V_BELT}` m/s, and the locked bounce at `v_belt = {LOCKED_V_BELT}` m/s. "
        f"At the singular point `p = b = 0` (issue 81), issue 53's arm (`m {ISSUE53['m']}, l {ISSUE53['l']}, sigma "
        f"{ISSUE53['sigma']}, k {ISSUE53['k']}, H {ISSUE53['h']}, alpha0 {ISSUE53['alpha0']}`) from rest, Siconos "
        f"at `h = {CORNER_H[0]:g}` and `{CORNER_H[1]:g}` s (the two Siconos columns of those rows): at `mu = "
        f"{CORNERS['attracted'][0]}` the slide is attracted into the point and the slip arrested there, at `mu = "
        f"{CORNERS['force first'][0]}` the force vanishes first and the tip lifts off with its slip. Measured {stamp}, "
        f"sil-host at commit `{commit}`. Tolerances: the coarse Siconos run's own error under first-order "
        f"convergence, `{H_COARSE / (H_COARSE - H_FINE):g} |X({H_COARSE:g}) - X({H_FINE:g})|` (at the singular "
        f"point `{CORNER_H[0] / (CORNER_H[0] - CORNER_H[1]):.3g} |X({CORNER_H[0]:g}) - X({CORNER_H[1]:g})|` plus the "
        f"fine step; for the locked bounce, at `h = {LOCKED_H[0]:g}` and `{LOCKED_H[1]:g}` s, "
        f"`{LOCKED_H[0] / (LOCKED_H[0] - LOCKED_H[1]):g} |X({LOCKED_H[0]:g}) - X({LOCKED_H[1]:g})|`), plus twice the "
        "count's sampling spread for the lift-offs and one lift-off for the locked bounce's window "
        "(tests/siconos/README.md); Richardson's `h -> 0` estimate beside them.",
        "",
        f"| check | Siconos h = {H_COARSE:g} s | Siconos h = {H_FINE:g} s | Siconos h -> 0 | sil-host | tolerance | result |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += ["| " + " | ".join(str(x) for x in row) + " |" for row in rows]
    lines += [
        "",
        f"Run time of the same case in the same sitting (x0a, mu = 0.6, {BOUNCE_T:g} s): Siconos at h = {H_COARSE:g} s "
        f"(model built and stepped from Python) {t['siconos_wall']:.2f} s wall, {t['siconos_cpu']:.2f} s CPU; "
        f"`sil-host simulate` (the whole process, files written, median of {t['runs']}) {t['sil_wall']:.3f} s wall, "
        f"{t['sil_cpu']:.3f} s CPU, {t['sil_sim']:.3f} s of it simulating. Siconos / sil-host: "
        f"**{t['siconos_wall'] / t['sil_wall']:.0f} times** the wall time, "
        f"{t['siconos_cpu'] / max(t['sil_cpu'], 1e-3):.0f} times the CPU time, "
        f"{t['siconos_wall'] / t['sil_sim']:.0f} times sil-host's simulation alone. The whole check: "
        f"{t['total']:.0f} s of wall time ({t['jobs']} Siconos runs at once; the machine's load average "
        f"{t['load']:.1f} on {os.cpu_count()} cores as it ended).",
    ]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def fmt(values):
    """Numbers (s) as a short bracketed list, 6 decimals."""
    return "[" + ", ".join(f"{v:.6f}" for v in values) + "]"


if __name__ == "__main__":
    sys.exit(main())
