//! The cases of the search ([`super`] documentation): where the controller runs
//! ([`Setting`]), the eight combinations of controller, initial condition and
//! setting ([`Combination`]), the initial conditions the search takes, and the
//! criteria a trial is judged by ([`Criteria`]).

use serde::Serialize;

use crate::error::AnalysisError;
use firmware::ControllerKind;
use plant::initial::PaperX0;

/// Where the controller runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Setting {
    /// Continuous time, exact measurements, no saturation (the paper's).
    Ideal,
    /// The firmware, sampled with quantised sensors and torques (docs/hardware.md).
    Sampled,
}

impl std::fmt::Display for Setting {
    /// [`Setting::name`].
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Setting {
    /// `ideal` or `sampled`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ideal => "ideal",
            Self::Sampled => "sampled",
        }
    }
}

/// Z_t,sliding starts from `x0d` or `x0u` (experiments 5 and 6).
///
/// # Errors
/// [`AnalysisError::BadInput`] for `x0a`.
pub fn check_x0(x0: PaperX0) -> Result<(), AnalysisError> {
    match x0 {
        PaperX0::D | PaperX0::U => Ok(()),
        PaperX0::A => Err(AnalysisError::BadInput("--x0 a: Z_t,sliding starts from x0d or x0u (experiments 5 and 6)".into())),
    }
}

/// The paper's `K'_I` of the hybrid law from initial condition `x0`, 1/s:
/// 0 from `x0u`, 650 otherwise (docs/model.md, experiment 6); the default of the
/// scenario key `controller.hybrid.ki` ([`rig::scenario::paper_hybrid_ki`]).
pub fn paper_hybrid_ki(x0: PaperX0) -> f64 {
    rig::scenario::paper_hybrid_ki(x0)
}

/// One of the eight cases of `sil-host zmax --all`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct Combination {
    /// The controller.
    pub controller: ControllerKind,
    /// The initial condition.
    pub x0: PaperX0,
    /// Ideal or sampled.
    pub setting: Setting,
}

impl Combination {
    /// All eight: 2 controllers x 2 initial conditions x ideal/sampled.
    pub fn all() -> Vec<Self> {
        let mut v = Vec::new();
        for controller in [ControllerKind::Pid, ControllerKind::Hybrid] {
            for x0 in [PaperX0::D, PaperX0::U] {
                for setting in [Setting::Ideal, Setting::Sampled] {
                    v.push(Self { controller, x0, setting });
                }
            }
        }
        v
    }

    /// A file-name stem, e.g. `pid-x0d-ideal`.
    pub fn stem(&self) -> String {
        format!("{}-x0{}-{}", self.controller.name(), self.x0.letter(), self.setting.name())
    }
}

/// What "slides to the target" and "tracked" mean (module docs) and how long a trial runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Criteria {
    /// Run length, s.
    pub duration_s: f64,
    /// Duration of the move of `z_t*` from the initial tip position to the target, s.
    pub move_time_s: f64,
    /// Largest `|z_t - z_t*|` over the settle window for the tip to count as having
    /// got to the target (`Z_t,sliding`), m.
    pub reach_tol_m: f64,
    /// Largest `|z_t - z_t*|` over the settle window for the target to count as
    /// tracked (the tracking limit), m; at most `reach_tol_m`.
    pub settle_tol_m: f64,
    /// The last part of the run where the tip must be within `settle_tol_m`, s.
    pub settle_window_s: f64,
    /// The lift-off criterion, m: 0 (the default) counts any departure from the belt
    /// (a lift-off event, located exactly); a gap `g > 0` counts the tip as lifted off
    /// only when its height above the belt exceeds `g` at a sample (every control
    /// period; a short hop between samples can be missed), so departures that stay
    /// within `g` are ignored (`sil-host sensitivity`'s lift-off criterion).
    pub lift_off_gap_m: f64,
}

impl Default for Criteria {
    fn default() -> Self {
        Self {
            duration_s: 10.0,
            move_time_s: 2.0,
            reach_tol_m: crate::sweep::run::TARGET_TOL_M,
            settle_tol_m: 1e-3,
            settle_window_s: 1.0,
            lift_off_gap_m: 0.0,
        }
    }
}

impl Criteria {
    /// Checks ranges: finite, `duration_s > move_time_s > 0`, `reach_tol_m >= settle_tol_m > 0`,
    /// `0 < settle_window_s <= duration_s - move_time_s`.
    ///
    /// # Errors
    /// [`AnalysisError::BadInput`] naming the flag.
    pub fn validate(&self) -> Result<(), AnalysisError> {
        let bad = |what: String| Err(AnalysisError::BadInput(what));
        if !(self.move_time_s.is_finite() && self.move_time_s > 0.0) {
            return bad(format!("move time {} s must be finite and > 0", self.move_time_s));
        }
        if !(self.duration_s.is_finite() && self.duration_s > self.move_time_s && self.duration_s <= 1e4) {
            return bad(format!(
                "--duration {} s must be longer than the {} s move (and at most 1e4 s)",
                self.duration_s, self.move_time_s
            ));
        }
        if !(self.lift_off_gap_m.is_finite() && (0.0..=0.1).contains(&self.lift_off_gap_m)) {
            return bad(format!("lift-off gap {} m must be in [0, 0.1]", self.lift_off_gap_m));
        }
        if !(self.settle_tol_m.is_finite() && self.settle_tol_m > 0.0) {
            return bad(format!("--settle-tol {} m must be finite and > 0", self.settle_tol_m));
        }
        if !(self.reach_tol_m.is_finite() && self.reach_tol_m >= self.settle_tol_m) {
            return bad(format!("--reach-tol {} m must be finite and at least --settle-tol ({} m)", self.reach_tol_m, self.settle_tol_m));
        }
        if !(self.settle_window_s.is_finite() && self.settle_window_s > 0.0 && self.settle_window_s <= self.duration_s - self.move_time_s) {
            return bad(format!(
                "--settle-window {} s must be > 0 and at most the run after the move ({} s)",
                self.settle_window_s,
                self.duration_s - self.move_time_s
            ));
        }
        Ok(())
    }
}
