//! A figure of `sil-host bench`: a measured value against its target, which way
//! the target points and whether it is met, the runs behind it; and the median
//! that wall-clock figures report.

use serde::Serialize;

/// Which way a figure's target points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Goal {
    /// The value must be at most the target (times, sizes, counts).
    AtMost,
    /// The value must be at least the target (rates).
    AtLeast,
}

/// Whether a figure meets its target.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "status", content = "reason")]
pub enum Status {
    /// Measured, and within the target.
    Met,
    /// Measured, and outside the target.
    NotMet,
    /// Not measured here; why, and what to do about it.
    Skipped(String),
}

/// One figure: a measured value (median of the runs for wall-clock figures,
/// exact for counts and sizes) against its target.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    /// Stable identifier for scripts, e.g. `control_step_hybrid`, `in_process`.
    pub id: &'static str,
    /// The group `--only` selects it by (`step`, `flash`, `in-process`, ...).
    pub group: &'static str,
    /// What it is, in words.
    pub name: String,
    /// The value (`None` when skipped).
    pub value: Option<f64>,
    /// Its unit: `instructions`, `bytes`, `periods/s`, `s`, `misses`.
    pub unit: &'static str,
    /// The target, in `unit`.
    pub target: f64,
    /// Which way the target points.
    pub goal: Goal,
    /// Met, not met, or skipped (with the reason).
    #[serde(flatten)]
    pub status: Status,
    /// Every run's value, in `unit` (one entry for exact figures).
    pub runs: Vec<f64>,
    /// Further figures in words (percentiles, the other controller, estimates).
    pub detail: Vec<String>,
    /// A command that measures this figure alone.
    pub command: String,
}

impl Figure {
    /// A measured figure; its status follows from `value`, `target` and `goal`.
    pub fn measured(
        id: &'static str,
        group: &'static str,
        name: impl Into<String>,
        value: f64,
        unit: &'static str,
        target: f64,
        goal: Goal,
    ) -> Self {
        let met = match goal {
            Goal::AtMost => value <= target,
            Goal::AtLeast => value >= target,
        };
        Self {
            id,
            group,
            name: name.into(),
            value: Some(value),
            unit,
            target,
            goal,
            status: if met { Status::Met } else { Status::NotMet },
            runs: vec![value],
            detail: Vec::new(),
            command: format!("sil-host bench --only {group}"),
        }
    }

    /// A figure that could not be measured, and why.
    pub fn skipped(
        id: &'static str,
        group: &'static str,
        name: impl Into<String>,
        unit: &'static str,
        target: f64,
        goal: Goal,
        why: String,
    ) -> Self {
        Self {
            id,
            group,
            name: name.into(),
            value: None,
            unit,
            target,
            goal,
            status: Status::Skipped(why),
            runs: Vec::new(),
            detail: Vec::new(),
            command: format!("sil-host bench --only {group}"),
        }
    }

    /// With every run's value (the figure's value is their median).
    pub fn with_runs(mut self, runs: Vec<f64>) -> Self {
        self.runs = runs;
        self
    }

    /// With one more line of detail.
    pub fn note(mut self, line: impl Into<String>) -> Self {
        self.detail.push(line.into());
        self
    }
}

/// The median of `v` (the upper one of an even count); 0 when empty.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_meets_its_target_only_on_the_right_side() {
        let f = |v, goal| Figure::measured("x", "step", "x", v, "s", 1.0, goal).status;
        assert_eq!(f(1.0, Goal::AtMost), Status::Met);
        assert_eq!(f(1.0 + 1e-12, Goal::AtMost), Status::NotMet);
        assert_eq!(f(1.0, Goal::AtLeast), Status::Met);
        assert_eq!(f(1.0 - 1e-12, Goal::AtLeast), Status::NotMet);
        assert_eq!(f(f64::NAN, Goal::AtLeast), Status::NotMet, "NaN never meets a target");
        assert_eq!(f(f64::NAN, Goal::AtMost), Status::NotMet);
    }

    #[test]
    fn the_median_is_the_middle_run() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 3.0);
        assert_eq!(median(&[]), 0.0);
    }
}
