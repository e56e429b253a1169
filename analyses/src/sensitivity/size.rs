//! How large the sensitivity study is: its sizes and the grids and windows of
//! each.

use serde::Serialize;

use crate::sweep::Axis;

/// How large the study is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Size {
    /// Coarse grids and short windows: a few minutes on 2 cores.
    Quick,
    /// The paper's resolution (experiment 3's grid, 250 s + 50 s, `Z_t,sliding` to 1 mm).
    Paper,
}

/// The grids and windows of a study size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Grids {
    /// Open loop: friction coefficients.
    pub mu: Axis,
    /// Open loop: belt speeds, m/s.
    pub v_belt: Axis,
    /// Open loop: transient and record window, s.
    pub open_windows_s: (f64, f64),
    /// Closed loop (hybrid, from `x0d`, `mu = 0.6`): belt speeds, m/s.
    pub closed_v_belt: Axis,
    /// Closed loop: transient and record window, s.
    pub closed_windows_s: (f64, f64),
    /// `Z_t,sliding`: bisection tolerance, m.
    pub zmax_tol_m: f64,
    /// `Z_t,sliding`: run length of a trial, s.
    pub zmax_duration_s: f64,
}

impl Size {
    /// The grids of this size.
    pub fn grids(self) -> Grids {
        match self {
            Self::Quick => Grids {
                mu: Axis { start: 0.1, stop: 1.0, step: 0.1 },
                v_belt: Axis { start: -1.0, stop: -0.1, step: 0.05 },
                open_windows_s: (100.0, 30.0),
                closed_v_belt: Axis { start: -1.0, stop: -0.1, step: 0.1 },
                closed_windows_s: (15.0, 10.0),
                zmax_tol_m: 4e-3,
                zmax_duration_s: 10.0,
            },
            Self::Paper => Grids {
                mu: Axis { start: 0.1, stop: 1.0, step: 0.1 },
                v_belt: Axis { start: -1.0, stop: -0.1, step: 0.005 },
                open_windows_s: (250.0, 50.0),
                closed_v_belt: Axis { start: -1.0, stop: -0.1, step: 0.02 },
                closed_windows_s: (250.0, 50.0),
                zmax_tol_m: 1e-3,
                zmax_duration_s: 10.0,
            },
        }
    }
}
