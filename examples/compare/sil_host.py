"""sil-host's side of the comparison: `sil-host simulate` and `sil-host sweep`, run and read
(examples/compare/README.md).

sil-host is the rigid model: the tip on the belt or off it, Coulomb friction, Newton's
restitution at touchdown (e_n, default 0.2) and the impact without collision where the contact
problem has no solution (docs/plant.md). Its defaults are the comparison's: `--impact-law newton
--e-n 0.2 --iwc restitution`.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import time

import numpy as np


class SilHostError(Exception):
    """sil-host failed on a valid command."""


def simulate(exe: str, x0: str, mu: float, v_belt: float, duration: float, folder: str,
             e_n: float = 0.2) -> dict:
    """Runs `sil-host simulate` (open loop) from docs/model.md's `x0` (`a` or `d`; sil-host
    projects it onto the belt) at `mu`, `v_belt` (m/s), Newton's `e_n`, for `duration` s into
    `folder` (summary.json, events.csv, trace.csv at 1 ms). Returns summary.json's document with
    `process_wall_s` (the whole process's wall time, s) added. Raises SilHostError on failure."""
    cmd = [exe, "simulate", "--x0", x0, "--mu", repr(mu), "--v-belt", repr(v_belt), "--e-n", repr(e_n),
           "--duration", repr(duration), "--no-page", "--json", "--out", folder]
    wall0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - wall0
    if done.returncode != 0:
        raise SilHostError(f"{' '.join(cmd)} exited {done.returncode}:\n{done.stderr}")
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    summary["process_wall_s"] = wall
    return summary


def digest(folder: str, summary: dict, window, high: float, belt_height: float) -> dict:
    """What the comparison reads from a sil-host run's folder over `window` = (t0, t1] s.

    lift_offs: the tip leaving the belt, from events.csv at the events' exact times (a
    `lift_off`, or a touchdown or impact without collision after which the tip flies:
    `mode_after` flight); high_flights: upward crossings of `high` m above the belt in
    trace.csv (1 ms samples; a flight that high lasts several ms); max_gap and min_gap: the
    largest and smallest z_n + H (m, `belt_height` = H) in trace.csv; final_z_t (m),
    final_mode, start_deg (the projected x0, deg), wall_s (its simulation's wall time, s)."""
    t0, t1 = window
    lifts = 0
    with open(os.path.join(folder, "events.csv")) as f:
        for row in csv.DictReader(f):
            t = float(row["t"])
            leaves = row["kind"] == "lift_off" or (
                row["kind"] in ("touchdown", "impact_without_collision") and row["mode_after"] == "flight")
            lifts += leaves and t0 < t <= t1
    trace = np.genfromtxt(os.path.join(folder, "trace.csv"), delimiter=",", names=True, usecols=(0, 6))
    t, gap = trace["t"], trace["z_n"] + belt_height
    inside = (t > t0) & (t <= t1 + 1e-12)
    up = gap > high
    rises = np.concatenate([[False], ~up[:-1] & up[1:]])
    used = summary["initial_condition"]["used_deg"]
    return {"lift_offs": int(lifts), "high_flights": int((rises & inside).sum()),
            "max_gap": float(gap[inside].max()), "min_gap": float(gap[inside].min()),
            "final_z_t": float(summary["final_tip"][0]), "final_mode": summary["final_mode"],
            "start_deg": (used[0], used[2]), "wall_s": float(summary["wall_s"]),
            "process_wall_s": float(summary["process_wall_s"])}


def sweep(exe: str, x0s, mu: float, v_belt: float, transient: float, record: float, folder: str,
          threads: int = 1, e_n: float = 0.2) -> dict:
    """Runs `sil-host sweep` open loop (u = 0, Newton's `e_n`, the impact without collision
    throwing the tip off: sil-host's defaults) at one `mu` and `v_belt` (m/s) from the paper's
    initial conditions `x0s` (`a`, `d`), `transient` s, then the record window of `record` s, into
    `folder`. Returns, by x0, runs.csv's record-window measurements: `lift_offs` (the tip leaving
    the belt, at the events' exact times), `max_gap` (the highest tip position above the belt, m)
    and `outcome` (the sweep's class: bouncing, contact, oscillating). Raises SilHostError on
    failure."""
    cmd = [exe, "sweep", "--mu", repr(mu), f"--v-belt={v_belt!r}", "--ics", ",".join(x0s),
           "--transient", repr(transient), "--record", repr(record), "--e-n", repr(e_n), "--threads", str(threads),
           "--out", folder, "--json"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SilHostError(f"{' '.join(cmd)} exited {done.returncode}:\n{done.stderr}")
    out = {}
    with open(os.path.join(folder, "runs.csv")) as f:
        for row in csv.DictReader(f):
            if row.get("error"):
                raise SilHostError(f"{' '.join(cmd)}: run {row['index']} failed: {row['error']}")
            out[row["ic"].removeprefix("x0")] = {"lift_offs": int(row["lift_offs"]),
                                                  "max_gap": float(row["tip_height_max"]),
                                                  "outcome": row["outcome"]}
    return out
