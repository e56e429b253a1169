"""MuJoCo's effective restitution: the arm's tip dropped on the belt (examples/compare/README.md).

MuJoCo has no restitution coefficient. A contact is a soft constraint whose reference
acceleration is a spring and a damper (solref: time constant and damping ratio) scaled by an
impedance that grows with the penetration (solimp). The normal velocity the tip leaves with is
whatever that spring and damper, the arm's own forces and the time step make of it. This
measures it: the arm at rest at a posture whose tip is `DROP_HEIGHT` above the belt, its joints
given the rates that move the tip straight down at `speed` (q_dot = J^-1 [0, -speed],
docs/model.md eq. 2), frictionless (condim 1: no slip enters), stepped until the tip leaves the
belt. The effective restitution is the tip's normal velocity out over the one it came in with
(each the velocity of the Euler step that crossed the belt's surface: z_n + H = 0). The contact
begins somewhere within a step; `PHASES` drops, from heights a fraction of a step's travel apart,
sample where.
"""

from __future__ import annotations

import mujoco
import numpy as np

import mujoco_arm

GIVE_UP_S = 0.5  # the tip has not left the belt by then: it stays (restitution 0)
DROP_HEIGHT = 1e-3  # m above the belt at the start
PHASES = 8  # drops per speed, their heights spread over one step's travel


def drop(model: mujoco.MjModel, params: dict, arm, z_t: float, speed: float, height: float = DROP_HEIGHT) -> dict:
    """One drop: `model` the arm in MuJoCo (mujoco_arm.build, condim 1) at `params` (Table I,
    painleve.Model().params; g and k 0 for the contact law alone), `arm` a painleve.Model
    (inverse kinematics, Jacobian, tip), `z_t` (m) where along the belt (elbow down), `speed`
    (m/s > 0) the tip's downward speed at the start, `height` (m) the tip's above the belt.
    Returns `e` (the normal velocity out over the one in; 0 when the tip has not left within
    GIVE_UP_S), `sink` (the deepest penetration, m), `contact_s` (how long the tip was in the
    belt, s) and `left`."""
    data = mujoco.MjData(model)
    h, belt = model.opt.timestep, params["h"]
    theta = arm.inverse_kinematics([z_t, -belt + height], branch="down")
    rates = np.linalg.solve(arm.jacobian(theta), [0.0, -speed])
    data.qpos[:] = [theta[0], theta[1] - theta[0], 0.0]
    data.qvel[:] = [rates[0], rates[1] - rates[0], 0.0]
    deepest, entered, v_in = 0.0, None, None
    for _ in range(int(round((GIVE_UP_S + height / speed) / h))):
        mujoco.mj_step(model, data)
        q = np.array([data.qpos[0], data.qpos[0] + data.qpos[1]])
        gap = arm.tip(q)[1] + belt
        deepest = min(deepest, gap)
        if (gap <= 0.0) == (entered is None):  # the step that crossed the surface, in or out
            q_dot = np.array([data.qvel[0], data.qvel[0] + data.qvel[1]])
            v_n = float((arm.jacobian(q) @ q_dot)[1])
            if entered is None:
                entered, v_in = data.time, v_n
            else:
                return {"e": -v_n / v_in, "sink": -deepest, "contact_s": data.time - entered, "left": True}
    return {"e": 0.0, "sink": -deepest, "contact_s": GIVE_UP_S, "left": False}


def drops(params: dict, arm, z_t: float, contact: mujoco_arm.Contact, h: float, speed: float,
          phases: int = PHASES) -> dict:
    """`phases` drops (see `drop`) from heights DROP_HEIGHT + j speed h / phases, j = 0 ..
    phases - 1, so that the contact begins at as many points within a step. Returns the mean,
    smallest and largest `e`, the deepest `sink` (m), the mean `contact_s` (s) and how many drops
    left the belt (`left`)."""
    model = mujoco_arm.build(params, 0.0, h, contact, condim=1)
    runs = [drop(model, params, arm, z_t, speed, DROP_HEIGHT + j * speed * h / phases) for j in range(phases)]
    es = [r["e"] for r in runs]
    return {"e": float(np.mean(es)), "e_min": min(es), "e_max": max(es), "sink": max(r["sink"] for r in runs),
            "contact_s": float(np.mean([r["contact_s"] for r in runs])), "left": sum(r["left"] for r in runs),
            "phases": phases}
