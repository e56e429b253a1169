//! What a sweep found: per impact law and `e_n`, and per initial condition (and
//! for any of them), the critical friction coefficient (the smallest `mu` with
//! persistent bouncing at some belt speed) and, for each `mu`, the belt-speed
//! bands of persistent bouncing (maximal runs of neighbouring grid speeds).
//!
//! Persistent bouncing at a grid point: the paper's indicator flagged
//! (`max theta1_dot` over the record window above the threshold) *and* the tip
//! left the belt in the record window ([`Outcome::Bouncing`]); in closed loop, a
//! lift-off in the record window ([`Outcome::LiftOff`]). The indicator alone
//! also flags an arm that moves on the belt without leaving it (in closed loop the
//! controller's answers to sensor noise keep `theta1_dot` near 1e-2 rad/s); those
//! points are counted separately (`indicator_points`).
//!
//! With several seeds per grid point (`--seeds N`, [`super::ensemble`]) a point
//! counts as bouncing when more than half of its seeds with a valid result do
//! (and as flagged by the indicator likewise); the fractions and their intervals
//! are the cells' ([`super::cells`]).

use std::{collections::BTreeMap, io::Write};

use plant::{Validity, impact::IwcRule};
use serde::Serialize;

use super::{
    SweepSpec,
    run::{Outcome, RunRow},
};

/// A band of neighbouring grid belt speeds with persistent bouncing, m/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    /// Most negative speed of the band (grid value).
    pub v_min: f64,
    /// Least negative speed (grid value).
    pub v_max: f64,
    /// Grid points in the band.
    pub points: usize,
}

/// The bands at one `mu`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MuBands {
    /// Friction coefficient.
    pub mu: f64,
    /// Grid points with persistent bouncing.
    pub bouncing_points: usize,
    /// Grid points where the paper's indicator alone is flagged (with or without lift-off).
    pub indicator_points: usize,
    /// Grid points with a result.
    pub points: usize,
    /// The bands, by increasing speed.
    pub bands: Vec<Band>,
}

/// One initial condition's (or `any`'s) results for one impact law and `e_n`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IcResults {
    /// Initial condition, or `any` (bouncing from at least one of them).
    pub ic: String,
    /// Smallest `mu` with persistent bouncing (`None`: none on the grid).
    pub critical_mu: Option<f64>,
    /// Bands per `mu`, by increasing `mu`.
    pub per_mu: Vec<MuBands>,
}

/// Results for one impact law and `e_n`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResults {
    /// Impact-without-collision rule.
    pub iwc: IwcRule,
    /// Impact law.
    pub impact_law: String,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Per initial condition, then `any`.
    pub ics: Vec<IcResults>,
}

/// The sweep's results (the deterministic part of `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Results {
    /// Runs with a result.
    pub runs: usize,
    /// Runs of the sweep (or shard) without one.
    pub missing: usize,
    /// Runs per outcome.
    pub outcomes: BTreeMap<String, usize>,
    /// Runs per outcome at each `mu` of the grid (every impact law, `e_n`, IWC rule
    /// and initial condition together), by increasing `mu`.
    pub outcomes_per_mu: Vec<MuOutcomes>,
    /// The indicator's threshold used, rad/s (the paper's: 0).
    pub threshold: f64,
    /// Validity counters summed over the runs.
    pub validity: Validity,
    /// Dynamic jams resolved by a tangential impact, summed over the runs (a corner
    /// of the model, not a violation; docs/plant.md "The jam corner").
    pub jams: u64,
    /// The runs whose trajectory violates the model (outcome `invalid` or an
    /// integrator failure), in index order: left out of the bands and counts below.
    pub invalid: Vec<InvalidRun>,
    /// Per IWC rule, impact law and `e_n`.
    pub cases: Vec<CaseResults>,
}

/// Runs per outcome at one `mu`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MuOutcomes {
    /// Friction coefficient.
    pub mu: f64,
    /// Runs per outcome name ([`Outcome::name`]).
    pub outcomes: BTreeMap<String, usize>,
}

/// A run with a violation, as listed in `summary.json` and the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InvalidRun {
    /// Run index.
    pub index: usize,
    /// Impact-without-collision rule.
    pub iwc: IwcRule,
    /// Impact law.
    pub impact_law: String,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Friction coefficient.
    pub mu: f64,
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Initial condition.
    pub ic: String,
    /// The violations in words.
    pub violations: String,
}

/// Computes the results from `rows` (any order) of sweep `spec`.
pub fn results(spec: &SweepSpec, rows: &[RunRow], missing: usize) -> Results {
    let ics = spec.initial_conditions();
    let (mus, vs) = (spec.mu.values(), spec.v_belt.values());
    let mut outcomes = BTreeMap::new();
    let mut validity = Validity::default();
    let mut sorted: Vec<&RunRow> = rows.iter().collect();
    sorted.sort_by_key(|r| r.index);
    let mut invalid = Vec::new();
    let mut outcomes_per_mu: Vec<MuOutcomes> = mus.iter().map(|&mu| MuOutcomes { mu, outcomes: BTreeMap::new() }).collect();
    let jams = sorted.iter().map(|r| r.jams).sum();
    for r in &sorted {
        *outcomes.entry(r.outcome.name().to_string()).or_insert(0) += 1;
        if let Some(m) = outcomes_per_mu.iter_mut().find(|m| m.mu == r.mu) {
            *m.outcomes.entry(r.outcome.name().to_string()).or_insert(0) += 1;
        }
        let v = r.validity();
        validity.add(&v);
        if !v.is_valid() {
            invalid.push(InvalidRun {
                index: r.index,
                iwc: r.iwc,
                impact_law: r.impact_law.clone(),
                e_n: r.e_n,
                mu: r.mu,
                v_belt: r.v_belt,
                ic: r.ic.clone(),
                violations: v.describe_violations(),
            });
        }
    }
    // counts[case][ic][i_mu][i_v]: (valid runs, persistent bouncing, indicator) over
    // the seeds; a grid point's flags are Some((more than half its seeds bounce,
    // more than half flag the indicator)) when it has a valid result (an invalid
    // run counts as no result). With one seed, its run's flags.
    let n_cases = spec.iwc_rules.len() * spec.impact_laws.len() * spec.e_n.len();
    let mut counts = vec![vec![vec![vec![(0usize, 0usize, 0usize); vs.len()]; mus.len()]; ics.len()]; n_cases];
    for r in rows.iter().filter(|r| r.outcome != Outcome::Invalid) {
        let key = spec.run_at(r.index);
        let case = (r.index % spec.runs_per_seed()) / (ics.len() * vs.len() * mus.len());
        let c = &mut counts[case][key.i_ic][key.i_mu][key.i_v];
        *c = (c.0 + 1, c.1 + usize::from(r.outcome.is_bouncing()), c.2 + usize::from(r.theta1_dot_over_threshold));
    }
    let flags: Vec<Vec<Vec<Vec<Option<Flags>>>>> = counts
        .iter()
        .map(|per_ic| {
            per_ic
                .iter()
                .map(|grid| {
                    grid.iter().map(|row| row.iter().map(|&(n, b, i)| (n > 0).then_some((2 * b > n, 2 * i > n))).collect()).collect()
                })
                .collect()
        })
        .collect();
    let mut cases = Vec::new();
    for (case, per_ic) in flags.iter().enumerate() {
        let first = spec.run_at(case * ics.len() * vs.len() * mus.len());
        let mut list: Vec<IcResults> = per_ic.iter().zip(&ics).map(|(grid, ic)| ic_results(&ic.name, grid, &mus, &vs)).collect();
        if ics.len() > 1 {
            let any: Vec<Vec<Option<Flags>>> = (0..mus.len())
                .map(|m| {
                    (0..vs.len())
                        .map(|v| {
                            let vals: Vec<Flags> = per_ic.iter().filter_map(|g| g[m][v]).collect();
                            (!vals.is_empty()).then(|| (vals.iter().any(|f| f.0), vals.iter().any(|f| f.1)))
                        })
                        .collect()
                })
                .collect();
            list.push(ic_results("any", &any, &mus, &vs));
        }
        cases.push(CaseResults { iwc: first.iwc, impact_law: first.impact_law.name().into(), e_n: first.e_n, ics: list });
    }
    Results { runs: rows.len(), missing, outcomes, outcomes_per_mu, threshold: spec.threshold, validity, jams, invalid, cases }
}

/// Persistent bouncing, and the paper's indicator flagged.
type Flags = (bool, bool);

fn ic_results(name: &str, grid: &[Vec<Option<Flags>>], mus: &[f64], vs: &[f64]) -> IcResults {
    let mut per_mu = Vec::new();
    for (m, row) in grid.iter().enumerate() {
        let mut bands: Vec<Band> = Vec::new();
        let mut open: Option<usize> = None;
        for v in 0..=row.len() {
            let on = v < row.len() && row[v].is_some_and(|f| f.0);
            match (on, open) {
                (true, None) => open = Some(v),
                (false, Some(s)) => {
                    bands.push(Band { v_min: vs[s], v_max: vs[v - 1], points: v - s });
                    open = None;
                }
                _ => {}
            }
        }
        per_mu.push(MuBands {
            mu: mus[m],
            bouncing_points: row.iter().filter(|f| f.is_some_and(|f| f.0)).count(),
            indicator_points: row.iter().filter(|f| f.is_some_and(|f| f.1)).count(),
            points: row.iter().filter(|f| f.is_some()).count(),
            bands,
        });
    }
    let critical_mu = per_mu.iter().find(|m| m.bouncing_points > 0).map(|m| m.mu);
    IcResults { ic: name.into(), critical_mu, per_mu }
}

fn fmt_bands(b: &MuBands) -> String {
    if b.points == 0 {
        return "(no results)".into();
    }
    if b.bands.is_empty() {
        return "-".into();
    }
    b.bands.iter().map(|x| format!("[{:.3}, {:.3}]", x.v_min, x.v_max)).collect::<Vec<_>>().join(" ")
}

/// Prints the human table of `r` to `o`.
pub fn print_table(o: &mut dyn Write, r: &Results) {
    let _ = writeln!(
        o,
        "persistent bouncing: max theta1_dot over the record window > {:e} rad/s (the paper's indicator; its threshold: > 0) with lift-offs in the window",
        r.threshold
    );
    for c in &r.cases {
        let _ = writeln!(o, "\nimpact law {}, e_n = {}, IWC {}", c.impact_law, c.e_n, c.iwc);
        let crit: Vec<String> =
            c.ics.iter().map(|i| format!("{} {}", i.ic, i.critical_mu.map_or("none".into(), |m| format!("{m}")))).collect();
        let _ = writeln!(o, "  critical mu: {}", crit.join(", "));
        let _ =
            writeln!(o, "  {:>5}  {:<5} {:>9} {:>9}  belt-speed bands of persistent bouncing (m/s)", "mu", "ic", "bouncing", "indicator");
        let n_mu = c.ics.first().map_or(0, |i| i.per_mu.len());
        for m in 0..n_mu {
            for (k, i) in c.ics.iter().enumerate() {
                let b = &i.per_mu[m];
                let mu = if k == 0 { format!("{}", b.mu) } else { String::new() };
                let _ = writeln!(o, "  {:>5}  {:<5} {:>9} {:>9}  {}", mu, i.ic, b.bouncing_points, b.indicator_points, fmt_bands(b));
            }
        }
    }
    if r.cases.len() > 1 {
        let _ = writeln!(o, "\nhow the bouncing region moves with the impact law, e_n and the IWC rule (any initial condition):");
        for c in &r.cases {
            if let Some(any) = c.ics.last() {
                let points: usize = any.per_mu.iter().map(|m| m.bouncing_points).sum();
                let widest = any
                    .per_mu
                    .iter()
                    .flat_map(|m| m.bands.iter().map(move |b| (m.mu, *b)))
                    .max_by_key(|(_, b)| b.points)
                    .map_or("-".into(), |(mu, b)| format!("mu {mu}: [{:.3}, {:.3}]", b.v_min, b.v_max));
                let _ = writeln!(
                    o,
                    "  {:<9} e_n {:<5} IWC {:<11} critical mu {:<6} bouncing grid points {:<6} widest band {}",
                    c.impact_law,
                    c.e_n,
                    c.iwc,
                    any.critical_mu.map_or("none".into(), |m| format!("{m}")),
                    points,
                    widest
                );
            }
        }
    }
    let outcomes: Vec<String> = r.outcomes.iter().map(|(k, v)| format!("{k} {v}")).collect();
    let _ = writeln!(
        o,
        "\nruns: {} ({}){}",
        r.runs,
        outcomes.join(", "),
        if r.missing > 0 { format!(", {} missing", r.missing) } else { String::new() }
    );
    let _ = writeln!(o, "validity: {}", r.validity);
    let _ = writeln!(o, "dynamic jams (resolved by a tangential impact): {}", r.jams);
    if !r.invalid.is_empty() {
        let _ = writeln!(o, "INVALID: {} runs violate the model (left out of the bands above):", r.invalid.len());
        for i in r.invalid.iter().take(10) {
            let _ = writeln!(
                o,
                "  run {}: {} e_n {} IWC {}, mu {}, v_belt {}, {}: {}",
                i.index, i.impact_law, i.e_n, i.iwc, i.mu, i.v_belt, i.ic, i.violations
            );
        }
        if r.invalid.len() > 10 {
            let _ = writeln!(o, "  ... and {} more (summary.json lists them all)", r.invalid.len() - 10);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An invalid run is listed, summed into the validity, and left out of the
    /// bands and counts: a grid point whose only run is invalid has no result.
    #[test]
    fn invalid_runs_are_listed_and_left_out_of_the_bands() {
        let spec = SweepSpec {
            mu: crate::sweep::Axis { start: 0.6, stop: 0.6, step: 0.1 },
            v_belt: crate::sweep::Axis { start: -0.6, stop: -0.5, step: 0.1 },
            paper_ics: vec![plant::initial::PaperX0::A],
            ..SweepSpec::paper()
        };
        let row = |index: usize, outcome: Outcome, cone: u64| RunRow {
            index,
            impact_law: "newton".into(),
            e_n: 0.2,
            iwc: IwcRule::Restitution,
            mu: 0.6,
            v_belt: spec.v_belt.value(index),
            ic: "x0a".into(),
            seed: 0,
            outcome,
            theta1_dot_over_threshold: true,
            theta1_dot_max: 1.0,
            t_theta1_dot_max: 0.0,
            lift_offs: 3,
            touchdowns: 3,
            impacts_without_collision: 0,
            z_n_max: 0.0,
            tip_height_max: 0.01,
            final_mode: "flight".into(),
            target_error_m: f64::NAN,
            lift_offs_transient: 0,
            rhs_evaluations: 0,
            energy_gains: 0,
            newton_fallbacks: 1,
            poisson_fallbacks: 0,
            cone_violations: cone,
            zeno_stops: 2,
            jams: 0,
            ledger_violations: 0,
            belt_j: 0.0,
            slip_j: 0.0,
            ledger_residual_j: 0.0,
            largest_event_belt_j: 0.0,
            integrator_failures: 0,
            error: String::new(),
        };
        let rows = [row(0, Outcome::Bouncing, 0), row(1, Outcome::Invalid, 1)];
        // The rows fill their declared columns (the fields serde writes are the declaration's).
        let t = tables::Table::of_rows(&rows).unwrap();
        assert_eq!(t.columns.len(), <RunRow as tables::Declared>::NAMES.len());
        assert!(matches!(&t.columns[8].1, tables::Column::Str(v) if v[1] == "invalid"), "{:?}", t.columns[7]);
        let r = results(&spec, &rows, 0);
        assert_eq!(r.invalid.len(), 1);
        assert_eq!((r.invalid[0].index, r.invalid[0].violations.as_str()), (1, "1 friction-cone violation"));
        assert_eq!((r.validity.cone_violations, r.validity.newton_fallbacks, r.validity.zeno_stops), (1, 2, 4));
        let mu = &r.cases[0].ics[0].per_mu[0];
        assert_eq!((mu.points, mu.bouncing_points, mu.indicator_points), (1, 1, 1), "the invalid run is no result");
        assert_eq!(mu.bands.len(), 1);
        assert_eq!((mu.bands[0].v_min, mu.bands[0].v_max), (-0.6, -0.6));
        assert_eq!(r.outcomes.get("invalid"), Some(&1));
    }

    #[test]
    fn bands_are_maximal_runs_of_flagged_speeds() {
        let vs = [-1.0, -0.9, -0.8, -0.7, -0.6];
        let (on, off) = (Some((true, true)), Some((false, true)));
        let grid = vec![vec![off; 5], vec![on, on, off, None, on]];
        let r = ic_results("x", &grid, &[0.1, 0.2], &vs);
        assert_eq!(r.critical_mu, Some(0.2));
        assert!(r.per_mu[0].bands.is_empty());
        let b = &r.per_mu[1].bands;
        assert_eq!(b.len(), 2);
        assert_eq!((b[0].v_min, b[0].v_max, b[0].points), (-1.0, -0.9, 2));
        assert_eq!((b[1].v_min, b[1].v_max, b[1].points), (-0.6, -0.6, 1));
        assert_eq!((r.per_mu[1].bouncing_points, r.per_mu[1].indicator_points, r.per_mu[1].points), (3, 4, 4));
        assert_eq!(r.per_mu[0].indicator_points, 5);
    }
}
