//! The search for runs that do not complete (issue 40; docs/plant.md "The corner
//! search"): open-loop runs on random perturbed arms, each with a fine `mu` scan
//! across its Painlevé threshold and a `v_belt` scan across the edge of its
//! bouncing band, under both IWC rules and several sample periods. Every run must
//! reach its end; the search counts the singular points, bridges and jams it met.
//!
//! Two families of arms. The first (issue 40, [`Family::Perturbed`]): each of Table I's `m`, `l`, `sigma`, `k`, `alpha0` moved uniformly
//! within +-25 %, `H` set so that `x0a` is on the belt (as in issue 24's search),
//! one impact law and `e_n` in [0, 0.6] drawn for it (ChaCha8 from the seed). Its
//! threshold is the smallest `mu` at which `p = Q_22 - mu |Q_21|` reaches 0 on the
//! belt on `x0a`'s branch (the critical `mu` of the paper's Fig. 3, `Q_22 / Q_12`);
//! its band edge is the first belt speed, from -1 m/s up in 0.05 m/s steps, where a
//! run from `x0a` at `max(0.6, threshold + 0.15)` changes from settled to bouncing
//! over the last fifth of the run (or back).
//!
//! The second (issue 53, [`Family::Corner`]) starts on the corner: arms within 3 %
//! of issue 53's (`m 0.15, l 0.23, sigma 0.008, k 1.0, alpha0 0.20`, arm 0 exactly it),
//! from its start within 0.5 deg (`H` putting the tip on the belt), Newton `e_n 0.2`,
//! `mu` across its band 0.410 to 0.432 and `v_belt` within 0.02 m/s of -0.5: a slide of
//! its bouncing orbit runs into `p = b = 0` about every 0.18 s. Its check is the energy
//! ledger: every run completes with no ledger violation.

use nalgebra::Vector2;
use plant::{
    Counters, Hold, Ledger, NoObserver, Plant, SimConfig, SimError,
    impact::{ImpactLaw, IwcRule},
    initial::{X0A, deg_to_state},
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use shared::{Arm, ElbowBranch, Params, kinematics::inverse_kinematics};

/// Which arms a search draws (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Family {
    /// Table I within 25 %, from `x0a`, scans across each arm's Painlevé threshold (issue 40).
    Perturbed,
    /// Issue 53's arm within 3 %, from its start, across its singular-point band.
    Corner,
}

/// The search's size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SearchSpec {
    /// The arms' family.
    pub family: Family,
    /// Random arms.
    pub arms: usize,
    /// Seed of the arms (ChaCha8).
    pub seed: u64,
    /// Points of each `mu` scan, over `threshold - 0.05` to `threshold + 0.25`.
    pub mu_points: usize,
    /// Points of the `v_belt` scan, over `edge +- 0.05` m/s.
    pub v_points: usize,
    /// Length of each run, s.
    pub duration_s: f64,
    /// Sample periods (the `advance` interval, s), each a run of its own.
    pub sample_periods: Vec<f64>,
}

impl SearchSpec {
    /// The full search of issue 40: 40 arms, 21-point scans, 300 s runs, 10 ms and
    /// 100 ms samples, both IWC rules: about 10 000 runs.
    pub fn full() -> Self {
        Self {
            family: Family::Perturbed,
            arms: 40,
            seed: 40,
            mu_points: 21,
            v_points: 21,
            duration_s: 300.0,
            sample_periods: vec![1e-2, 1e-1],
        }
    }

    /// The corner search of issue 53: 25 arms, 21 `mu` by 5 `v_belt`, both IWC rules,
    /// 10 ms and 100 ms samples (10 500 runs of 60 s).
    pub fn corner() -> Self {
        Self { family: Family::Corner, arms: 25, seed: 53, mu_points: 21, v_points: 5, duration_s: 60.0, sample_periods: vec![1e-2, 1e-1] }
    }

    /// The corner search's subset CI runs: 2 arms (issue 53's first), 7 `mu` by 2
    /// `v_belt`, both IWC rules, 10 ms samples, 30 s runs (56 runs).
    pub fn corner_quick() -> Self {
        Self { family: Family::Corner, arms: 2, seed: 53, mu_points: 7, v_points: 2, duration_s: 30.0, sample_periods: vec![1e-2] }
    }

    /// The subset CI runs: 3 arms (issue 24's first), 13-point `mu` scans, 5-point
    /// `v_belt` scans, 130 s runs, 10 ms samples (186 runs).
    pub fn quick() -> Self {
        Self { family: Family::Perturbed, arms: 3, seed: 40, mu_points: 13, v_points: 5, duration_s: 130.0, sample_periods: vec![1e-2] }
    }
}

/// One run of the search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SearchRun {
    /// The arm's index.
    pub arm: usize,
    /// The arm, with this run's `mu` and `v_belt`.
    pub params: Params<f64>,
    /// The simulator's settings (impact law, `e_n`, IWC rule).
    pub sim: SimConfig,
    /// Sample period, s.
    pub sample_period_s: f64,
    /// The start `[theta1, theta1_dot, theta2, theta2_dot]`, rad and rad/s.
    pub x0: [f64; 4],
}

/// What the search found.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SearchReport {
    /// Runs made.
    pub runs: usize,
    /// Runs that reached their end.
    pub completed: usize,
    /// Singular points met, over all runs.
    pub singular_points: u64,
    /// Moreau-Jean bridges, over all runs.
    pub bridges: u64,
    /// Time bridged, s, over all runs.
    pub bridged_s: f64,
    /// Dynamic jams, over all runs (of which at a collapsed step: `jams_at_collapse`).
    pub jams: u64,
    /// Jams resolved where the step collapsed.
    pub jams_at_collapse: u64,
    /// Runs that bounced persistently (touchdowns in the last fifth of the run).
    pub bouncing: usize,
    /// Located passages of `p = 0` with the reaction finite (each followed by an IWC), over all runs.
    pub p_zero: u64,
    /// Integration steps the energy ledger rejected and took again smaller, over all runs.
    pub refinements: u64,
    /// Energy-ledger violations, over all runs (0 for a sound search).
    pub ledger_violations: u64,
    /// The largest ratio of an accepted entry's residual to its tolerance.
    pub worst_ledger_ratio: f64,
    /// The largest `|E(t) - E(0) - works|` of a run's end, J.
    pub worst_residual_j: f64,
    /// The runs that failed, each with its error.
    pub failures: Vec<(SearchRun, String)>,
}

impl SearchReport {
    /// One line of what the search met: runs, singular points, located `p = 0`
    /// passages, bridges, jams, ledger refinements and violations, failures.
    pub fn line(&self) -> String {
        format!(
            "{} runs ({} completed, {} bouncing), singular points {}, p_zero {}, bridges {}, jams {} (at collapse {}), ledger refinements {}, ledger violations {}, worst ratio {:.3e}, worst residual {:.3e} J, failures {}",
            self.runs,
            self.completed,
            self.bouncing,
            self.singular_points,
            self.p_zero,
            self.bridges,
            self.jams,
            self.jams_at_collapse,
            self.refinements,
            self.ledger_violations,
            self.worst_ledger_ratio,
            self.worst_residual_j,
            self.failures.len()
        )
    }
}

/// The critical `mu` of `params` on `branch`: the smallest `Q_22 / |Q_21|` over
/// the belt (400 points across the reach), where `p(s)` can reach 0.
pub fn threshold(params: &Params<f64>, branch: ElbowBranch) -> Option<f64> {
    let arm = Arm::new(*params);
    let reach = (4.0 * params.l * params.l - params.h * params.h).sqrt();
    (1..400)
        .filter_map(|i| {
            let z_t = reach * (2.0 * f64::from(i) / 400.0 - 1.0);
            let q = inverse_kinematics(params.l, &Vector2::new(z_t, -params.h), branch).ok()?;
            let qm = arm.q_matrix(&q);
            Some(qm[(1, 1)] / qm[(0, 1)].abs())
        })
        .min_by(f64::total_cmp)
}

/// The `i`-th arm of `seed`, its impact law and `e_n`. Arm 0 is the one issue 24's
/// search found (Table I's `m` +11 %, `l` +4 %, `sigma` +19 %, `k` -16 %, `alpha0`
/// -17 %; Poisson, `e_n = 0.1`), where slides run into the dynamic jam; the
/// others are random.
pub fn arm(seed: u64, i: usize) -> (Params<f64>, ImpactLaw, f64) {
    if i == 0 {
        let params = Params {
            m: 0.13288317384683318,
            l: 0.21762723339408532,
            sigma: 0.005932199636113795,
            k: 1.0920241576528966,
            h: 0.3912149518771235,
            alpha0: 0.19777060647993205,
            ..Params::paper()
        };
        return (params, ImpactLaw::Poisson, 0.1);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i as u64));
    let base = Params::<f64>::paper();
    let mut f = || 0.75 + 0.5 * rng.random::<f64>();
    let (m, l, sigma, k, alpha0) = (base.m * f(), base.l * f(), base.sigma * f(), base.k * f(), base.alpha0 * f());
    let x0a = deg_to_state(X0A.deg);
    let h = l * (x0a[0].cos() + x0a[2].cos());
    let law = ImpactLaw::ALL[rng.random_range(0..3usize)];
    let e_n = 0.6 * rng.random::<f64>();
    (Params { m, l, sigma, k, alpha0, h, ..base }, law, e_n)
}

/// A run's counters, ledger and whether it bounced in the last fifth, or its error.
pub type RunOutcome = Result<(Counters, Ledger, bool), SimError>;

/// One open-loop run from the run's start under zero torque; its counters, ledger,
/// whether it bounced in the last fifth, or its error.
pub fn simulate(run: &SearchRun, duration_s: f64) -> RunOutcome {
    let mut plant = Plant::new(run.params, run.sim, run.x0, 0.0, [0.0, 0.0])?;
    let n = (duration_s / run.sample_period_s).round() as usize;
    let mut late_touchdowns = 0;
    for k in 0..n {
        let before = plant.counters().touchdowns + plant.counters().lift_offs;
        plant.advance(&Hold([0.0, 0.0]), (k + 1) as f64 * run.sample_period_s - plant.time(), &mut NoObserver)?;
        if k >= n * 4 / 5 {
            late_touchdowns += plant.counters().touchdowns + plant.counters().lift_offs - before;
        }
    }
    Ok((*plant.counters(), plant.ledger(), late_touchdowns > 0))
}

/// The first belt speed from -1 m/s up (0.05 m/s steps) where bouncing starts or
/// stops at `mu` (runs of `duration_s`, 10 ms samples); -0.4 m/s if none.
fn band_edge(params: &Params<f64>, sim: SimConfig, mu: f64, duration_s: f64) -> f64 {
    let bouncing = |v: f64| {
        let run = SearchRun { arm: 0, params: Params { mu, v_belt: v, ..*params }, sim, sample_period_s: 1e-2, x0: deg_to_state(X0A.deg) };
        simulate(&run, duration_s).map(|(_, _, b)| b).unwrap_or(false)
    };
    let speeds: Vec<f64> = (0..=18).map(|i| -1.0 + 0.05 * f64::from(i)).collect();
    let states: Vec<bool> = speeds.par_iter().map(|&v| bouncing(v)).collect();
    states.windows(2).position(|w| w[0] != w[1]).map_or(-0.4, |i| 0.5 * (speeds[i] + speeds[i + 1]))
}

/// The belt speed of the second `mu` scan, m/s: near the fast end of Table I's
/// range, where issue 24's arm ran into the jam.
const FAST_BELT: f64 = -0.98;

/// The runs of the search: per arm, the `mu` scans from 0.05 below its threshold
/// to 0.25 above it (across the Painlevé threshold and the onset of bouncing) at
/// its band-edge speed and at -0.98 m/s, and the `v_belt` scan over the edge
/// plus and minus 0.05 m/s at `max(0.6, threshold + 0.15)` (at most 1.2), under
/// both IWC rules and every sample period.
pub fn plan(spec: &SearchSpec) -> Vec<SearchRun> {
    if spec.family == Family::Corner {
        return plan_corner(spec);
    }
    let mut runs = Vec::new();
    for i in 0..spec.arms {
        let (params, impact_law, e_n) = arm(spec.seed, i);
        let Some(mu_c) = threshold(&params, ElbowBranch::Down) else { continue };
        let sim = SimConfig { impact_law, e_n, ..SimConfig::default() };
        let mu_band = (mu_c + 0.15).clamp(0.6, 1.2);
        let edge = band_edge(&params, sim, mu_band, spec.duration_s.min(100.0));
        let scan = |lo: f64, hi: f64, points: usize| -> Vec<f64> {
            (0..points).map(|k| lo + (hi - lo) * k as f64 / (points.max(2) - 1) as f64).collect()
        };
        let mut points = Vec::new();
        for v in [edge, FAST_BELT] {
            points.extend(scan(mu_c - 0.05, mu_c + 0.25, spec.mu_points).into_iter().filter(|&m| m > 0.0).map(|m| (m, v)));
        }
        points
            .extend(scan(edge - 0.05, edge + 0.05, spec.v_points).into_iter().filter(|&v| (-1.0..0.0).contains(&v)).map(|v| (mu_band, v)));
        push_runs(&mut runs, spec, (i, params, sim, deg_to_state(X0A.deg)), points);
    }
    runs
}

/// Issue 53's start, degrees.
const ISSUE53_START_DEG: [f64; 2] = [34.53531701873741, 23.744016380660902];

/// The `i`-th arm of the corner family of `seed` and its start (rad, rad/s): arm 0
/// is issue 53's, the others move each of its `m`, `l`, `sigma`, `k`, `alpha0`
/// within 3 % and its start's angles within 0.5 deg; `H` puts the tip on the belt.
pub fn corner_arm(seed: u64, i: usize) -> (Params<f64>, [f64; 4]) {
    let (mut f, mut d) = ([1.0; 5], [0.0; 2]);
    if i > 0 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i as u64));
        f = std::array::from_fn(|_| 0.97 + 0.06 * rng.random::<f64>());
        d = std::array::from_fn(|_| rng.random::<f64>() - 0.5);
    }
    let (q1, q2) = ((ISSUE53_START_DEG[0] + d[0]).to_radians(), (ISSUE53_START_DEG[1] + d[1]).to_radians());
    let (m, l, sigma, k, alpha0) = (0.15 * f[0], 0.23 * f[1], 0.008 * f[2], 1.0 * f[3], 0.20 * f[4]);
    let h = l * (q1.cos() + q2.cos());
    (Params { m, l, sigma, k, alpha0, h, ..Params::paper() }, [q1, 0.0, q2, 0.0])
}

/// The runs of the corner family: per arm, `mu` from 0.410 to 0.432 by `v_belt`
/// from -0.52 to -0.48 m/s, both IWC rules, every sample period; Newton, `e_n 0.2`.
fn plan_corner(spec: &SearchSpec) -> Vec<SearchRun> {
    let scan = |lo: f64, hi: f64, points: usize| -> Vec<f64> {
        (0..points).map(|k| if points < 2 { 0.5 * (lo + hi) } else { lo + (hi - lo) * k as f64 / (points - 1) as f64 }).collect()
    };
    let sim = SimConfig { impact_law: ImpactLaw::Newton, e_n: 0.2, ..SimConfig::default() };
    let mut runs = Vec::new();
    for i in 0..spec.arms {
        let (params, x0) = corner_arm(spec.seed, i);
        let points = scan(0.410, 0.432, spec.mu_points)
            .into_iter()
            .flat_map(|mu| scan(-0.52, -0.48, spec.v_points).into_iter().map(move |v| (mu, v)));
        push_runs(&mut runs, spec, (i, params, sim, x0), points);
    }
    runs
}

/// Appends the runs of arm `i` (its parameters, settings and start) at each
/// `(mu, v_belt)` of `points`, under both IWC rules and every sample period.
fn push_runs(
    runs: &mut Vec<SearchRun>,
    spec: &SearchSpec,
    arm: (usize, Params<f64>, SimConfig, [f64; 4]),
    points: impl IntoIterator<Item = (f64, f64)>,
) {
    let (i, params, sim, x0) = arm;
    for (mu, v_belt) in points {
        for iwc in IwcRule::ALL {
            for &sample_period_s in &spec.sample_periods {
                runs.push(SearchRun {
                    arm: i,
                    params: Params { mu, v_belt, ..params },
                    sim: SimConfig { iwc, ..sim },
                    sample_period_s,
                    x0,
                });
            }
        }
    }
}

/// Runs the search on every core; `progress(done, total)` after each run.
pub fn search(spec: &SearchSpec, progress: &(dyn Fn(usize, usize) + Sync)) -> SearchReport {
    let runs = plan(spec);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<(SearchRun, RunOutcome)> = runs
        .par_iter()
        .map(|run| {
            let r = simulate(run, spec.duration_s);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1, runs.len());
            (*run, r)
        })
        .collect();
    let mut report = SearchReport { runs: results.len(), ..SearchReport::default() };
    for (run, r) in results {
        match r {
            Ok((c, ledger, bouncing)) => {
                report.completed += 1;
                report.p_zero += c.p_zero;
                report.refinements += ledger.refinements;
                report.ledger_violations += ledger.violations;
                report.worst_ledger_ratio = report.worst_ledger_ratio.max(ledger.worst_ratio);
                report.worst_residual_j = report.worst_residual_j.max(ledger.residual_j.abs());
                report.singular_points += c.singular_points;
                report.bridges += c.bridges;
                report.bridged_s += c.bridged_s;
                report.jams += c.jams;
                report.jams_at_collapse += c.jams_at_collapse;
                report.bouncing += usize::from(bouncing);
            }
            Err(e) => report.failures.push((run, e.to_string())),
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CI's subset: every run completes, and the scans cross something (some runs
    /// bounce, some do not).
    #[test]
    fn every_run_of_the_quick_corner_search_completes() {
        let report = search(&SearchSpec::quick(), &|_, _| {});
        eprintln!("QUICK: {}", report.line());
        assert!(report.runs >= 50, "{report:?}");
        assert!(report.failures.is_empty(), "{:#?}", report.failures);
        assert_eq!(report.completed, report.runs);
        assert!(report.bouncing > 0 && report.bouncing < report.runs, "the scans cross a band edge: {report:?}");
        assert!(report.jams > 0, "issue 24's arm meets the corner: {report:?}");
    }

    /// The full search (docs/plant.md "The corner search"): `cargo test --release
    /// -p analyses --lib corner_search -- --ignored --nocapture`.
    #[test]
    #[ignore = "the full search: a few minutes on 2 cores"]
    fn every_run_of_the_full_corner_search_completes() {
        let report = search(&SearchSpec::full(), &|done, total| {
            if done % 200 == 0 || done == total {
                eprintln!("{done} of {total} runs");
            }
        });
        eprintln!("{}", report.line());
        assert!(report.failures.is_empty(), "{:#?}", report.failures);
        assert_eq!(report.completed, report.runs);
    }

    /// CI's subset of the corner search (issue 53): every run completes, meets the
    /// singular point, and closes its energy ledger.
    #[test]
    fn every_run_of_the_quick_corner_search_completes_with_its_ledger_closed() {
        let report = search(&SearchSpec::corner_quick(), &|_, _| {});
        eprintln!("CORNER QUICK: {}", report.line());
        assert!(report.failures.is_empty(), "{:#?}", report.failures);
        assert_eq!(report.completed, report.runs);
        assert_eq!(report.ledger_violations, 0, "{report:?}");
        assert!(report.worst_residual_j < 1e-6, "{report:?}");
        assert!(report.singular_points + report.p_zero >= 100, "the runs pass the corner: {report:?}");
    }

    /// The full corner search (docs/plant.md "The corner search"): `cargo test
    /// --release -p analyses --lib corner_search -- --ignored --nocapture`.
    #[test]
    #[ignore = "the full corner search: about ten minutes on 2 cores"]
    fn every_run_of_the_full_corner_search_completes_with_its_ledger_closed() {
        let report = search(&SearchSpec::corner(), &|done, total| {
            if done % 500 == 0 || done == total {
                eprintln!("{done} of {total} runs");
            }
        });
        eprintln!("{}", report.line());
        let SearchReport { runs, completed, singular_points, ledger_violations, .. } = report;
        assert!(report.failures.is_empty(), "{:#?}", report.failures);
        assert_eq!(completed, runs);
        assert!(runs >= 10_000 && singular_points >= 1_000, "{runs} runs, {singular_points} singular points");
        assert_eq!(ledger_violations, 0);
    }

    /// The threshold of the paper's arm is the paper's critical `mu` (about 0.4).
    #[test]
    fn the_paper_arms_threshold_is_its_critical_mu() {
        let mu_c = threshold(&Params::paper(), ElbowBranch::Down).unwrap();
        assert!((0.3..0.5).contains(&mu_c), "{mu_c}");
    }
}
