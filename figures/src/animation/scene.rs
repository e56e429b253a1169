//! Where the arm is drawn: the joints from the angles by the `shared` crate's
//! forward kinematics (the plant's), and the one mapping from the plane of the
//! arm (z_t to the right, z_n up, the base joint at the origin, m) to the
//! frame's pixels (x to the right, y down), equal scales on both axes, fitted
//! around everything the animation shows.

use shared::kinematics::joint_positions;

use super::trace::ArmTrace;

/// The arm and belt as the scenario has them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arm {
    /// Length of each link `l`, m.
    pub l: f64,
    /// Height of the base joint above the belt `H`, m.
    pub h: f64,
    /// Belt speed along z_t, m/s.
    pub v_belt: f64,
}

/// The elbow and the tip `[z_t, z_n]` (m) of angles `theta1`, `theta2` (rad from
/// the downward vertical), links of length `l` (m), by
/// [`shared::kinematics::joint_positions`] (the plant's kinematics).
pub fn joints(l: f64, theta1: f64, theta2: f64) -> [[f64; 2]; 2] {
    let [elbow, tip] = joint_positions(l, &nalgebra::Vector2::new(theta1, theta2));
    [[elbow[0], elbow[1]], [tip[0], tip[1]]]
}

/// A rectangle of the frame, px: left, top, width, height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    /// Left edge, px.
    pub x: f64,
    /// Top edge, px.
    pub y: f64,
    /// Width, px.
    pub w: f64,
    /// Height, px.
    pub h: f64,
}

/// The mapping from the arm's plane (m) to the frame (px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scene {
    /// Pixels per metre, on both axes.
    pub px_per_m: f64,
    /// The pixel of the base joint (z_t = 0, z_n = 0).
    pub origin: (f64, f64),
}

/// The belt's drawn thickness, m.
pub const BELT_THICKNESS_M: f64 = 0.025;

impl Scene {
    /// The largest equal-scale mapping that puts into `area`, with `margin_m`
    /// (m) around them, the base joint, the belt's surface and its thickness
    /// below it, and the elbow and tip at every sample of `trace` from index `from`
    /// to `to` (inclusive; clamped to the trace), centred in `area`.
    pub fn fit(arm: &Arm, trace: &ArmTrace, from: usize, to: usize, area: Rect, margin_m: f64) -> Self {
        let (mut lo_t, mut hi_t, mut lo_n, mut hi_n) = (0.0f64, 0.0f64, -arm.h - BELT_THICKNESS_M, 0.0f64);
        let to = to.min(trace.len().saturating_sub(1));
        for i in from.min(to)..=to {
            for p in joints(arm.l, trace.theta1[i], trace.theta2[i]) {
                (lo_t, hi_t, lo_n, hi_n) = (lo_t.min(p[0]), hi_t.max(p[0]), lo_n.min(p[1]), hi_n.max(p[1]));
            }
        }
        let (lo_t, hi_t, lo_n, hi_n) = (lo_t - margin_m, hi_t + margin_m, lo_n - 0.2 * margin_m, hi_n + margin_m);
        let px_per_m = (area.w / (hi_t - lo_t)).min(area.h / (hi_n - lo_n));
        let (cx, cn) = ((lo_t + hi_t) / 2.0, (lo_n + hi_n) / 2.0);
        let origin = (area.x + area.w / 2.0 - cx * px_per_m, area.y + area.h / 2.0 + cn * px_per_m);
        Self { px_per_m, origin }
    }

    /// The pixel of the point `(z_t, z_n)` (m): `x = origin.x + z_t s`,
    /// `y = origin.y - z_n s` with `s` = [`Scene::px_per_m`].
    pub fn px(&self, z_t: f64, z_n: f64) -> (f64, f64) {
        (self.origin.0 + z_t * self.px_per_m, self.origin.1 - z_n * self.px_per_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_joints_are_the_plants_and_the_scene_keeps_them_inside() {
        let l = 0.21;
        let [elbow, tip] = joints(l, 0.3, -0.5);
        assert!((elbow[0] - l * 0.3f64.sin()).abs() < 1e-15 && (elbow[1] + l * 0.3f64.cos()).abs() < 1e-15);
        let q = nalgebra::Vector2::new(0.3, -0.5);
        let z = shared::kinematics::tip_position(l, &q);
        assert!((tip[0] - z[0]).abs() < 1e-15 && (tip[1] - z[1]).abs() < 1e-15);
        let arm = Arm { l, h: 0.3775, v_belt: -0.4 };
        let trace = ArmTrace { t: vec![0.0], theta1: vec![0.3], theta2: vec![-0.5], ..Default::default() };
        let area = Rect { x: 10.0, y: 20.0, w: 400.0, h: 300.0 };
        let s = Scene::fit(&arm, &trace, 0, 0, area, 0.02);
        for p in [(0.0, 0.0), (tip[0], tip[1]), (elbow[0], elbow[1]), (0.0, -arm.h - BELT_THICKNESS_M)] {
            let (x, y) = s.px(p.0, p.1);
            assert!(x >= area.x && x <= area.x + area.w && y >= area.y && y <= area.y + area.h, "{p:?} at {x}, {y}");
        }
        // Up in the plane is up on the screen.
        assert!(s.px(0.0, 0.1).1 < s.px(0.0, 0.0).1);
    }
}
