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
use crate::zmax::{Combination, StopReason};

/// The open-loop headline results under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpenLoop {
    /// Critical `mu` from `x0a` (the smallest `mu` of the grid with persistent bouncing).
    pub critical_mu_x0a: Option<f64>,
    /// Critical `mu` from `x0d`.
    pub critical_mu_x0d: Option<f64>,
    /// The main interval `[v_min, v_max]` (m/s) of persistent bouncing at `mu = 0.6`
    /// from `x0a`: the longest run of neighbouring grid speeds that bounce (the
    /// lower one on a tie).
    pub band_x0a_mu06: Option<[f64; 2]>,
    /// The other grid speeds (m/s) that bounce at `mu = 0.6` from `x0a`, listed
    /// apart so that an isolated island does not move an edge of the band.
    pub band_outside: Vec<f64>,
    /// Grid speeds with persistent bouncing at `mu = 0.6` from `x0a` (in the main
    /// interval or outside it).
    pub band_points: usize,
    /// Whether `x0d` bounces persistently anywhere on the grid.
    pub x0d_bounces: bool,
    /// Runs that violate the model (left out).
    pub invalid_runs: usize,
    /// Validity summed over the runs.
    pub validity: Validity,
}

/// `Z_t,sliding` and the tracking limit of one case under one choice
/// ([`crate::zmax`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Zmax {
    /// The case.
    pub combination: Combination,
    /// `Z_t,sliding`, m: the largest target the tip slides to with no lift-off
    /// (`None` when the bracket's lower end already fails).
    pub z_t_sliding: Option<f64>,
    /// `found`, `lower_fails` or `upper_reached`.
    pub outcome: &'static str,
    /// Why the first target above `Z_t,sliding` (or the lower end) failed: a lift-off,
    /// the safe state, a failure, not reached, a model violation (`None` for
    /// `upper_reached`).
    pub stop_above: Option<StopReason>,
    /// When that target was not reached: by how much it was missed, the largest
    /// `|z_t - z_t*|` over the settle window, m (issue 41: a limit a missed target
    /// sets is not a lift-off limit).
    pub missed_by_m: Option<f64>,
    /// The tracking limit, m: the largest target also settled within the settle
    /// tolerance (`None` when the lower end is not tracked).
    pub z_t_tracking: Option<f64>,
    /// The tracking bisection's `found`, `lower_fails` or `upper_reached`.
    pub tracking_outcome: &'static str,
    /// Why the first target above the tracking limit was not tracked.
    pub tracking_stop_above: Option<StopReason>,
    /// Validity summed over the trials.
    pub validity: Validity,
}

/// The hybrid closed loop's headline under one choice: how its runs over the belt
/// speeds ended ([`crate::sweep::run::Outcome`]'s closed-loop classes).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClosedLoop {
    /// Runs per belt speed (the sensor-noise seeds, `--seeds`); the counts below
    /// are of runs, one per speed and seed.
    pub seeds: usize,
    /// The runs that lift off above the lift-off criterion, as a fraction of the
    /// runs with a result, with its Wilson 95 % interval.
    pub lift_off: crate::sweep::Proportion,
    /// The runs that latched the safe state, likewise.
    pub safe_state: crate::sweep::Proportion,
    /// Whether the tip lifts off above the lift-off criterion at any belt speed.
    pub bounces: bool,
    /// Belt speeds where the tip lifts off in the record window, above the
    /// lift-off criterion.
    pub lift_off_points: usize,
    /// The highest the tip rose above the belt in those runs' record windows, m.
    pub highest_lift_off_m: Option<f64>,
    /// Belt speeds where the firmware latched its safe state.
    pub safe_state_points: usize,
    /// Belt speeds where the tip stayed on the belt but ended away from its target.
    pub target_not_reached_points: usize,
    /// Belt speeds whose simulation failed.
    pub failed_points: usize,
    /// Belt speeds with a result (all but the invalid runs).
    pub points: usize,
    /// Validity summed over the runs.
    pub validity: Validity,
}

impl OpenLoop {
    /// The band at `mu = 0.6` from `x0a` for tables: `[from, to]` (m/s, to 3
    /// decimals), then `+ v` for each bouncing speed outside it; `none`.
    pub fn band_text(&self) -> String {
        let Some(b) = self.band_x0a_mu06 else { return "none".into() };
        let mut t = format!("[{}, {}]", round3(b[0]), round3(b[1]));
        for v in &self.band_outside {
            t.push_str(&format!(" + {}", round3(*v)));
        }
        t
    }
}

fn round3(x: f64) -> f64 {
    (x * 1e3).round() / 1e3 + 0.0
}

impl Zmax {
    /// `Z_t,sliding` (or with `tracking` the tracking limit) for tables, in mm: the
    /// value in mm (`>= v` when the bracket's upper end passes), or `< lo` with
    /// the lower end's stop reason (`< lo: lift_off`). A `Z_t,sliding` set by a
    /// missed target rather than a lift-off says so: `-141 (above: missed by 5 mm)`,
    /// `< lo: missed by 9 mm`.
    pub fn cell_text(&self, tracking: bool) -> String {
        let (value, outcome, stop) = if tracking {
            (self.z_t_tracking, self.tracking_outcome, self.tracking_stop_above)
        } else {
            (self.z_t_sliding, self.outcome, self.stop_above)
        };
        let missed = match (tracking, stop, self.missed_by_m) {
            (false, Some(StopReason::NotReached), Some(m)) if m.is_finite() => Some(format!("missed by {:.0} mm", m * 1e3)),
            _ => None,
        };
        match (outcome, value, missed) {
            ("lower_fails", _, Some(m)) | (_, None, Some(m)) => format!("< lo: {m}"),
            ("lower_fails", _, None) | (_, None, None) => format!("< lo: {}", stop.map_or("?", StopReason::name)),
            ("upper_reached", Some(v), _) => format!(">= {:.0}", v * 1e3),
            (_, Some(v), Some(m)) => format!("{:.0} (above: {m})", v * 1e3),
            (_, Some(v), None) => format!("{:.0}", v * 1e3),
        }
    }
}

impl ClosedLoop {
    /// How the runs ended, for tables: `lift-off k (up to h mm)`, `safe state k`,
    /// `not reached k`, `failed k`, each when not 0, then `of n`; `contact, all n`
    /// when every run stayed on the belt at its target.
    pub fn text(&self) -> String {
        if self.seeds > 1 {
            // Over the seeds: the fractions with their intervals.
            let p = |x: &crate::sweep::Proportion| format!("{}/{} [{:.2}, {:.2}]", x.k, x.n, x.lo, x.hi);
            return format!("lift-off {}, safe state {} ({} seeds)", p(&self.lift_off), p(&self.safe_state), self.seeds);
        }
        let mut parts = Vec::new();
        if self.lift_off_points > 0 {
            let h = self.highest_lift_off_m.map_or(String::new(), |h| format!(" (up to {} mm)", (h * 1e5).round() / 1e2));
            parts.push(format!("lift-off {}{h}", self.lift_off_points));
        }
        for (n, what) in
            [(self.safe_state_points, "safe state"), (self.target_not_reached_points, "not reached"), (self.failed_points, "failed")]
        {
            if n > 0 {
                parts.push(format!("{what} {n}"));
            }
        }
        if parts.is_empty() { format!("contact, all {}", self.points) } else { format!("{} of {}", parts.join(", "), self.points) }
    }
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
    /// Runs per belt speed of the closed-loop sweeps (`--seeds`; the open loop
    /// and the `Z_t,sliding` searches run once).
    pub seeds: usize,
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

// `sensitivity.csv`: the columns serde writes, declared (CSV reader, Arrow schema).
tables::declare!(Row { choice: str, value: str, is_default: bool, result: str, outcome: str });

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
                push(
                    "band_mu0.6_x0a_outside".into(),
                    if o.band_outside.is_empty() {
                        "none".into()
                    } else {
                        o.band_outside.iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(" ")
                    },
                );
                push("x0d_bounces".into(), o.x0d_bounces.to_string());
            }
            for z in &r.zmax {
                let k = z.combination;
                push(format!("zt_sliding_{}_x0{}_{}", k.controller, k.x0, k.setting), num(z.z_t_sliding));
                push(format!("zt_tracking_{}_x0{}_{}", k.controller, k.x0, k.setting), num(z.z_t_tracking));
            }
            if let Some(cl) = &r.closed_loop {
                push("hybrid_closed_loop_bounces".into(), cl.bounces.to_string());
                push("hybrid_closed_loop_lift_off_speeds".into(), cl.lift_off_points.to_string());
                push("hybrid_closed_loop_safe_state_speeds".into(), cl.safe_state_points.to_string());
                push("hybrid_closed_loop_not_reached_speeds".into(), cl.target_not_reached_points.to_string());
                if cl.seeds > 1 {
                    push("hybrid_closed_loop_lift_off_fraction".into(), format!("{}", cl.lift_off.fraction));
                    push("hybrid_closed_loop_lift_off_lo".into(), format!("{}", cl.lift_off.lo));
                    push("hybrid_closed_loop_lift_off_hi".into(), format!("{}", cl.lift_off.hi));
                }
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
    let speeds = spec.v_belt.values();
    let bouncing_at = |v: f64| valid.iter().any(|r| r.ic == "x0a" && (r.mu - 0.6).abs() < 1e-9 && r.v_belt == v && bounces(r, gap));
    let flags: Vec<bool> = speeds.iter().map(|&v| bouncing_at(v)).collect();
    let (band, band_outside) = main_interval(&speeds, &flags);
    OpenLoop {
        critical_mu_x0a: critical("x0a"),
        critical_mu_x0d: critical("x0d"),
        band_x0a_mu06: band,
        band_outside,
        band_points: flags.iter().filter(|&&f| f).count(),
        x0d_bounces: valid.iter().any(|r| r.ic == "x0d" && bounces(r, gap)),
        invalid_runs: rows.len() - valid.len(),
        validity,
    }
}

/// The hybrid closed loop's headline from its runs `rows`, with lift-off gap `gap` (m).
pub(super) fn closed_results(rows: &[RunRow], gap: f64, seeds: usize) -> ClosedLoop {
    let mut validity = Validity::default();
    for r in rows {
        validity.add(&r.validity());
    }
    let lifted: Vec<&RunRow> = rows.iter().filter(|r| bounces(r, gap)).collect();
    let count = |o: Outcome| rows.iter().filter(|r| r.outcome == o).count();
    let with_result = rows.iter().filter(|r| r.outcome != Outcome::Invalid).count();
    ClosedLoop {
        seeds,
        lift_off: crate::sweep::Proportion::of(lifted.len(), with_result),
        safe_state: crate::sweep::Proportion::of(count(Outcome::SafeState), with_result),
        bounces: !lifted.is_empty(),
        lift_off_points: lifted.len(),
        highest_lift_off_m: lifted.iter().map(|r| r.tip_height_max).filter(|h| h.is_finite()).reduce(f64::max),
        safe_state_points: count(Outcome::SafeState),
        target_not_reached_points: count(Outcome::TargetNotReached),
        failed_points: count(Outcome::Failed),
        points: rows.iter().filter(|r| r.outcome != Outcome::Invalid).count(),
        validity,
    }
}

/// The longest run of neighbouring `speeds` (in grid order) whose `flags` are set, as
/// `[min, max]` (the first such run on a tie), and the flagged speeds outside it.
pub(super) fn main_interval(speeds: &[f64], flags: &[bool]) -> (Option<[f64; 2]>, Vec<f64>) {
    let mut best: Option<(usize, usize)> = None;
    let mut i = 0;
    while i < flags.len() {
        if !flags[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < flags.len() && flags[i] {
            i += 1;
        }
        if best.is_none_or(|(a, b)| i - start > b - a) {
            best = Some((start, i));
        }
    }
    let Some((a, b)) = best else { return (None, Vec::new()) };
    let (lo, hi) = (speeds[a].min(speeds[b - 1]), speeds[a].max(speeds[b - 1]));
    let outside = (0..flags.len()).filter(|&k| flags[k] && !(a..b).contains(&k)).map(|k| speeds[k]).collect();
    (Some([lo, hi]), outside)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of `sensitivity.csv` fills its declared columns (serde's fields are the declaration's).
    #[test]
    fn a_row_fills_its_declared_columns() {
        let row = Row { choice: "mu", value: "0.6".into(), is_default: true, result: "critical_mu_x0a".into(), outcome: "none".into() };
        let t = tables::Table::of_rows(&[row]).unwrap();
        assert_eq!(t.columns.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), <Row as tables::Declared>::NAMES);
        assert!(matches!(&t.columns[1].1, tables::Column::Str(v) if v[0] == "0.6"), "text stays text");
    }

    /// A limit a missed target sets reads as a missed target (issue 41), not as a
    /// lift-off limit; a lift-off limit reads as before.
    #[test]
    fn a_limit_set_by_a_missed_target_says_by_how_much() {
        let combination = Combination::all()[0];
        let z = |z_t_sliding, outcome, stop, missed_by_m| Zmax {
            combination,
            z_t_sliding,
            outcome,
            stop_above: Some(stop),
            missed_by_m,
            z_t_tracking: None,
            tracking_outcome: "lower_fails",
            tracking_stop_above: Some(stop),
            validity: Validity::default(),
        };
        assert_eq!(z(None, "lower_fails", StopReason::NotReached, Some(8.7e-3)).cell_text(false), "< lo: missed by 9 mm");
        assert_eq!(z(Some(-0.1409), "found", StopReason::NotReached, Some(5.03e-3)).cell_text(false), "-141 (above: missed by 5 mm)");
        assert_eq!(z(Some(0.1642), "found", StopReason::LiftOff, None).cell_text(false), "164");
        assert_eq!(z(None, "lower_fails", StopReason::LiftOff, None).cell_text(false), "< lo: lift_off");
        assert_eq!(z(None, "lower_fails", StopReason::NotReached, Some(8.7e-3)).cell_text(true), "< lo: not_reached");
    }

    #[test]
    fn an_isolated_bouncing_speed_is_listed_apart_and_does_not_move_the_band() {
        let speeds = [-1.0, -0.95, -0.9, -0.85, -0.8, -0.75, -0.7, -0.65];
        let flags = [false, true, false, false, true, true, true, false];
        assert_eq!(main_interval(&speeds, &flags), (Some([-0.8, -0.7]), vec![-0.95]));
        // A tie keeps the first run; nothing flagged gives no band.
        let flags = [true, true, false, true, true, false, false, false];
        assert_eq!(main_interval(&speeds, &flags), (Some([-1.0, -0.95]), vec![-0.85, -0.8]));
        assert_eq!(main_interval(&speeds, &[false; 8]), (None, vec![]));
        // The whole grid.
        assert_eq!(main_interval(&speeds, &[true; 8]), (Some([-1.0, -0.65]), vec![]));
    }
}
