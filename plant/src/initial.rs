//! The paper's initial conditions (docs/model.md) and their projection onto the belt.
//!
//! The paper gives `x0a`, `x0d`, `x0u` in degrees rounded to 0.01 or 0.1; at
//! those values the tip sits a fraction of a millimetre inside the belt. The plant
//! projects a tip up to [`crate::PROJECTION_TOLERANCE`] inside the belt onto
//! it at the same `z_t` and elbow branch; [`describe_projection`] says by how much.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use shared::{ElbowBranch, Params, kinematics::tip_position};

/// A named initial condition `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and deg/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperInitialCondition {
    /// `x0a`, `x0d` or `x0u`.
    pub name: &'static str,
    /// `[theta1, theta1_dot, theta2, theta2_dot]`, degrees and degrees per second.
    pub deg: [f64; 4],
}

/// `x0a = [32 deg, 0, 18.27 deg, 0]` (docs/model.md experiments 3 and 4).
pub const X0A: PaperInitialCondition = PaperInitialCondition { name: "x0a", deg: [32.0, 0.0, 18.27, 0.0] };
/// `x0d = [-11.4 deg, 0, -35.1 deg, 0]`, elbow down (docs/model.md experiments 3, 5, 6).
pub const X0D: PaperInitialCondition = PaperInitialCondition { name: "x0d", deg: [-11.4, 0.0, -35.1, 0.0] };
/// `x0u = [-35.1 deg, 0, -11.4 deg, 0]`, elbow up (docs/model.md experiments 5 and 6).
pub const X0U: PaperInitialCondition = PaperInitialCondition { name: "x0u", deg: [-35.1, 0.0, -11.4, 0.0] };

/// One of the paper's initial conditions, by its letter: scenario files
/// (`plant.x0 = "a" | "d" | "u"`), the analyses and the command line (`--x0`)
/// all use this one type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum PaperX0 {
    /// `x0a = [32 deg, 0, 18.27 deg, 0]` (experiments 3 and 4).
    A,
    /// `x0d = [-11.4 deg, 0, -35.1 deg, 0]`, elbow down (experiments 3, 5, 6).
    D,
    /// `x0u = [-35.1 deg, 0, -11.4 deg, 0]`, elbow up (experiments 5 and 6).
    U,
}

impl PaperX0 {
    /// The three, in the paper's order.
    pub const ALL: [PaperX0; 3] = [PaperX0::A, PaperX0::D, PaperX0::U];

    /// The condition named `a`/`x0a`, `d`/`x0d` or `u`/`x0u`; `None` otherwise.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|x| name == x.letter() || name == x.condition().name)
    }

    /// The initial condition in degrees ([`X0A`], [`X0D`] or [`X0U`]).
    pub fn condition(self) -> PaperInitialCondition {
        match self {
            Self::A => X0A,
            Self::D => X0D,
            Self::U => X0U,
        }
    }

    /// The elbow branch of the condition ([`ElbowBranch::of`] its angles):
    /// down for `x0a` and `x0d`, up for `x0u`.
    pub fn branch(self) -> ElbowBranch {
        let x = deg_to_state(self.condition().deg);
        ElbowBranch::of(&Vector2::new(x[0], x[2]))
    }

    /// `a`, `d` or `u` (as in scenario files and on the command line).
    pub fn letter(self) -> &'static str {
        match self {
            Self::A => "a",
            Self::D => "d",
            Self::U => "u",
        }
    }
}

impl std::fmt::Display for PaperX0 {
    /// The letter, as in `x0{letter}`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.letter())
    }
}

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
    /// Elbow branch of the configuration (`up` or `down`).
    pub branch: ElbowBranch,
}

/// Where the tip of state `x` (rad, rad/s) sits relative to the belt, and whether
/// the plant projects it (any tip at or inside the belt, within the tolerance).
pub fn describe_projection(params: &Params<f64>, x: [f64; 4]) -> ProjectionInfo {
    let q = Vector2::new(x[0], x[2]);
    let z = tip_position(params.l, &q);
    let height = z[1] + params.h;
    ProjectionInfo { tip_given: [z[0], z[1]], height_above_belt: height, projected: height <= 1e-12, branch: ElbowBranch::of(&q) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_letters_parse_back() {
        for x in PaperX0::ALL {
            assert_eq!(PaperX0::parse(x.letter()), Some(x));
            assert_eq!(PaperX0::parse(x.condition().name), Some(x));
        }
        assert_eq!(PaperX0::parse("x0b"), None);
        assert_eq!(PaperX0::parse(""), None);
        // x0d is elbow down, x0u elbow up (docs/model.md, "Initial conditions").
        assert_eq!((PaperX0::D.branch(), PaperX0::U.branch()), (ElbowBranch::Down, ElbowBranch::Up));
    }
}
