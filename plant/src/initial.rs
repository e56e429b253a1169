//! The paper's initial conditions (MODEL.md) and their projection onto the belt.
//!
//! The paper gives `x0a`, `x0d`, `x0u` in degrees rounded to 0.01 or 0.1; at
//! those values the tip sits a fraction of a millimetre inside the belt. The plant
//! projects a tip up to [`crate::PROJECTION_TOLERANCE`] inside the belt onto
//! it at the same `z_t` and elbow branch; [`describe_projection`] says by how much.

use nalgebra::Vector2;
use serde::Serialize;
use shared::{ElbowBranch, Params, kinematics::tip_position};

/// A named initial condition `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and deg/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperInitialCondition {
    /// `x0a`, `x0d` or `x0u`.
    pub name: &'static str,
    /// `[theta1, theta1_dot, theta2, theta2_dot]`, degrees and degrees per second.
    pub deg: [f64; 4],
}

/// `x0a = [32 deg, 0, 18.27 deg, 0]` (MODEL.md experiments 3 and 4).
pub const X0A: PaperInitialCondition = PaperInitialCondition { name: "x0a", deg: [32.0, 0.0, 18.27, 0.0] };
/// `x0d = [-11.4 deg, 0, -35.1 deg, 0]`, elbow down (MODEL.md experiments 3, 5, 6).
pub const X0D: PaperInitialCondition = PaperInitialCondition { name: "x0d", deg: [-11.4, 0.0, -35.1, 0.0] };
/// `x0u = [-35.1 deg, 0, -11.4 deg, 0]`, elbow up (MODEL.md experiments 5 and 6).
pub const X0U: PaperInitialCondition = PaperInitialCondition { name: "x0u", deg: [-35.1, 0.0, -11.4, 0.0] };

/// Converts `[deg, deg/s, deg, deg/s]` to `[rad, rad/s, rad, rad/s]`.
pub fn deg_to_state(deg: [f64; 4]) -> [f64; 4] {
    deg.map(f64::to_radians)
}

/// How the plant will treat an initial state relative to the belt.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProjectionInfo {
    /// Tip position `[z_t, z_n]` as given, m.
    pub tip_given: [f64; 2],
    /// Signed distance of the tip above the belt, m (negative: inside it).
    pub height_above_belt: f64,
    /// Whether the tip is projected onto the belt (same `z_t`, same elbow branch).
    pub projected: bool,
    /// Elbow branch of the configuration.
    pub branch: &'static str,
}

/// Where the tip of state `x` (rad, rad/s) sits relative to the belt, and whether
/// the plant projects it (any tip at or inside the belt, within the tolerance).
pub fn describe_projection(params: &Params<f64>, x: [f64; 4]) -> ProjectionInfo {
    let q = Vector2::new(x[0], x[2]);
    let z = tip_position(params.l, &q);
    let height = z[1] + params.h;
    ProjectionInfo { tip_given: [z[0], z[1]], height_above_belt: height, projected: height <= 1e-12, branch: ElbowBranch::of(&q).name() }
}
