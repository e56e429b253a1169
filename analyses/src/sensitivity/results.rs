//! The sensitivity study's headline results: what each choice gives (open loop,
//! `Z_t,sliding`, the hybrid closed loop), the whole study and its table, and the
//! headline results read from a sweep's runs.

use plant::Validity;
use serde::Serialize;

use super::{
    choices::{Choice, Knobs},
    size::{Grids, Size},
};
use crate::sweep::{
    SweepSpec,
    run::{Outcome, RunRow},
};
use crate::zmax::Combination;

/// The open-loop headline results under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpenLoop {
    /// Critical `mu` from `x0a` (the smallest `mu` of the grid with persistent bouncing).
    pub critical_mu_x0a: Option<f64>,
    /// Critical `mu` from `x0d`.
    pub critical_mu_x0d: Option<f64>,
    /// Extent `[v_min, v_max]` (m/s) of persistent bouncing at `mu = 0.6` from `x0a`.
    pub band_x0a_mu06: Option<[f64; 2]>,
    /// Grid speeds with persistent bouncing at `mu = 0.6` from `x0a`.
    pub band_points: usize,
    /// Whether `x0d` bounces persistently anywhere on the grid.
    pub x0d_bounces: bool,
    /// Runs that violate the model (left out).
    pub invalid_runs: usize,
    /// Validity summed over the runs.
    pub validity: Validity,
}

/// `Z_t,sliding` of one case under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Zmax {
    /// The case.
    pub combination: Combination,
    /// `Z_t,sliding`, m (`None` when the bracket's lower end already fails).
    pub z_t_sliding: Option<f64>,
    /// `found`, `lower_fails` or `upper_reached`.
    pub outcome: &'static str,
    /// Validity summed over the trials.
    pub validity: Validity,
}

/// The hybrid closed loop's headline under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClosedLoop {
    /// Whether it bounces persistently at any belt speed.
    pub bounces: bool,
    /// Belt speeds with persistent bouncing.
    pub bouncing_points: usize,
    /// Belt speeds with a result.
    pub points: usize,
    /// Runs that stopped early (failure or safe state).
    pub stopped_runs: usize,
    /// Validity summed over the runs.
    pub validity: Validity,
}

/// The headline results under one choice (`None`: the choice does not enter that result).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChoiceResult {
    /// The choice.
    pub choice: Choice,
    /// Open loop.
    pub open_loop: Option<OpenLoop>,
    /// `Z_t,sliding` per case (the cases the choice enters).
    pub zmax: Vec<Zmax>,
    /// The hybrid closed loop.
    pub closed_loop: Option<ClosedLoop>,
}

/// The whole study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Study {
    /// Its size.
    pub size: Size,
    /// Its grids.
    pub grids: Grids,
    /// The defaults every choice starts from.
    pub defaults: Knobs,
    /// One result per choice (the defaults appear once per dimension).
    pub results: Vec<ChoiceResult>,
    /// Validity summed over everything simulated.
    pub validity: Validity,
}

/// A flat row of the study's table (`sensitivity.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Dimension label.
    pub choice: &'static str,
    /// The value.
    pub value: String,
    /// Whether it is the default.
    pub is_default: bool,
    /// The headline result's name.
    pub result: String,
    /// Its value (a number, `true`/`false`, or `none`).
    pub outcome: String,
}

impl Study {
    /// The table: one row per choice and headline result computed under it.
    pub fn rows(&self) -> Vec<Row> {
        let mut rows = Vec::new();
        for r in &self.results {
            let c = &r.choice;
            let mut push = |result: String, outcome: String| {
                rows.push(Row { choice: c.dimension.label(), value: c.value.clone(), is_default: c.is_default, result, outcome });
            };
            let num = |x: Option<f64>| x.map_or("none".to_string(), |v| format!("{v}"));
            if let Some(o) = &r.open_loop {
                push("critical_mu_x0a".into(), num(o.critical_mu_x0a));
                push("critical_mu_x0d".into(), num(o.critical_mu_x0d));
                push("band_mu0.6_x0a_from".into(), num(o.band_x0a_mu06.map(|b| b[0])));
                push("band_mu0.6_x0a_to".into(), num(o.band_x0a_mu06.map(|b| b[1])));
                push("x0d_bounces".into(), o.x0d_bounces.to_string());
            }
            for z in &r.zmax {
                let k = z.combination;
                push(format!("zt_sliding_{}_x0{}_{}", k.controller, k.x0, k.setting), num(z.z_t_sliding));
            }
            if let Some(cl) = &r.closed_loop {
                push("hybrid_closed_loop_bounces".into(), cl.bounces.to_string());
            }
        }
        rows
    }
}

/// Persistent bouncing under a lift-off gap: the sweep's outcome (open loop's
/// bouncing, closed loop's lift-off), and the tip above the gap in the record window.
fn bounces(r: &RunRow, gap: f64) -> bool {
    r.outcome.is_bouncing() && (gap == 0.0 || r.tip_height_max > gap)
}

/// The open-loop headline results of the sweep `spec` from its runs `rows`, with
/// lift-off gap `gap` (m).
pub(super) fn open_results(spec: &SweepSpec, rows: &[RunRow], gap: f64) -> OpenLoop {
    let mut validity = Validity::default();
    let valid: Vec<&RunRow> = rows.iter().filter(|r| r.outcome != Outcome::Invalid).collect();
    for r in rows {
        validity.add(&r.validity());
    }
    let critical = |ic: &str| spec.mu.values().into_iter().find(|&mu| valid.iter().any(|r| r.ic == ic && r.mu == mu && bounces(r, gap)));
    let at06: Vec<f64> = valid.iter().filter(|r| r.ic == "x0a" && (r.mu - 0.6).abs() < 1e-9 && bounces(r, gap)).map(|r| r.v_belt).collect();
    let band = (!at06.is_empty()).then(|| [at06.iter().cloned().fold(f64::MAX, f64::min), at06.iter().cloned().fold(f64::MIN, f64::max)]);
    OpenLoop {
        critical_mu_x0a: critical("x0a"),
        critical_mu_x0d: critical("x0d"),
        band_x0a_mu06: band,
        band_points: at06.len(),
        x0d_bounces: valid.iter().any(|r| r.ic == "x0d" && bounces(r, gap)),
        invalid_runs: rows.len() - valid.len(),
        validity,
    }
}

/// The hybrid closed loop's headline from its runs `rows`, with lift-off gap `gap` (m).
pub(super) fn closed_results(rows: &[RunRow], gap: f64) -> ClosedLoop {
    let mut validity = Validity::default();
    for r in rows {
        validity.add(&r.validity());
    }
    let bouncing = rows.iter().filter(|r| bounces(r, gap)).count();
    ClosedLoop {
        bounces: bouncing > 0,
        bouncing_points: bouncing,
        points: rows.iter().filter(|r| r.outcome != Outcome::Invalid).count(),
        stopped_runs: rows.iter().filter(|r| matches!(r.outcome, Outcome::Failed | Outcome::SafeState)).count(),
        validity,
    }
}
