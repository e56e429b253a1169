#!/usr/bin/env python3
"""The paper's arm in MuJoCo beside sil-host: why not MuJoCo? (issue 69; examples/compare/README.md)

Builds the arm on the moving belt in MuJoCo (mujoco_arm.py), checks it against docs/model.md at
random states (model_check.py), and runs three cases in MuJoCo with its default soft contact and
with its stiffest stable one, beside `sil-host simulate` (sil_host.py):

1. the bounce from x0a at mu 0.6, v_belt -0.5 m/s (sil-host bounces);
2. the critical mu, from x0a at v_belt -0.5 m/s: 0.34 slides and 0.39 bounces in sil-host;
3. x0d at mu 0.6 (sil-host slides);

and measures MuJoCo's effective restitution with a drop test (restitution.py). It prints one PASS
or FAIL line per check of the outcomes (what each contact model does in each case) and the table.

    python examples/compare/compare.py --sil-host target/release/sil-host            # 300 s runs
    python examples/compare/compare.py --sil-host target/release/sil-host --quick    # the test's
    python examples/compare/compare.py --record examples/compare/results.md          # the record

Exit codes: 0 every check passed, 1 a check failed (or sil-host failed), 2 MuJoCo, painleve,
NumPy or sil-host missing.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass

PASS, FAIL, SETUP = 0, 1, 2

V_BELT = -0.5  # m/s, every case
HIGH = 1e-4  # m: a flight counts as a bounce when the tip rises this far above the belt
BOUNCES_MIN = 5  # flights that high in the window: the tip bounces
SUNK = 1e-8  # m: a tip deeper in the belt than this is said to sink (sil-host's rigid belt: 0)
BIG_GAP = 0.01  # m: a large bounce (sil-host's at mu 0.6 reaches 4.8 cm)
SPEED_DEPENDENCE = 0.1  # a restitution that differs by this much depends on the impact (its speed, its step phase)
MODEL_TOL = 1e-12  # the MuJoCo model against docs/model.md, relative
START_TOL_DEG = 1e-6  # this example's projected start against sil-host's
BELT_TOL = 0.01  # the belt servo holds v_belt within this fraction
H_COARSE, H_FINE = 1e-4, 1e-5  # MuJoCo's steps, s
DROP_SPEEDS = (0.1, 0.3, 1.0)  # m/s, the drop test's impact speeds
X0_DEG = {"a": (32.0, 18.27), "d": (-11.4, -35.1)}  # docs/model.md: theta1, theta2 at rest, deg

# Durations (s) and windows (t0, t1] (s): the record's follow experiment 3 (250 s of transient, 50 s
# recorded); the quick ones (the test's) record the same 50 s after 10 s, when every class has settled.
SIZES = {
    "full": {"duration": 300.0, "window": (250.0, 300.0), "fine_duration": 60.0, "fine_window": (10.0, 60.0),
             "fine": None},
    "quick": {"duration": 60.0, "window": (10.0, 60.0), "fine_duration": 20.0, "fine_window": (5.0, 20.0),
              "fine": [("1", "default"), ("3", "stiffest")]},
}


@dataclass(frozen=True)
class Case:
    """One run's set-up: `key` (the table's case), docs/model.md's initial condition `x0` (`a`
    or `d`), Coulomb's `mu`, and what the case is about."""

    key: str
    x0: str
    mu: float
    about: str


CASES = [
    Case("1", "a", 0.6, "the bounce from x0a"),
    Case("2a", "a", 0.34, "below the critical mu"),
    Case("2b", "a", 0.39, "above the critical mu"),
    Case("3", "d", 0.6, "x0d"),
]
CASE = {c.key: c for c in CASES}


def classify(d: dict) -> str:
    """`bounces` (at least BOUNCES_MIN flights higher than HIGH in the window), `slides` (none:
    the tip never rises HIGH above the belt; a soft contact may still leave it by less, at the
    step's scale) or `hops` (in between)."""
    if d["high_flights"] >= BOUNCES_MIN:
        return "bounces"
    return "slides" if d["high_flights"] == 0 else "hops"


def project(arm, x0: str):
    """docs/model.md's `x0` (`a` or `d`) put on the belt at the same z_t and elbow branch
    ("Initial conditions"): [theta1, theta2] in rad, from painleve.Model's inverse kinematics."""
    th1, th2 = (math.radians(v) for v in X0_DEG[x0])
    z_t = arm.tip([th1, th2])[0]
    return arm.inverse_kinematics([z_t, -arm.params["h"]], branch="down" if th2 < th1 else "up")


def measure(exe: str, size: str, jobs: int, work: str) -> dict:
    """Every measurement (see the module's docstring) at `size` (`full` or `quick`), MuJoCo on
    `jobs` threads, sil-host's files in `work`. Returns a dict: `sil` (by case) and `sil_e0`
    (sil_host.digest's), `mj` (mujoco_arm.Digest's fields by (case, contact, h)), `drops`
    (restitution.drops' by (contact, "arm" or "law", speed)), `model` (model_check.check's),
    `starts` (the projected x0, here and sil-host's), `times` (s), `versions`, `durations`
    (SIZES[size]) and `size`."""
    import mujoco
    import painleve

    import model_check
    import mujoco_arm
    import restitution
    import sil_host

    sz = SIZES[size]
    arm = painleve.Model(mu=0.6, v_belt=V_BELT)
    params = {k: v for k, v in arm.params.items() if k not in ("mu", "v_belt")}
    out = {"size": size, "sil": {}, "mj": {}, "drops": {}, "times": {}, "starts": {}}
    started = time.perf_counter()

    out["model"] = model_check.check(mujoco_arm.build(params, 0.6, H_COARSE, mujoco_arm.default_contact()), arm)

    # sil-host, each case, and x0a at mu 0.6 with e_n = 0 (what the default contact resembles).
    for c in CASES:
        folder = os.path.join(work, f"sil-{c.key}")
        summary = sil_host.simulate(exe, c.x0, c.mu, V_BELT, sz["duration"], folder)
        out["sil"][c.key] = sil_host.digest(folder, summary, sz["window"], HIGH, params["h"])
    folder = os.path.join(work, "sil-1-e0")
    summary = sil_host.simulate(exe, "a", 0.6, V_BELT, sz["duration"], folder, e_n=0.0)
    out["sil_e0"] = sil_host.digest(folder, summary, sz["window"], HIGH, params["h"])
    for c in CASES:
        mine = [math.degrees(v) for v in project(arm, c.x0)]
        out["starts"][c.x0] = (mine, out["sil"][c.key]["start_deg"])

    def batch(runs, h, duration, window):
        """MuJoCo runs [(case, contact name)] at step h in one rollout batch, their digests into
        out["mj"]; returns the batch's wall time (s)."""
        models, states = [], []
        for key, contact in runs:
            c = CASE[key]
            setting = mujoco_arm.default_contact() if contact == "default" else mujoco_arm.stiffest_contact(h)
            model = mujoco_arm.build(params, c.mu, h, setting)
            th = project(arm, c.x0)
            models.append(model)
            states.append(mujoco_arm.initial_state(model, [th[0], 0.0, th[1], 0.0], V_BELT))
        digests = mujoco_arm.roll(models, states, duration, h, [window] * len(runs), [V_BELT] * len(runs),
                                  params, HIGH, nthread=jobs)
        for (key, contact), d in zip(runs, digests):
            out["mj"][(key, contact, h)] = vars(d)
        return digests[0].wall_s if digests else 0.0

    every = [(c.key, contact) for c in CASES for contact in ("default", "stiffest")]
    out["times"]["coarse"] = batch(every, H_COARSE, sz["duration"], sz["window"])
    out["times"]["fine"] = batch(sz["fine"] or every, H_FINE, sz["fine_duration"], sz["fine_window"])

    # The effective restitution: the tip dropped on the belt where x0d puts it.
    z_t = arm.tip(project(arm, "d"))[0]
    free = dict(params, g=0.0, k=0.0)  # the contact law alone: no gravity, no spring
    for contact in (mujoco_arm.default_contact(), mujoco_arm.stiffest_contact(H_COARSE)):
        for speed in DROP_SPEEDS:
            out["drops"][(contact.name, "arm", speed)] = restitution.drops(params, arm, z_t, contact, H_COARSE, speed)
            out["drops"][(contact.name, "law", speed)] = restitution.drops(free, arm, z_t, contact, H_COARSE, speed)

    if size == "full":
        # Run time of case 1 alone for the whole duration: MuJoCo (stiffest, one thread) and sil-host.
        model = mujoco_arm.build(params, 0.6, H_COARSE, mujoco_arm.stiffest_contact(H_COARSE))
        th = project(arm, "a")
        state = mujoco_arm.initial_state(model, [th[0], 0.0, th[1], 0.0], V_BELT)
        d, = mujoco_arm.roll([model], [state], sz["duration"], H_COARSE, [sz["window"]], [V_BELT], params, HIGH, 1)
        walls = sorted(sil_host.simulate(exe, "a", 0.6, V_BELT, sz["duration"], os.path.join(work, "sil-time"))
                       ["process_wall_s"] for _ in range(3))
        out["times"]["one_mujoco"], out["times"]["one_sil"] = d.wall_s, walls[1]
    out["times"]["total"] = time.perf_counter() - started
    out["versions"] = {"mujoco": mujoco.__version__, "python": platform.python_version()}
    out["durations"] = sz
    return out


def evaluate(r: dict) -> list:
    """The checks over measure()'s result `r`: a list of (passed, text)."""
    checks = []
    mj, sil = r["mj"], r["sil"]
    m = r["model"]
    worst = max(m["mass_matrix"], m["forces"], m["tip"])
    checks.append((worst <= MODEL_TOL,
                   f"the MuJoCo model is docs/model.md's at {m['samples']} random states: largest relative difference "
                   f"mass matrix {m['mass_matrix']:.1e}, passive minus bias forces {m['forces']:.1e}, tip "
                   f"{m['tip']:.1e} (tolerance {MODEL_TOL:g})"))
    for x0, (mine, theirs) in sorted(r["starts"].items()):
        err = max(abs(a - b) for a, b in zip(mine, theirs))
        checks.append((err <= START_TOL_DEG,
                       f"x0{x0} projected onto the belt: here [{mine[0]:.6f}, {mine[1]:.6f}] deg, sil-host "
                       f"[{theirs[0]:.6f}, {theirs[1]:.6f}] deg (differ by {err:.1e} deg)"))
    want = {"1": "bounces", "2a": "slides", "2b": "bounces", "3": "slides"}
    for key, cls in want.items():
        got = classify(sil[key])
        checks.append((got == cls, f"sil-host, case {key} ({describe(key)}): {cls} (measured: {said(sil[key])})"))
    for (key, contact, h), d in sorted(mj.items(), key=lambda kv: (kv[0][2] != H_COARSE, kv[0])):
        if contact == "default":
            checks.append((classify(d) == "slides",
                           f"MuJoCo default contact, h {h:g} s, case {key} ({describe(key)}): never bounces "
                           f"(measured: {said(d)})"))
    for h in sorted({k[2] for k in mj}, reverse=True):
        if ("3", "stiffest", h) in mj:
            d = mj[("3", "stiffest", h)]
            checks.append((classify(d) == "bounces" and classify(sil["3"]) == "slides",
                           f"MuJoCo stiffest contact, h {h:g} s, case 3 (x0d, mu 0.6): bounces where sil-host slides "
                           f"(measured: {said(d)})"))
    for h in sorted({k[2] for k in mj}, reverse=True):
        runs = {key: mj[(key, "stiffest", h)] for key in CASE if (key, "stiffest", h) in mj}
        if len(runs) == len(CASE):
            big = {key: d["max_gap"] >= BIG_GAP for key, d in runs.items()}
            ok = classify(runs["2a"]) == "bounces" and big == {"1": False, "2a": True, "2b": False, "3": False}
            checks.append((ok, f"MuJoCo stiffest contact, h {h:g} s: the large bounce (a gap of {BIG_GAP * 100:g} cm "
                               f"or more) only at mu 0.34, below sil-host's critical mu (largest gaps: "
                               + ", ".join(f"case {k} {d['max_gap'] * 100:.2f} cm" for k, d in runs.items()) + ")"))
    for (key, contact, h), d in mj.items():
        if h != H_COARSE and (key, contact, H_COARSE) in mj:
            coarse = mj[(key, contact, H_COARSE)]
            checks.append((classify(d) == classify(coarse),
                           f"MuJoCo {contact} contact, case {key}: h {h:g} s gives h {H_COARSE:g} s's outcome "
                           f"({classify(d)}; at h {H_COARSE:g}: {classify(coarse)})"))
    err = max(d["belt_speed_error"] for d in mj.values())
    checks.append((err <= BELT_TOL * abs(V_BELT),
                   f"MuJoCo's belt servo holds v_belt: largest |v - v_belt| {err:.1e} m/s in any window "
                   f"(tolerance {BELT_TOL * abs(V_BELT):g})"))
    lo, hi = (r["drops"][("default", "arm", s)]["e"] for s in (DROP_SPEEDS[0], DROP_SPEEDS[-1]))
    checks.append((hi - lo >= SPEED_DEPENDENCE,
                   f"MuJoCo default contact: the effective restitution depends on the impact speed: {lo:.3f} at "
                   f"{DROP_SPEEDS[0]:g} m/s, {hi:.3f} at {DROP_SPEEDS[-1]:g} m/s (differ by {SPEED_DEPENDENCE:g} or more)"))
    spreads = [r["drops"][("stiffest", "law", s)] for s in DROP_SPEEDS]
    checks.append((all(d["e_max"] - d["e_min"] >= SPEED_DEPENDENCE for d in spreads),
                   "MuJoCo stiffest contact: the contact law's effective restitution depends on where in a step the "
                   "contact begins: "
                   + ", ".join(f"{d['e_min']:.3f} to {d['e_max']:.3f} at {s:g} m/s" for s, d in zip(DROP_SPEEDS, spreads))
                   + f" over {spreads[0]['phases']} starts a fraction of a step apart (ranges of {SPEED_DEPENDENCE:g} "
                   "or more)"))
    return checks


def describe(key: str) -> str:
    """A case's set-up in words: `x0a, mu 0.6`."""
    c = CASE[key]
    return f"x0{c.x0}, mu {c.mu:g}"


def said(d: dict, per: str = "") -> str:
    """A run's outcome in words, with its numbers (the window's); `per` follows a count."""
    cls = classify(d)
    if cls == "slides":
        text = f"slides to z_t {d['final_z_t']:.4f} m"
        if d["min_gap"] < -SUNK:
            text += f", sunk {-d['min_gap'] * 1e6:.1f} um at most"
        if d["lift_offs"]:
            text += f"; {d['lift_offs']} step-scale lift-offs{per} of at most {d['max_gap'] * 1e6:.1f} um"
        return text
    return (f"{cls}: {d['high_flights']} flights above {HIGH * 1e3:g} mm{per} ({d['lift_offs']} lift-offs), "
            f"largest gap {d['max_gap'] * 100:.2f} cm")


def table(r: dict) -> list:
    """The comparison as Markdown lines: the outcomes at h 1e-4 s, then at h 1e-5 s, then the drops."""
    sz = r["durations"]
    w0, w1 = sz["window"]
    per = f" / {w1 - w0:g} s"
    lines = [
        f"| case | sil-host (rigid, Newton e_n 0.2) | MuJoCo default contact (solref 0.02 1) | "
        f"MuJoCo stiffest contact (solref 2h 1, solimp 0.99 0.999 1e-4) |",
        "|---|---|---|---|",
    ]
    for c in CASES:
        cells = [f"{c.key}: {c.about} ({describe(c.key)})", said(r["sil"][c.key], per)]
        for contact in ("default", "stiffest"):
            cells.append(said(r["mj"][(c.key, contact, H_COARSE)], per))
        lines.append("| " + " | ".join(cells) + " |")
    fine = sorted({(k[0], k[1]) for k in r["mj"] if k[2] == H_FINE})
    if fine:
        f0, f1 = sz["fine_window"]
        lines += ["", f"At h = {H_FINE:g} s ({sz['fine_duration']:g} s runs, window ({f0:g}, {f1:g}] s; the stiffest "
                      f"contact's time constant 2h = {2 * H_FINE:g} s):", "",
                  "| case | MuJoCo default contact | MuJoCo stiffest contact |", "|---|---|---|"]
        for c in CASES:
            if any(k == c.key for k, _ in fine):
                cells = [said(r["mj"][(c.key, contact, H_FINE)], f" / {f1 - f0:g} s")
                         if (c.key, contact, H_FINE) in r["mj"] else "(not run)" for contact in ("default", "stiffest")]
                lines.append(f"| {c.key} ({describe(c.key)}) | " + " | ".join(cells) + " |")
    lines += ["", f"The tip dropped on the belt (frictionless, the belt at rest, where x0d puts the tip, h = {H_COARSE:g} s, "
                  "each the mean of drops that begin a fraction of a step apart, their range in brackets): the effective "
                  "restitution e (normal velocity out over in), the deepest sink, how long the tip stays in the belt:", "",
              "| contact | forces on the arm | " + " | ".join(f"{s:g} m/s" for s in DROP_SPEEDS) + " |",
              "|---|---|" + "---|" * len(DROP_SPEEDS)]
    for contact in ("default", "stiffest"):
        for forces, words in (("arm", "its own (gravity, spring)"), ("law", "none (the contact law alone)")):
            cells = []
            for s in DROP_SPEEDS:
                d = r["drops"][(contact, forces, s)]
                cells.append(f"e {d['e']:.3f} [{d['e_min']:.3f}, {d['e_max']:.3f}], sinks {d['sink'] * 1e3:.3f} mm, "
                             f"{d['contact_s'] * 1e3:.1f} ms")
            lines.append(f"| {contact} | {words} | " + " | ".join(cells) + " |")
    return lines


def report(r: dict, checks: list) -> None:
    """Prints the checks, the table and what else was measured."""
    for ok, text in checks:
        print(("PASS " if ok else "FAIL ") + text)
    print()
    print("\n".join(table(r)))
    print()
    print(notes(r))


def notes(r: dict) -> str:
    """The measurements beside the table, as one paragraph."""
    e0, t = r["sil_e0"], r["times"]
    text = (f"sil-host with e_n = 0 (perfectly plastic touchdowns) from x0a at mu 0.6: {said(e0)} (MuJoCo's default "
            f"contact from x0a at mu 0.6: {said(r['mj'][('1', 'default', H_COARSE)])}).")
    if "one_mujoco" in t:
        text += (f" Run time of case 1 for {r['durations']['duration']:g} s: MuJoCo at h = {H_COARSE:g} s (stiffest "
                 f"contact, mujoco.rollout on one thread) {t['one_mujoco']:.1f} s; `sil-host simulate` (the whole "
                 f"process, files written, median of 3) {t['one_sil']:.2f} s: **{t['one_mujoco'] / t['one_sil']:.0f} "
                 f"times** sil-host's wall time.")
    text += f" The whole comparison: {t['total']:.0f} s of wall time."
    return text


def write_record(path: str, r: dict, checks: list) -> None:
    """The comparison as Markdown (the body of docs/results.md's "Against MuJoCo", which `sil-host
    report` includes from examples/compare/results.md)."""
    here = os.path.dirname(os.path.abspath(__file__))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=here).stdout.strip() or "?"
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    sz, v = r["durations"], r["versions"]
    w0, w1 = sz["window"]
    passed = sum(ok for ok, _ in checks)
    m = r["model"]
    lines = [
        "```",
        "python examples/compare/compare.py --sil-host target/release/sil-host --record examples/compare/results.md",
        "```",
        "",
        f"MuJoCo {v['mujoco']} (PyPI `mujoco`, Python {v['python']}): the arm of docs/model.md as two hinges with its "
        "spring and damping, the belt a box on a slide joint held at `v_belt` by a stiff velocity servo, the tip a "
        "0.2 mm sphere; condim 3, friction `mu`, the pyramidal cone, Euler; against `sil-host simulate` (Newton "
        f"`e_n = 0.2`). The model equals docs/model.md's at {m['samples']} random states (mass matrix, passive minus "
        f"bias forces, tip: largest relative difference {max(m['mass_matrix'], m['forces'], m['tip']):.1e}). From x0a "
        f"and x0d projected onto the belt, `v_belt = {V_BELT}` m/s; each run {sz['duration']:g} s, outcomes over "
        f"t in ({w0:g}, {w1:g}] s. A bounce: {BOUNCES_MIN} flights or more higher than {HIGH * 1e3:g} mm in the "
        f"window; slides: none (the soft contact's step-scale lift-offs are counted beside). Measured {stamp}, "
        f"sil-host at commit `{commit}`; {passed} of {len(checks)} checks passed.",
        "",
    ]
    lines += table(r)
    lines += ["", notes(r)]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main(argv=None) -> int:
    """Measures, checks, prints; returns the exit code (0 pass, 1 a check failed, 2 setup)."""
    code, _, _ = run(argv)
    return code


def run(argv=None):
    """main's work: returns (exit code, measure()'s result or None, the checks)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sil-host", default=os.environ.get("PAINLEVE_SIL_HOST", "target/release/sil-host"),
                        help="the sil-host binary (default: $PAINLEVE_SIL_HOST or target/release/sil-host)")
    parser.add_argument("--quick", action="store_true",
                        help=f"the test's sizes: {SIZES['quick']['duration']:g} s runs at h {H_COARSE:g} s and two "
                             f"{SIZES['quick']['fine_duration']:g} s runs at {H_FINE:g} s (default: "
                             f"{SIZES['full']['duration']:g} s, every case at both steps)")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1), help="MuJoCo's threads")
    parser.add_argument("--keep", metavar="DIR", help="keep sil-host's outputs in DIR")
    parser.add_argument("--record", metavar="FILE",
                        help="write the comparison as Markdown to FILE (examples/compare/results.md, which `sil-host "
                             "report` puts in docs/results.md as \"Against MuJoCo\")")
    args = parser.parse_args(argv)
    here = os.path.dirname(os.path.abspath(__file__))
    if here not in sys.path:
        sys.path.insert(0, here)  # the example's modules
    try:
        import mujoco  # noqa: F401
        import numpy  # noqa: F401
        import painleve  # noqa: F401
    except ImportError as e:
        print(f"SETUP {e}: pip install mujoco==4.0.0 numpy and the painleve package (pip install ./python, "
              "docs/python.md)", flush=True)
        return SETUP, None, []
    exe = os.path.abspath(args.sil_host)
    if not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
        print(f"SETUP no sil-host at {exe}: cargo build --release -p sil-host", flush=True)
        return SETUP, None, []
    import sil_host

    work = args.keep or tempfile.mkdtemp(prefix="mujoco-compare-")
    os.makedirs(work, exist_ok=True)
    size = "quick" if args.quick else "full"
    print(f"MuJoCo {mujoco.__version__} against {exe}: {SIZES[size]['duration']:g} s runs ({size}), "
          f"v_belt {V_BELT} m/s, h {H_COARSE:g} and {H_FINE:g} s", flush=True)
    try:
        r = measure(exe, size, max(1, args.jobs), work)
    except sil_host.SilHostError as e:
        print(f"FAIL {e}", flush=True)
        return FAIL, None, []
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    checks = evaluate(r)
    report(r, checks)
    failed = not all(ok for ok, _ in checks)
    print(f"MuJoCo comparison {'FAILED' if failed else 'passed'} in {r['times']['total']:.1f} s wall", flush=True)
    if args.record:
        write_record(args.record, r, checks)
        print(f"wrote {args.record}")
    return (FAIL if failed else PASS), r, checks


if __name__ == "__main__":
    sys.exit(main())
