"""The MuJoCo arm against docs/model.md at random states (examples/compare/README.md).

MuJoCo's coordinates are r = [theta1, theta2 - theta1] (the hinges), docs/model.md's are
q = [theta1, theta2]: q = T r with T = [[1, 0], [1, 1]]. So MuJoCo's mass matrix of the arm must be
T^T M T, and its generalised forces without contact, qfrc_passive - qfrc_bias (the spring, the
damping, minus gravity and the centripetal terms), must be T^T (-(w + c)) (docs/model.md eq. 1:
M q_ddot = -w - c + J^T f + u). The tip, link 2's end, is the tip sphere's centre: (x, z) =
(z_t, z_n). `painleve.Model` gives M, w + c (`bias`) and the tip from the project's own code
(shared::model::Arm), which is tested against the formulas of docs/model.md.
"""

from __future__ import annotations

import mujoco
import numpy as np

T = np.array([[1.0, 0.0], [1.0, 1.0]])  # q = T r


def check(model: mujoco.MjModel, arm, samples: int = 200, seed: int = 69) -> dict:
    """Compares `model` (mujoco_arm.build) with `arm` (a painleve.Model at the same parameters)
    at `samples` random states: angles uniform in [-pi, pi] rad, rates in [-10, 10] rad/s. (Passive
    and bias forces do not depend on contacts.) Returns, per quantity, the largest difference relative to
    the largest magnitude of that quantity over the samples (dimensionless): `mass_matrix`,
    `forces` (passive minus bias) and `tip`, and `samples`."""
    rng = np.random.default_rng(seed)
    data = mujoco.MjData(model)
    full = np.zeros((model.nv, model.nv))
    worst = {"mass_matrix": [0.0, 0.0], "forces": [0.0, 0.0], "tip": [0.0, 0.0]}  # [largest diff, largest value]
    tip_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "tip")
    for _ in range(samples):
        q = rng.uniform(-np.pi, np.pi, 2)
        qd = rng.uniform(-10.0, 10.0, 2)
        data.qpos[:] = [q[0], q[1] - q[0], 0.0]
        data.qvel[:] = [qd[0], qd[1] - qd[0], 0.0]
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, full)
        state = np.array([q[0], qd[0], q[1], qd[1]])
        pairs = {
            "mass_matrix": (full[:2, :2], T.T @ arm.mass_matrix(q) @ T),
            "forces": ((data.qfrc_passive - data.qfrc_bias)[:2], T.T @ -arm.bias(state)),
            "tip": (data.geom_xpos[tip_geom][[0, 2]], arm.tip(q)),
        }
        for name, (mine, theirs) in pairs.items():
            worst[name][0] = max(worst[name][0], float(np.abs(mine - theirs).max()))
            worst[name][1] = max(worst[name][1], float(np.abs(theirs).max()))
    out = {name: diff / scale for name, (diff, scale) in worst.items()}
    out["samples"] = samples
    return out
