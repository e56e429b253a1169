//! The arm's frames in 3D: where Foxglove's world is, and the transforms of
//! the base, the two links and the tip at a configuration (docs/model.md
//! "Geometry and state").
//!
//! The world frame `world` has its origin at the base joint, `x` along the
//! belt (`z_t`), `z` up (`z_n`) and `y` across the belt (right-handed, as
//! Foxglove's 3D panel has it). The plane of the arm is `y = 0`; the belt's
//! surface is the plane `z = -h`. A link frame's `-z` axis runs along its link,
//! from its joint to the next: link `i` is turned by `-theta_i` about `y` from
//! hanging straight down (`theta_i` is measured from the downward vertical,
//! positive towards `+x`).

use foxglove::messages::{FrameTransform, FrameTransforms, Quaternion, Timestamp, Vector3};

/// The frame names of [`frame_transforms`], root first.
pub const FRAMES: [&str; 5] = ["world", "base", "link1", "link2", "tip"];

/// The arm's dimensions and the belt's speed, what the view draws with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmGeometry {
    /// Length of each link `l`, m.
    pub l: f64,
    /// Height of the base joint above the belt `H`, m.
    pub h: f64,
    /// Belt speed along `z_t`, m/s.
    pub v_belt: f64,
}

impl ArmGeometry {
    /// The geometry of the plant's parameters `p` (`l`, `h`, `v_belt`).
    pub fn of(p: &shared::params::Params<f64>) -> Self {
        Self { l: p.l, h: p.h, v_belt: p.v_belt }
    }

    /// The tip `[z_t, z_n]` (m, world `x` and `z`) at angles `theta1`, `theta2`
    /// (rad): `shared::kinematics::joint_positions`, the plant's own, as every view draws it.
    pub fn tip(&self, theta1: f64, theta2: f64) -> [f64; 2] {
        let [_, z] = shared::kinematics::joint_positions(self.l, &nalgebra::Vector2::new(theta1, theta2));
        [z[0], z[1]]
    }
}

/// A time `t` (s, `t >= 0`) as a Foxglove timestamp (seconds and nanoseconds);
/// a negative or NaN time is 0, one past `u32::MAX` s saturates.
pub fn timestamp(t: f64) -> Timestamp {
    let ns = tables::mcap::log_time_ns(t);
    let sec = u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX);
    Timestamp::new(sec, (ns % 1_000_000_000) as u32)
}

/// The rotation by `angle` (rad) about the world's `y` axis, as a quaternion.
pub fn about_y(angle: f64) -> Quaternion {
    Quaternion { x: 0.0, y: (angle / 2.0).sin(), z: 0.0, w: (angle / 2.0).cos() }
}

/// The transforms of the arm at `theta1`, `theta2` (rad), time `t` (s):
/// `world -> base` (the identity), `base -> link1` (turned by `-theta1` about
/// `y`), `link1 -> link2` (at the elbow, `l` down link 1, turned by
/// `-(theta2 - theta1)`), `link2 -> tip` (`l` down link 2). Composed, the tip's
/// origin is at `(z_t, 0, z_n)` of [`ArmGeometry::tip`].
pub fn frame_transforms(g: &ArmGeometry, t: f64, theta1: f64, theta2: f64) -> FrameTransforms {
    let v = |x, z| Some(Vector3 { x, y: 0.0, z });
    let link = |parent: &str, child: &str, translation, rotation| FrameTransform {
        timestamp: Some(timestamp(t)),
        parent_frame_id: parent.into(),
        child_frame_id: child.into(),
        translation,
        rotation: Some(rotation),
    };
    FrameTransforms {
        transforms: vec![
            link(FRAMES[0], FRAMES[1], v(0.0, 0.0), about_y(0.0)),
            link(FRAMES[1], FRAMES[2], v(0.0, 0.0), about_y(-theta1)),
            link(FRAMES[2], FRAMES[3], v(0.0, -g.l), about_y(-(theta2 - theta1))),
            link(FRAMES[3], FRAMES[4], v(0.0, -g.l), about_y(0.0)),
        ],
    }
}

/// `v` (3-vector) turned by the unit quaternion `q` (`v + 2 w (u x v) + 2 u x (u x v)`,
/// `u = (x, y, z)`).
pub fn rotate(q: &Quaternion, v: [f64; 3]) -> [f64; 3] {
    let u = [q.x, q.y, q.z];
    let cross = |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let c = cross(u, v);
    let cc = cross(u, c);
    [0, 1, 2].map(|i| v[i] + 2.0 * q.w * c[i] + 2.0 * cc[i])
}

/// The Hamilton product `a b` (the turn `b`, then `a`).
pub fn multiply(a: &Quaternion, b: &Quaternion) -> Quaternion {
    Quaternion {
        w: a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
        x: a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
        y: a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
        z: a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
    }
}

/// The origin of `frame` in `world` (m), composing the transforms of `tf` from
/// the root down, as Foxglove does: what a reader of `/tf` finds the tip at.
/// `None` when the chain from `frame` does not reach `world` (a frame without
/// a parent, a loop, a transform without translation or rotation).
pub fn origin_in_world(tf: &FrameTransforms, frame: &str) -> Option<[f64; 3]> {
    let mut chain = Vec::new();
    let mut child = frame;
    while child != FRAMES[0] {
        let t = tf.transforms.iter().find(|t| t.child_frame_id == child)?;
        if chain.len() > tf.transforms.len() {
            return None;
        }
        chain.push(t);
        child = &t.parent_frame_id;
    }
    let mut p = [0.0; 3];
    let mut r = Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 };
    for t in chain.iter().rev() {
        let v = t.translation?;
        let d = rotate(&r, [v.x, v.y, v.z]);
        p = [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
        r = multiply(&r, &t.rotation?);
    }
    Some(p)
}
