"""The paper's arm on the moving belt, built in MuJoCo (docs/model.md; examples/compare/README.md).

The model, in MuJoCo's frame (x along the belt = z_t, z up = z_n, y out of the plane):

- two hinges about -y, so that a positive angle swings a hanging link towards +x, as theta1 and
  theta2 do (docs/model.md "Geometry and state"): joint `shoulder` is theta1, joint `elbow` the
  elbow's relative angle theta2 - theta1 (the arm's spring acts on it: stiffness k, spring
  reference -alpha0, so that its torque is -k (theta2 - theta1 + alpha0)); both damped by sigma,
  which is MODEL.md's damping (the dissipation sigma/2 (theta1_dot^2 + (theta2_dot - theta1_dot)^2)
  gives w's damping terms);
- each link a uniform rod of mass m and length l: an explicit inertial at its middle, m l^2/12
  about y; no geom (nothing of the links collides);
- the tip a sphere of radius TIP_RADIUS at link 2's end, the only geom of the arm;
- the belt a long box on a slide joint along x, heavy (BELT_MASS), held at v_belt by a velocity
  servo (gain BELT_KV); its top face at z = -H - TIP_RADIUS, so that the sphere touches it when
  the tip (its centre) is at z_n = -H: the gap z_n + H is MuJoCo's contact distance;
- the contact: condim 3 (normal and tangential friction in the plane), friction mu on both geoms,
  the contact setting's friction cone (pyramidal or elliptic) and MuJoCo's soft contact with its
  solref and solimp (`Contact`);
- the contact setting's integrator (Euler or implicitfast) at the time step h.

Functions: `build` (an MjModel), `initial_state` (MuJoCo's full physical state from docs/model.md's
x), `joint_of` (the arm's q, q_dot from MuJoCo's qpos, qvel), `roll` (a batch of runs with
mujoco.rollout, digested step by step without keeping the trajectory).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout

TIP_RADIUS = 2e-4  # the tip sphere's radius, m
BELT_HALF_LENGTH = 400.0  # m: the belt moves 150 m in 300 s at 0.5 m/s
BELT_HALF_THICKNESS = 0.01  # m
BELT_MASS = 1000.0  # kg: the arm's impulses barely move it (a 0.2 N s impact: 0.2 mm/s)
BELT_KV = 1e6  # N s/m, the belt's velocity servo: a 1 ms time constant, kv h / m = 0.1 at h 1e-4 (explicit: < 2)
CHUNK_STEPS = 100_000  # steps per rollout call at most: the trajectory of a chunk is kept, then digested
CHUNK_RUN_STEPS = 2_000_000  # runs x steps per call at most (7 doubles a state: 112 MB of trajectory)
DEFAULT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)  # MuJoCo's default impedance


@dataclass(frozen=True)
class Contact:
    """A MuJoCo soft-contact setting: solref (time constant s, damping ratio) and solimp
    (d_min, d_max, width m, midpoint, power), as MJCF's geom attributes take them, the friction
    cone (`pyramidal`, MuJoCo's default, or `elliptic`) and the integrator (`Euler`, MuJoCo's
    default, or `implicitfast`), as MJCF's option takes them."""

    name: str
    solref: tuple
    solimp: tuple
    cone: str = "pyramidal"
    integrator: str = "Euler"

    def describe(self) -> str:
        """The setting as MJCF writes it."""
        return (f"cone {self.cone}, {self.integrator}, solref {' '.join(f'{v:g}' for v in self.solref)}, "
                f"solimp {' '.join(f'{v:g}' for v in self.solimp[:3])}")


def damping_ratio(e: float) -> float:
    """The damping ratio zeta of a linear spring and damper whose rebound has restitution `e`
    (0 < e < 1): a contact that lasts half a damped period leaves with e = exp(-zeta pi /
    sqrt(1 - zeta^2)), so zeta = -ln e / sqrt(pi^2 + ln^2 e) (e 0.2: 0.456)."""
    return -math.log(e) / math.hypot(math.pi, math.log(e))


def default_contact() -> Contact:
    """MuJoCo's default soft contact: solref 0.02 1, solimp 0.9 0.95 0.001 0.5 2."""
    return Contact("default", (0.02, 1.0), DEFAULT_SOLIMP)


def mjcf(params: dict, mu: float, h: float, contact: Contact, condim: int = 3) -> str:
    """The MJCF text of the arm on the belt. `params`: paper Table I (painleve.Model().params:
    m kg, l m, sigma N m s/rad, k N m/rad, h m, alpha0 rad, g m/s^2); `mu` Coulomb's
    coefficient; `h` the time step, s; `contact` the soft contact's setting; `condim` 3 (the
    comparison) or 1 (frictionless: the drop test). The belt's speed is the servo's control
    (`roll`'s `v_belts`, or MjData.ctrl)."""
    m, l, k, sigma = params["m"], params["l"], params["k"], params["sigma"]
    inertia = m * l * l / 12.0  # a uniform rod about its middle, kg m^2
    top = -params["h"] - TIP_RADIUS  # the belt's top face, m
    solref = " ".join(repr(float(v)) for v in contact.solref)
    solimp = " ".join(repr(float(v)) for v in contact.solimp)
    friction = f"{mu!r} 0 0"  # condim 3 reads the first (sliding) coefficient only
    return f"""
<mujoco model="painleve-arm">
  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>
  <option timestep="{h!r}" integrator="{contact.integrator}" cone="{contact.cone}" gravity="0 0 {-params['g']!r}"/>
  <worldbody>
    <body name="link1" pos="0 0 0">
      <joint name="shoulder" type="hinge" axis="0 -1 0" damping="{sigma!r}"/>
      <inertial pos="0 0 {-l / 2!r}" mass="{m!r}" diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>
      <body name="link2" pos="0 0 {-l!r}">
        <joint name="elbow" type="hinge" axis="0 -1 0" damping="{sigma!r}" stiffness="{k!r}"
               springref="{-params['alpha0']!r}"/>
        <inertial pos="0 0 {-l / 2!r}" mass="{m!r}" diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>
        <geom name="tip" type="sphere" pos="0 0 {-l!r}" size="{TIP_RADIUS!r}" condim="{condim}"
              friction="{friction}" solref="{solref}" solimp="{solimp}"/>
      </body>
    </body>
    <body name="belt" pos="0 0 {top - BELT_HALF_THICKNESS!r}">
      <joint name="belt" type="slide" axis="1 0 0"/>
      <inertial pos="0 0 0" mass="{BELT_MASS!r}" diaginertia="1 1 1"/>
      <geom name="belt" type="box" size="{BELT_HALF_LENGTH!r} 0.05 {BELT_HALF_THICKNESS!r}" condim="{condim}"
            friction="{friction}" solref="{solref}" solimp="{solimp}"/>
    </body>
  </worldbody>
  <actuator>
    <velocity name="belt" joint="belt" kv="{BELT_KV!r}"/>
  </actuator>
</mujoco>
"""


def build(params: dict, mu: float, h: float, contact: Contact, condim: int = 3) -> mujoco.MjModel:
    """The compiled model (see `mjcf`)."""
    return mujoco.MjModel.from_xml_string(mjcf(params, mu, h, contact, condim))


STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS  # what rollout carries from one chunk to the next


def initial_state(model: mujoco.MjModel, x, v_belt: float) -> np.ndarray:
    """MuJoCo's full physical state (mjSTATE_FULLPHYSICS) at t = 0 for docs/model.md's state
    `x = [theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s), the belt at 0 m moving at
    `v_belt` m/s."""
    data = mujoco.MjData(model)
    data.qpos[:] = [x[0], x[2] - x[0], 0.0]
    data.qvel[:] = [x[1], x[3] - x[1], v_belt]
    mujoco.mj_forward(model, data)
    out = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, out, STATE)
    return out


def joint_of(qpos: np.ndarray, qvel: np.ndarray):
    """docs/model.md's q = [theta1, theta2] and q_dot from MuJoCo's qpos and qvel (arrays whose
    last axis is MuJoCo's: shoulder, elbow, belt)."""
    q = np.stack([qpos[..., 0], qpos[..., 0] + qpos[..., 1]], axis=-1)
    qd = np.stack([qvel[..., 0], qvel[..., 0] + qvel[..., 1]], axis=-1)
    return q, qd


@dataclass
class Digest:
    """What `roll` keeps of one run, over its window (t0, t1] s.

    lift_offs: how many times in the window the tip left the belt (the contact distance z_n + H
    went from <= 0 to > 0: MuJoCo makes a contact while the distance is below the margin, 0);
    high_flights: how many times it rose through `high` m above the belt (one per flight higher
    than that); max_gap, min_gap: the largest and smallest z_n + H (m) in the window (negative:
    the tip sunk into the soft belt); touchdowns: the first three times (s) of the whole run at
    which the distance went from > 0 to <= 0; final: docs/model.md's x at the end; final_z_t
    and z_t_before: z_t (m) at the end and one second earlier; belt_speed_error: the largest
    |belt velocity - v_belt| (m/s) in the window; steps, wall_s: the run's steps and the wall
    time (s) of the batch it ran in."""

    window: tuple
    lift_offs: int = 0
    high_flights: int = 0
    max_gap: float = -math.inf
    min_gap: float = math.inf
    touchdowns: list = field(default_factory=list)
    final: tuple = ()
    final_z_t: float = math.nan
    z_t_before: float = math.nan
    belt_speed_error: float = 0.0
    steps: int = 0
    wall_s: float = 0.0


def roll(models, states, duration: float, h: float, windows, v_belts, params: dict, high: float,
         nthread: int = 2):
    """Runs each model from its initial state for `duration` s at step `h`, all in one
    mujoco.rollout batch on `nthread` threads, CHUNK_STEPS steps a call (fewer for a large batch:
    CHUNK_RUN_STEPS runs x steps at most), and digests each run over
    its window (t0, t1] s (`windows`, one per run) without keeping the trajectory. `v_belts` (m/s):
    the belt servos' set-points (the control). `params`: Table I (l and H give the gap); `high`
    (m): the height that counts a flight in `Digest.high_flights`. Between chunks the full
    physical state carries over; the constraint solver's warm start does not (rollout takes it
    but does not return it), which moves that step's forces within the solver's tolerance.
    Returns one Digest per run."""
    l, hh = params["l"], params["h"]
    n, nq = len(models), models[0].nq
    total = int(round(duration / h))
    before_end = total - int(round(1.0 / h))  # steps before the one a second before the end
    datas = [mujoco.MjData(models[0]) for _ in range(max(1, nthread))]
    state = np.array(states, dtype=float)
    control = np.array(v_belts, dtype=float).reshape(n, 1, 1)
    digests = [Digest(window=tuple(w)) for w in windows]
    gap0 = hh - l * (np.cos(state[:, 1]) + np.cos(state[:, 1] + state[:, 2]))
    was_on, was_high = gap0 <= 0.0, gap0 > high  # at the previous step, per run
    done = 0
    wall0 = time.perf_counter()
    with rollout.Rollout(nthread=max(1, nthread)) as pool:
        while done < total:
            steps = min(max(1000, min(CHUNK_STEPS, CHUNK_RUN_STEPS // n)), total - done)
            traj, _ = pool.rollout(models, datas, state, control, nstep=steps)
            t = traj[:, :, 0]
            th1, th2 = traj[:, :, 1], traj[:, :, 1] + traj[:, :, 2]
            gap = hh - l * (np.cos(th1) + np.cos(th2))
            on, up = gap <= 0.0, gap > high
            on_before = np.concatenate([was_on[:, None], on[:, :-1]], axis=1)
            up_before = np.concatenate([was_high[:, None], up[:, :-1]], axis=1)
            leaves, lands, rises = on_before & ~on, ~on_before & on, ~up_before & up
            for i, d in enumerate(digests):
                t0, t1 = d.window
                inside = (t[i] > t0) & (t[i] <= t1 + 1e-12)
                d.lift_offs += int((leaves[i] & inside).sum())
                d.high_flights += int((rises[i] & inside).sum())
                if len(d.touchdowns) < 3:
                    d.touchdowns.extend(t[i][lands[i]][: 3 - len(d.touchdowns)].tolist())
                if inside.any():
                    d.max_gap = max(d.max_gap, float(gap[i][inside].max()))
                    d.min_gap = min(d.min_gap, float(gap[i][inside].min()))
                    err = float(np.abs(traj[i, :, 1 + nq + 2][inside] - v_belts[i]).max())
                    d.belt_speed_error = max(d.belt_speed_error, err)
                if done <= before_end - 1 < done + steps:
                    k = before_end - 1 - done
                    d.z_t_before = l * (math.sin(th1[i, k]) + math.sin(th2[i, k]))
            was_on, was_high = on[:, -1], up[:, -1]
            state = traj[:, -1, :].copy()
            done += steps
    wall = time.perf_counter() - wall0
    for i, d in enumerate(digests):
        th1, ph, th1d, phd = state[i, 1], state[i, 2], state[i, 1 + nq], state[i, 2 + nq]
        d.final = (th1, th1d, th1 + ph, th1d + phd)
        d.final_z_t = l * (math.sin(th1) + math.sin(th1 + ph))
        d.steps, d.wall_s = total, wall
    return digests
