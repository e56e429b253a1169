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

/// One row of `classes.csv`: a belt speed classified, with its validity counters.
#[derive(Debug, Clone, Serialize)]
pub struct ClassRow {
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// `equilibrium`, `settling`, `periodic`, `chaotic`, `aperiodic`, `failed` or `invalid`.
    pub class: &'static str,
    /// Period in crossings, when periodic.
    pub period: Option<usize>,
    /// Section crossings in the record window.
    pub n_crossings: usize,
    /// Distinct section points (greedy clustering at the tolerance).
    pub distinct_points: usize,
    /// Largest Lyapunov exponent of the section map, per crossing.
    pub lyapunov_per_crossing: Option<f64>,
    /// The same per second, 1/s.
    pub lyapunov_per_s: Option<f64>,
    /// Its standard error, per crossing.
    pub lyapunov_std_error: Option<f64>,
    /// Crossings averaged in the estimate.
    pub lyapunov_iterations: Option<usize>,
    /// Renormalisations whose separation collapsed (floored).
    pub lyapunov_collapsed: Option<usize>,
    /// Contact mode at the end of the record.
    pub final_mode: &'static str,
    /// `theta1` at the end of the record, rad.
    pub final_theta1: f64,
    /// Lift-offs in the record window: every departure of the tip from the belt,
    /// bounces included ([`analyses::lift_offs::of`]).
    pub lift_offs: u64,
    /// Touchdowns in the record window.
    pub touchdowns: u64,
    /// The simulation's error (empty when none).
    pub error: String,
    /// Wall-clock time of this speed, s.
    pub wall_s: f64,
    /// Validity: energy-creating impacts.
    pub energy_gains: u64,
    /// Validity: Newton-law fallbacks.
    pub newton_fallbacks: u64,
    /// Validity: Poisson-law fallbacks.
    pub poisson_fallbacks: u64,
    /// Validity: friction-cone violations.
    pub cone_violations: u64,
    /// Validity: Zeno stops.
    pub zeno_stops: u64,
    /// Validity: integrator failures.
    pub integrator_failures: u64,
    /// Validity: energy-ledger violations (docs/plant.md "The energy ledger").
    pub ledger_violations: u64,
    /// The energy the moving belt put in, J.
    pub belt_j: f64,
    /// The contact's work in the belt's frame (dissipated), J.
    pub slip_j: f64,
    /// What the energy ledger leaves unexplained, J.
    pub ledger_residual_j: f64,
}

// `classes.csv`: the columns serde writes, declared; an optional count is a float (NaN when empty).
tables::declare!(ClassRow {
    v_belt: f64,
    class: str,
    period: f64,
    n_crossings: int,
    distinct_points: int,
    lyapunov_per_crossing: f64,
    lyapunov_per_s: f64,
    lyapunov_std_error: f64,
    lyapunov_iterations: f64,
    lyapunov_collapsed: f64,
    final_mode: str,
    final_theta1: f64,
    lift_offs: int,
    touchdowns: int,
    error: str,
    wall_s: f64,
    energy_gains: int,
    newton_fallbacks: int,
    poisson_fallbacks: int,
    cone_violations: int,
    zeno_stops: int,
    integrator_failures: int,
    ledger_violations: int,
    belt_j: f64,
    slip_j: f64,
    ledger_residual_j: f64,
});

impl From<&PointResult> for ClassRow {
    fn from(r: &PointResult) -> Self {
        Self {
            v_belt: r.v_belt,
            class: r.class.name(),
            period: r.period,
            n_crossings: r.n_crossings,
            distinct_points: r.distinct_points,
            lyapunov_per_crossing: r.lyapunov.map(|l| l.per_iteration),
            lyapunov_per_s: r.lyapunov.map(|l| l.per_second),
            lyapunov_std_error: r.lyapunov.map(|l| l.std_error),
            lyapunov_iterations: r.lyapunov.map(|l| l.iterations),
            lyapunov_collapsed: r.lyapunov.map(|l| l.collapsed),
            final_mode: r.final_mode,
            final_theta1: r.final_theta1,
            lift_offs: r.lift_offs,
            touchdowns: r.touchdowns,
            error: r.error.clone().unwrap_or_default(),
            wall_s: r.wall_s,
            energy_gains: r.validity.energy_gains,
            newton_fallbacks: r.validity.newton_fallbacks,
            poisson_fallbacks: r.validity.poisson_fallbacks,
            cone_violations: r.validity.cone_violations,
            zeno_stops: r.validity.zeno_stops,
            integrator_failures: r.validity.integrator_failures,
            ledger_violations: r.validity.ledger_violations,
            belt_j: r.ledger.belt_j,
            slip_j: r.ledger.slip_j,
            ledger_residual_j: r.ledger.residual_j,
        }
    }
}

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
