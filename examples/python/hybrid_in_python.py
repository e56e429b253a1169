"""The paper's hybrid force/motion law written in Python with `painleve.Model`, run in
the rig's loop with `painleve.run_controller`, and compared with the firmware's run of
the same scenario (docs/python.md, "The paper's hybrid law in Python").

Marchese, Coraggio, Hogan, di Bernardo, "Control of Painlevé Paradox in a Robotic
System" (ECC 2019), eqs. 9 to 11 (docs/model.md, experiment 6):

    u   = w + c + M J^-1 (-J_dot q_dot + i_x a_v) + J^T (-i_x f_t_hat - i_y a_f)
    a_v = z_t_ddot* + K'_P (z_t* - z_t) + K'_D (z_t_dot* - z_t_dot)
    a_f = f_n* + K'_I int (f_n* - f_n) dt

with `u` the generalised torque (`[u1 - u2, u2]`, N m), `J` the tip Jacobian (eq. 2),
`M` the mass matrix and `w + c` the arm's own forces (eq. 1), `f_t_hat = -mu_hat
sign(z_r_dot) a_f` (the firmware's default friction term, "commanded"). Every model
quantity comes from `painleve.Model` (`jacobian`, `jdot_qdot`, `mass_matrix`, `bias`,
`tip`, `generalised_torque`); the rest is NumPy.

The firmware's run (`painleve.run`, `firmware::Firmware::step`) adds what the paper
leaves open; this law does the same, as the firmware does it (firmware/src, read for
this port):

- the reference `z_t*(t)`: a quintic (minimum-jerk) move from the tip's position at the
  first frame to `controller.target_z_t` over `controller.move_time_s`, then a hold
  (firmware/src/reference.rs);
- a bumpless start: `f_n*` ramps (the same quintic) from the first frame's measured
  `f_n` (clamped to `[0, f_n*]`) to `controller.f_n_ref` over 0.25 s (`force_ramp_s`,
  firmware/src/config.rs; not a scenario key);
- anti-windup: the force integral holds while a motor saturated in the previous period
  and is clamped to `+-4 max(f_n*, 1) / K'_I`; it enters `a_f` one period after the
  error it integrates (firmware/src/law.rs);
- joint velocities from an alpha-beta tracker per angle at 40 Hz (both poles at
  `exp(-w Ts)`, `w = 2 pi 40` rad/s) whose prediction is driven by the model's joint
  acceleration `M^-1 (u - (w + c) + J^T f)` under the last applied torque and the
  measured tip force (firmware/src/estimator.rs, controller/step.rs). `Sensed.theta1_dot`
  is the same tracker without that prediction: `--observer sensed` uses it instead,
  to show what the model-driven prediction is worth.

What differs and cannot be removed: the firmware computes in `f32`, this law in
`float64`; the firmware's monitors (lift-off, sensor consistency, runaway, tracking)
never act on the default run, so they are left out. Both see the same frames (the
run_controller loop decodes them as the firmware does) and their torques go out as
the same 12-bit codes, so the residual is rounding, amplified only where the
contact is sensitive (the first touchdowns).

    python examples/python/hybrid_in_python.py                  # the default scenario (hybrid, x0d)
    python examples/python/hybrid_in_python.py --scenario scenarios/hybrid-x0u.toml
    python examples/python/hybrid_in_python.py --observer sensed

Prints the largest and final |z_t (Python law) - z_t (firmware)| in mm and exits 1 if
either is above 1 mm (`--tolerance-mm`).
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Dict, Optional, Tuple

import numpy as np

import painleve

# The firmware's constants that are not scenario keys (firmware/src/config.rs, Config::default).
FORCE_RAMP_S = 0.25  # s, the bumpless start of f_n*
OBSERVER_BANDWIDTH = 2.0 * math.pi * 40.0  # rad/s, the joint trackers' poles
TORQUE_LIMIT = 5.0  # N m per motor (docs/hardware.md)
TORQUE_LSB = TORQUE_LIMIT / 2048.0  # N m per 12-bit torque code (shared::wire::encode_torque)


def quintic(start: float, target: float, duration: float, t: float) -> Tuple[float, float, float]:
    """Position (m or N), velocity (/s) and acceleration (/s^2) of the minimum-jerk move
    `start + (target - start) (10 tau^3 - 15 tau^4 + 6 tau^5)`, `tau = t / duration`,
    held at `target` from `duration` on (firmware/src/reference.rs)."""
    if t >= duration:
        return target, 0.0, 0.0
    tau = max(t, 0.0) / duration
    d = target - start
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    ds = 30.0 * tau**2 * (1.0 - 2.0 * tau + tau**2)
    dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * tau**2)
    return start + d * s, d * ds / duration, d * dds / duration**2


def wrap(angle: float) -> float:
    """`angle` (rad) wrapped to `[-pi, pi)`."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def applied_torque(u: float) -> Tuple[float, bool]:
    """The torque (N m) the motor applies for command `u`, and whether it saturated:
    `u` limited to +-5 N m, then the 12-bit code, rounded half away from zero and
    limited to `[-2048, 2047]`, decoded (firmware::law::saturate,
    shared::wire::encode_torque). `run_controller` sends the controller's torques the
    same way."""
    x = min(max(u, -TORQUE_LIMIT), TORQUE_LIMIT) / TORQUE_LSB
    code = math.copysign(math.floor(abs(x) + 0.5), x)
    clamped = min(max(code, -2048.0), 2047.0)
    return clamped * TORQUE_LSB, abs(u) > TORQUE_LIMIT or clamped != code


class AngleTracker:
    """A critically damped alpha-beta tracker of one angle (firmware/src/estimator.rs):
    `r = exp(-w Ts)`, `alpha = 1 - r^2`, `beta = (1 - r)^2`, its prediction driven by a
    known angular acceleration (rad/s^2)."""

    def __init__(self, angle: float, w: float, ts: float) -> None:
        r = math.exp(-w * ts)
        self.angle, self.rate = angle, 0.0  # rad, rad/s
        self.alpha, self.beta_over_ts = 1.0 - r * r, (1.0 - r) ** 2 / ts

    def update(self, measured: float, dt: float, accel: float) -> None:
        predicted = self.angle + self.rate * dt + 0.5 * accel * dt * dt
        self.rate += accel * dt
        residual = wrap(measured - predicted)
        self.angle = predicted + self.alpha * residual
        self.rate += self.beta_over_ts * residual


class HybridLaw:
    """The paper's hybrid law (eqs. 9 to 11) as a `run_controller` controller:
    `law(t, sensed) -> (u1, u2)` in N m. Gains, reference and `mu_hat` from `scenario`
    (`controller.*`), the arm from `painleve.Model(scenario)`.

    `observer`: `"model"` (the firmware's model-driven tracker, the default) or
    `"sensed"` (`Sensed.theta1_dot`, `theta2_dot`: the tracker without the model)."""

    def __init__(self, scenario: painleve.Scenario, observer: str = "model") -> None:
        if observer not in ("model", "sensed"):
            raise ValueError(f"observer: expected 'model' or 'sensed', got {observer!r}")
        if scenario["controller.kind"] != "hybrid" or scenario["controller.friction"] != "commanded":
            raise ValueError("this port is of the hybrid law with the commanded friction term "
                             "(controller.kind = 'hybrid', controller.friction = 'commanded')")
        c = scenario.to_dict()["controller"]
        if "model" in c:
            raise ValueError("controller.model (a firmware model unlike the plant) is not ported")
        self.model = painleve.Model(scenario)  # the plant's [plant] parameters, paper Table I
        self.observer = observer
        self.kp = float(c["hybrid"]["kp"])  # K'_P, 1/s^2
        self.kd = float(c["hybrid"]["kd"])  # K'_D, 1/s
        # K'_I, 1/s: the scenario's, or the paper's, 650 from x0a and x0d, 0 from x0u
        # (rig::scenario::ControllerSection::hybrid_ki).
        self.ki = float(c["hybrid"].get("ki", 0.0 if scenario["plant.x0"] == "u" else 650.0))
        self.mu_hat = float(c["mu_hat"])
        self.target = float(c["target_z_t"])  # z_t*, m
        self.move_time = float(c["move_time_s"])  # s
        self.f_n_ref = float(c["f_n_ref"])  # f_n*, N
        self.ts = 1.0 / float(scenario["timing.rate_hz"])  # s
        self.started = False
        self.safe_at: Optional[float] = None  # s, when the law latched zero torque (a straight arm)

    def _start(self, y: painleve.Sensed) -> None:
        """The first frame: trackers at the measured angles at rest, the reference from
        the tip's position, the force ramp from the measured f_n."""
        self.trackers = [AngleTracker(y.theta1, OBSERVER_BANDWIDTH, self.ts), AngleTracker(y.theta2, OBSERVER_BANDWIDTH, self.ts)]
        self.z0 = float(self.model.tip([y.theta1, y.theta2])[0])
        self.f0 = min(max(y.f_n, 0.0), self.f_n_ref)
        self.k0 = y.k
        self.integral = 0.0  # int (f_n* - f_n) dt, N s
        self.applied = np.zeros(2)  # the motor torques applied in the last period, N m
        self.saturated = False
        self.started = True

    def _estimate(self, y: painleve.Sensed) -> Tuple[np.ndarray, np.ndarray]:
        """Joint angles (rad) and velocities (rad/s) at this frame."""
        if self.observer == "sensed":
            return np.array([y.theta1, y.theta2]), np.array([y.theta1_dot, y.theta2_dot])
        if y.k != self.k0:
            tr = self.trackers
            x = [tr[0].angle, tr[0].rate, tr[1].angle, tr[1].rate]
            theta = [x[0], x[2]]
            # M q_ddot = u - (w + c) + J^T f (paper eq. 1) under the torque applied since
            # the last frame and the force measured now.
            rhs = self.model.generalised_torque(self.applied) - self.model.bias(x) + self.model.jacobian(theta).T @ [y.f_t, y.f_n]
            qdd = np.linalg.solve(self.model.mass_matrix(theta), rhs)
            if not np.all(np.isfinite(qdd)):
                qdd = np.zeros(2)
            tr[0].update(y.theta1, self.ts, qdd[0])
            tr[1].update(y.theta2, self.ts, qdd[1])
        tr = self.trackers
        return np.array([tr[0].angle, tr[1].angle]), np.array([tr[0].rate, tr[1].rate])

    def __call__(self, t: float, y: painleve.Sensed) -> Tuple[float, float]:
        if not y.valid:
            # A frame with a sensor flagged or a count out of range (NaN values): the
            # firmware holds its previous command and does not step its estimator.
            return tuple(self.applied) if self.started else (0.0, 0.0)
        if not self.started:
            self._start(y)
        q, qd = self._estimate(y)
        state = np.array([q[0], qd[0], q[1], qd[1]])
        t_run = (y.k - self.k0) * self.ts
        pos, vel, acc = quintic(self.z0, self.target, self.move_time, t_run)
        f_ref = quintic(self.f0, self.f_n_ref, FORCE_RAMP_S, t_run)[0]
        m = self.model
        jac = m.jacobian(q)  # eq. 2, m/rad
        if self.safe_at is not None or abs(math.sin(q[0] - q[1])) < 1e-3:
            # A straight arm: J^-1 does not exist. The firmware latches its safe state
            # (zero torque, firmware::law::LawError::Singular); so does this law.
            self.safe_at = t if self.safe_at is None else self.safe_at
            self.applied = np.zeros(2)
            return 0.0, 0.0
        z_t = m.tip(q)[0]
        z_dot = jac @ qd
        a_v = acc + self.kp * (pos - z_t) + self.kd * (vel - z_dot[0])  # eq. 10, m/s^2
        a_f = f_ref + self.ki * self.integral  # eq. 11, N (the integral up to the last frame)
        if not self.saturated:
            self.integral += (f_ref - y.f_n) * self.ts
        i_max = 4.0 * max(f_ref, 1.0) / self.ki if self.ki > 0 else 0.0
        self.integral = min(max(self.integral, -i_max), i_max)
        s = -1.0 if z_dot[0] - y.v_belt < 0.0 else 1.0  # sign(z_r_dot)
        f_t_hat = -self.mu_hat * s * a_f  # N
        u_gen = (
            m.bias(state)
            + m.mass_matrix(q) @ np.linalg.solve(jac, np.array([a_v, 0.0]) - m.jdot_qdot(state))
            + jac.T @ np.array([-f_t_hat, -a_f])
        )  # eq. 9, N m
        u = (u_gen[0] + u_gen[1], u_gen[1])  # motor torques [u1, u2] = [u_1' + u_2', u_2']
        (a1, s1), (a2, s2) = applied_torque(u[0]), applied_torque(u[1])
        self.applied, self.saturated = np.array([a1, a2]), s1 or s2
        return u


def compare(scenario: Optional[painleve.Scenario] = None, observer: str = "model") -> Dict[str, object]:
    """Runs the firmware (`painleve.run`) and the Python law (`painleve.run_controller`)
    on `scenario` (default: the default scenario, hybrid from x0d, 10 s) and returns both
    results and the differences of `z_t`, m: `max_dz` over the run, `final_dz` at its end."""
    scenario = painleve.Scenario.default() if scenario is None else scenario
    firmware = painleve.run(scenario=scenario, progress=False)
    law = HybridLaw(scenario, observer)
    python = painleve.run_controller(law, scenario)
    for r in (firmware, python):
        r.check()
    fz, pz = firmware.trace["z_t"], python.trace["z_t"]
    if fz.shape != pz.shape:
        raise AssertionError(f"the runs have {fz.size} and {pz.size} periods")
    dz = pz - fz
    # The firmware's own constants, which this port writes out, as the run reports them.
    cfg = firmware.summary["firmware_config"]
    for name, mine, theirs in [
        ("force_ramp_s", FORCE_RAMP_S, cfg["force_ramp_s"]),
        ("observer_bandwidth", OBSERVER_BANDWIDTH, cfg["observer_bandwidth"]),
        ("torque_limit", TORQUE_LIMIT, cfg["torque_limit"]),
        ("hybrid.ki", law.ki, cfg["hybrid"]["ki"]),
    ]:
        if not math.isclose(mine, theirs, rel_tol=1e-6):
            raise AssertionError(f"the port's {name} = {mine} but the firmware's is {theirs}")
    return {
        "firmware": firmware,
        "python": python,
        "law": law,
        "dz": dz,
        "max_dz": float(np.max(np.abs(dz))),
        "t_max_dz": float(firmware.trace["t"][np.argmax(np.abs(dz))]),
        "final_dz": float(abs(dz[-1])),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", help="a scenario TOML (default: the default scenario, hybrid from x0d)")
    ap.add_argument("--observer", choices=["model", "sensed"], default="model",
                    help="joint velocities: the firmware's model-driven tracker (default) or Sensed.theta*_dot")
    ap.add_argument("--tolerance-mm", type=float, default=1.0, help="the largest |delta z_t| allowed, mm (1)")
    args = ap.parse_args(argv)
    scenario = painleve.Scenario.load(args.scenario) if args.scenario else painleve.Scenario.default()
    c = compare(scenario, args.observer)
    fw, py = c["firmware"], c["python"]
    print(f"scenario {scenario.name}: {fw.trace.nrows} periods, observer {args.observer}")
    print(f"final z_t: firmware {fw.trace['z_t'][-1]:+.6f} m, Python law {py.trace['z_t'][-1]:+.6f} m "
          f"(target {scenario['controller.target_z_t']:+.3f} m)")
    print(f"lift-offs: firmware {fw.summary['lift_offs']}, Python law {py.summary['lift_offs']}")
    if c["law"].safe_at is not None:
        print(f"the Python law found the arm straight (J singular) at t = {c['law'].safe_at} s and held zero torque from then on")
    print(f"max |dz_t| = {c['max_dz'] * 1e3:.4f} mm (at t = {c['t_max_dz']:.3f} s), final |dz_t| = {c['final_dz'] * 1e3:.4f} mm")
    if max(c["max_dz"], c["final_dz"]) * 1e3 > args.tolerance_mm:
        print(f"hybrid_in_python: the Python law is more than {args.tolerance_mm} mm from the firmware's run", file=sys.stderr)
        return 1
    print(f"within {args.tolerance_mm} mm of the firmware's run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
