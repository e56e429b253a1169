//! The outputs of `sil-host poincare` other than the figures: the rows of `section.csv` and `classes.csv`, `summary.json` and the human summary.

use crate::simulate::summary::InitialCondition;
use analyses::poincare::{
    Band, PointResult,
    classify::{Class, ClassifyConfig},
    lyapunov::LyapunovConfig,
};
use plant::SimConfig;
use serde::Serialize;

/// One row of `section.csv`: an upward crossing of `theta1_dot = 0`.
#[derive(Debug, Clone, Serialize)]
pub struct SectionRow {
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Time of the crossing, s (from the start of the run, transient included).
    pub t: f64,
    /// `theta1`, rad.
    pub theta1: f64,
    /// `theta1`, degrees.
    pub theta1_deg: f64,
    /// `theta1_dot`, rad/s (0 up to the location's tolerance; the velocity after
    /// the jump for a crossing at an impact).
    pub theta1_dot: f64,
    /// `theta2`, rad.
    pub theta2: f64,
    /// `theta2_dot`, rad/s.
    pub theta2_dot: f64,
    /// `smooth` (located on the dense output) or `jump` (at an impact).
    pub kind: &'static str,
    /// Contact mode at the crossing.
    pub mode: &'static str,
}

// `section.csv`: the columns serde writes, declared (CSV reader, Arrow schema).
tables::declare!(SectionRow {
    v_belt: f64,
    t: f64,
    theta1: f64,
    theta1_deg: f64,
    theta1_dot: f64,
    theta2: f64,
    theta2_dot: f64,
    kind: str,
    mode: str,
});

/// One row of `classes.csv`: a belt speed classified ([`PointResult`], borrowed), its
/// Lyapunov estimate, validity counters and ledger inline; an optional count is a
/// float (NaN when empty). Its columns, each with its kind and its cell, are declared
/// once ([`tables::declare_view!`]).
pub struct ClassRow<'a>(pub &'a PointResult);

tables::declare_view!(ClassRow of PointResult {
    v_belt: f64 = |r| r.v_belt,
    class: str = |r| r.class.name(),
    period: f64 = |r| r.period,
    n_crossings: int = |r| r.n_crossings,
    distinct_points: int = |r| r.distinct_points,
    lyapunov_per_crossing: f64 = |r| r.lyapunov.map(|l| l.per_iteration),
    lyapunov_per_s: f64 = |r| r.lyapunov.map(|l| l.per_second),
    lyapunov_std_error: f64 = |r| r.lyapunov.map(|l| l.std_error),
    lyapunov_iterations: f64 = |r| r.lyapunov.map(|l| l.iterations),
    lyapunov_collapsed: f64 = |r| r.lyapunov.map(|l| l.collapsed),
    final_mode: str = |r| r.final_mode,
    final_theta1: f64 = |r| r.final_theta1,
    lift_offs: int = |r| r.lift_offs,
    touchdowns: int = |r| r.touchdowns,
    error: str = |r| r.error.as_deref().unwrap_or_default(),
    wall_s: f64 = |r| r.wall_s,
    energy_gains: int = |r| r.validity.energy_gains,
    newton_fallbacks: int = |r| r.validity.newton_fallbacks,
    poisson_fallbacks: int = |r| r.validity.poisson_fallbacks,
    cone_violations: int = |r| r.validity.cone_violations,
    zeno_stops: int = |r| r.validity.zeno_stops,
    integrator_failures: int = |r| r.validity.integrator_failures,
    ledger_violations: int = |r| r.validity.ledger_violations,
    belt_j: f64 = |r| r.ledger.belt_j,
    slip_j: f64 = |r| r.ledger.slip_j,
    ledger_residual_j: f64 = |r| r.ledger.residual_j,
});

/// Count of grid points per class.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ClassCounts {
    /// No crossings.
    pub equilibrium: usize,
    /// Too few crossings.
    pub settling: usize,
    /// Periodic, any period.
    pub periodic: usize,
    /// Chaotic.
    pub chaotic: usize,
    /// Aperiodic without a positive exponent.
    pub aperiodic: usize,
    /// Failed simulations.
    pub failed: usize,
    /// Simulations whose trajectory violates the model.
    pub invalid: usize,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// `ok`, or `failed` when some belt speed failed.
    pub status: &'static str,
    /// Friction coefficient.
    pub mu: f64,
    /// The parameters used: paper Table I with `--set`, and `mu` (SI, radians);
    /// `v_belt` here is the grid's upper end, each point runs at its own.
    pub params: shared::Params<f64>,
    /// The initial condition and its projection onto the belt.
    pub initial_condition: InitialCondition,
    /// Belt-speed grid: `[min, max]`, m/s.
    pub v_belt_range: [f64; 2],
    /// Grid step, m/s.
    pub v_step: f64,
    /// Grid points.
    pub grid_points: usize,
    /// Transient, s.
    pub transient_s: f64,
    /// Record window, s.
    pub record_s: f64,
    /// Simulator settings.
    pub sim: SimConfig,
    /// Classification settings.
    pub classify: ClassifyConfig,
    /// Lyapunov settings.
    pub lyapunov: LyapunovConfig,
    /// Hysteresis of the section, rad/s.
    pub section_depth: f64,
    /// Longest wait of the section map for a return, s.
    pub max_return_s: f64,
    /// Grid points per class.
    pub counts: ClassCounts,
    /// Validity counters summed over the belt speeds (`classes.csv` has them per speed).
    pub validity: plant::Validity,
    /// Runs of neighbouring belt speeds with equal class and period.
    pub bands: Vec<Band>,
    /// Section points written.
    pub section_points: usize,
    /// Worker threads.
    pub threads: usize,
    /// Wall time of the sweep (without writing files), s.
    pub wall_s: f64,
    /// Median wall time of one belt speed (one thread), s.
    pub median_point_wall_s: f64,
    /// Files written.
    pub files: Vec<String>,
}

/// A band of equal class in words: its class and `v_belt` range.
pub fn band_name(b: &Band) -> String {
    match (b.class, b.period) {
        (Class::Periodic, Some(p)) => format!("period-{p}"),
        (c, _) => c.name().to_string(),
    }
}
