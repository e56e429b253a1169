"""A law of one's own, prototyped in Python before it goes to the MCU: the impedance
controller of examples/law-template (N. Hogan, "Impedance Control", ASME JDSMC 107,
1985) as a `painleve.run_controller` function (docs/python.md, "Your own law, from
Python to the MCU"; the Rust law: examples/law-template/src/lib.rs).

    F_t = k_t (z_t* - z_t) + d_t (z_t_dot* - z_t_dot)
    F_n = k_n (-H - f_n*/k_n - z_n) - d_n z_n_dot
    u'  = w + c + J^T [F_t, F_n]          (generalised torques, N m; painleve.Model.bias)
    u   = [u'_1 + u'_2, u'_2]              (motor torques, N m)

`z_t*` is the firmware's quintic move from the first frame's tip position to
`controller.target_z_t` over `controller.move_time_s`, `f_n*` its ramp from the first
frame's measured `f_n` over 0.25 s, and the joint angles and velocities the firmware's
model-driven alpha-beta trackers' (all three from hybrid_in_python.py, which ports them
from firmware/src): the Rust law gets the same estimate from the firmware's step.
`--observer sensed` uses `Sensed.theta1_dot`, `theta2_dot` instead (the trackers
without the model's prediction): their lag at 40 Hz is enough to lift this law's tip
off the belt, which is why the firmware drives its prediction with the model.

    python examples/python/impedance_prototype.py                   # the template's scenario, 2 s
    python examples/python/impedance_prototype.py --compare runs/impedance

`--compare DIR` reads a run of the Rust law (`sil-host run --attach`, `sil-host pil
--image .../law-pil`: examples/law-template/README.md) and prints both.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from typing import Tuple

import numpy as np

import painleve

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hybrid_in_python import FORCE_RAMP_S, OBSERVER_BANDWIDTH, AngleTracker, applied_torque, quintic  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENARIO = os.path.join(ROOT, "examples", "law-template", "impedance.toml")


class Impedance:
    """`law(t, sensed) -> (u1, u2)` in N m: the impedance law with the parameters of
    `scenario`'s `[law]` table (k_t, d_t N/m and N s/m along the belt; k_n, d_n across)."""

    def __init__(self, scenario: painleve.Scenario, observer: str = "model") -> None:
        d = scenario.to_dict()
        self.observer = observer
        self.ts = 1.0 / float(scenario["timing.rate_hz"])  # s
        self.applied = np.zeros(2)  # the motor torques applied since the last frame, N m
        law, c = d["law"], d["controller"]
        self.k_t, self.d_t, self.k_n, self.d_n = (float(law[k]) for k in ("k_t", "d_t", "k_n", "d_n"))
        self.model = painleve.Model(scenario)
        self.h = self.model.params["h"]  # m, the belt's surface is z_n = -H
        self.target, self.move_time, self.f_n_ref = float(c["target_z_t"]), float(c["move_time_s"]), float(c["f_n_ref"])
        self.start = None

    def _estimate(self, y: painleve.Sensed) -> Tuple[np.ndarray, np.ndarray]:
        """Joint angles (rad) and velocities (rad/s): the trackers, their prediction
        driven by the model's `M q_ddot = u - (w + c) + J^T f` (paper eq. 1) under the
        torque applied since the last frame and the force measured now."""
        if self.observer == "sensed":
            return np.array([y.theta1, y.theta2]), np.array([y.theta1_dot, y.theta2_dot])
        tr = self.trackers
        if self.updated:
            x = [tr[0].angle, tr[0].rate, tr[1].angle, tr[1].rate]
            theta = [x[0], x[2]]
            rhs = self.model.generalised_torque(self.applied) - self.model.bias(x) + self.model.jacobian(theta).T @ [y.f_t, y.f_n]
            qdd = np.linalg.solve(self.model.mass_matrix(theta), rhs)
            tr[0].update(y.theta1, self.ts, qdd[0])
            tr[1].update(y.theta2, self.ts, qdd[1])
        self.updated = True
        return np.array([tr[0].angle, tr[1].angle]), np.array([tr[0].rate, tr[1].rate])

    def __call__(self, t: float, y: painleve.Sensed) -> Tuple[float, float]:
        if not y.valid:  # a flagged frame: the firmware holds its command
            return tuple(self.applied)
        if self.start is None:  # the first frame: the trackers, the reference's and the ramp's start
            self.trackers = [AngleTracker(y.theta1, OBSERVER_BANDWIDTH, self.ts), AngleTracker(y.theta2, OBSERVER_BANDWIDTH, self.ts)]
            self.updated = False
            z0 = self.model.tip([y.theta1, y.theta2])
            self.start = (t, float(z0[0]), min(max(y.f_n, 0.0), self.f_n_ref))
        q, qd = self._estimate(y)
        z = self.model.tip(q)
        t0, z0, f0 = self.start
        pos, vel, _ = quintic(z0, self.target, self.move_time, t - t0)
        f_ref = quintic(f0, self.f_n_ref, FORCE_RAMP_S, t - t0)[0]
        jac = self.model.jacobian(q)
        z_dot = jac @ qd
        force = np.array([
            self.k_t * (pos - z[0]) + self.d_t * (vel - z_dot[0]),
            self.k_n * (-self.h - f_ref / self.k_n - z[1]) - self.d_n * z_dot[1],
        ])
        u = self.model.bias(np.array([q[0], qd[0], q[1], qd[1]])) + jac.T @ force
        motor = (float(u[0] + u[1]), float(u[1]))
        self.applied = np.array([applied_torque(motor[0])[0], applied_torque(motor[1])[0]])
        return motor


def figures(trace) -> Tuple[float, float, float]:
    """Final z_t (m), rms |z_t - z_t*| over the run (m) and final f_n (N) of a trace."""
    z, ref, f_n = (np.asarray(trace[c], dtype=float) for c in ("z_t", "z_t_ref", "f_n"))
    if np.isnan(ref).all():  # run_controller's trace has no reference: the law's own
        ref = None
    err = None if ref is None else float(np.sqrt(np.nanmean((z - ref) ** 2)))
    return float(z[-1]), err, float(f_n[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=SCENARIO)
    ap.add_argument("--duration", type=float, default=2.0, help="s (default 2)")
    ap.add_argument("--compare", metavar="DIR", help="a run folder of the Rust law to print beside")
    ap.add_argument("--observer", choices=("model", "sensed"), default="model", help="the joint velocities: the firmware's (default) or Sensed's")
    args = ap.parse_args(argv)
    scenario = painleve.Scenario.load(args.scenario).set("timing.duration_s", args.duration)
    result = painleve.run_controller(Impedance(scenario, args.observer), scenario)
    z_end, _, f_end = figures(result.trace)
    print(f"Python prototype: final z_t {z_end:.5f} m (target {scenario['controller.target_z_t']} m), final f_n {f_end:.3f} N")
    if args.compare:
        run = painleve.load(args.compare)
        z_rust, rms, f_rust = figures(run.trace)
        print(f"Rust law ({args.compare}): final z_t {z_rust:.5f} m, final f_n {f_rust:.3f} N"
              + ("" if rms is None else f", rms tracking error {rms * 1e3:.3f} mm"))
        print(f"difference: z_t {abs(z_end - z_rust) * 1e3:.3f} mm, f_n {abs(f_end - f_rust):.3f} N")
    return 0


if __name__ == "__main__":
    sys.exit(main())
