//! `Z_t,sliding` (docs/model.md experiments 5 and 6): the largest tangential
//! target the tip reaches with no lift-off, by bisection ([`analyses::zmax`]
//! defines the trial and the criteria), for the PID and the hybrid controller
//! from `x0d` and `x0u`, ideal or sampled: the settings' check and plan, the
//! searches both fronts run ([`run_searches`]), the rows and the summary.

use std::sync::atomic::AtomicBool;

use rayon::prelude::*;

use crate::{error::Error, settings::ZmaxArgs};
use analyses::admissible::{p_on_belt, positive_intervals};
use analyses::zmax::{Combination, Criteria, Search, Setting, default_bracket, max_trials, sampled_scenario, search_until};
use plant::initial::PaperX0;
use rig::scenario::Scenario;

pub mod summary;
use summary::*;

fn combinations(args: &ZmaxArgs) -> Vec<Combination> {
    if args.all {
        return Combination::all();
    }
    let (controller, x0) = (args.controller, args.x0);
    let setting = if args.ideal { Setting::Ideal } else { Setting::Sampled };
    vec![Combination { controller, x0, setting }]
}

/// The base scenario (`--scenario` or the embedded default) with the `--set`
/// overrides and `--iwc` (a key is set in one place: `--set plant.iwc` with `--iwc` is refused).
fn base_scenario(args: &ZmaxArgs) -> Result<Scenario, Error> {
    rig::overrides::check_keys(&args.set, &TRIAL_KEYS).map_err(rig::scenario::ScenarioError::from)?;
    if args.iwc.is_some() {
        rig::overrides::check_keys(&args.set, &[("plant.iwc", "--iwc")]).map_err(rig::scenario::ScenarioError::from)?;
    }
    crate::scenario::refuse_board_overrides(&args.set, "zmax (the firmware in-process, or the ideal law)")?;
    let mut s = crate::scenario::read_scenario(args.scenario.as_deref(), &args.set)?;
    if let Some(iwc) = args.iwc {
        s.plant.iwc = iwc;
    }
    Ok(s)
}

/// End of the admissible range on the initial condition's branch, `z_r_dot > 0`.
fn p_zero_end(base: &Scenario, x0: PaperX0, bracket: (f64, f64)) -> Option<f64> {
    let params = base.plant.params();
    let arm = shared::Arm::new(params);
    let branch = x0.branch();
    let p = |z| p_on_belt(&arm, z, branch, shared::SlipDirection::Positive);
    positive_intervals(p, bracket.0, bracket.1 + 1e-3 - 1e-9, 20_000, 1e-9).iter().find(|i| i.hi_is_root).map(|i| i.hi)
}

/// The `z_t` (m) of the largest `theta1` on the belt on the initial condition's
/// branch, by a scan of 20 000 steps over the bracket; `None` at an end of it.
fn theta1_fold(x0: PaperX0, bracket: (f64, f64)) -> Option<f64> {
    let params = shared::Params::<f64>::paper();
    let branch = x0.branch();
    let n = 20_000;
    let z_at = |i: usize| bracket.0 + (bracket.1 - bracket.0) * i as f64 / n as f64;
    let theta1 = |z: f64| {
        shared::kinematics::inverse_kinematics(params.l, &nalgebra::Vector2::new(z, -params.h), branch).map_or(f64::NEG_INFINITY, |q| q[0])
    };
    let best = (0..=n).max_by(|&a, &b| theta1(z_at(a)).total_cmp(&theta1(z_at(b))))?;
    (best > 0 && best < n).then(|| z_at(best))
}

/// A `Z_t,sliding` search checked and set up, before anything runs: what [`plan`] returns.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The base scenario (`--scenario` or the embedded default, with `--set` and `--iwc`).
    pub base: Scenario,
    /// The trial's criteria.
    pub criteria: Criteria,
    /// The searches: each case with its bracket of targets, m (seed 0, the nominal ones).
    pub jobs: Vec<(Combination, (f64, f64))>,
    /// With `--seeds N`: the sampled cases' searches at seeds `1..N`, each as the
    /// index of its case in `jobs` and its seed ([`analyses::sweep::Draw`]).
    pub seeded: Vec<(usize, usize)>,
    /// Seeds per sampled case (1: the nominal search only).
    pub seeds: usize,
    /// The jitter of seeds `1..` (`f_n*` and the delay only).
    pub jitter: analyses::sweep::Jitter,
}

impl Plan {
    /// Every search to run: the nominal ones (`jobs`), then the seeded ones, each
    /// with its scenario (seed `k`'s noise seed, `f_n*` and delay), case and bracket.
    pub fn searches(&self) -> Vec<(Scenario, Combination, (f64, f64))> {
        let nominal = self.jobs.iter().map(|&(c, b)| (self.base.clone(), c, b));
        let seeded = self.seeded.iter().map(|&(j, k)| {
            let mut s = self.base.clone();
            analyses::sweep::run::apply_draw(&mut s, &analyses::sweep::Draw::of(self.base.sensors.seed, &self.jitter, k));
            (s, self.jobs[j].0, self.jobs[j].1)
        });
        nominal.chain(seeded).collect()
    }

    /// The most trials the searches can take (the progress bar's length).
    pub fn max_trials(&self, tol: f64) -> u64 {
        self.searches().iter().map(|(_, _, b)| u64::from(max_trials(b.0, b.1, tol))).sum()
    }
}

/// Checks `sil-host zmax`'s options and every case's set-up (the sampled
/// scenario and the ideal law at the top of its bracket).
///
/// # Errors
/// Bad input (exit 2).
pub fn plan(args: &ZmaxArgs) -> Result<Plan, Error> {
    let base = base_scenario(args)?;
    let criteria = Criteria {
        duration_s: args.duration,
        move_time_s: base.controller.move_time_s,
        reach_tol_m: args.reach_tol,
        settle_tol_m: args.settle_tol,
        settle_window_s: args.settle_window,
        lift_off_gap_m: args.lift_off_gap,
    };
    criteria.validate()?;
    if !(args.tol.is_finite() && args.tol > 0.0) {
        return Err(Error::bad_input(format!("--tol {} m must be finite and > 0", args.tol)));
    }
    let combos = combinations(args);
    for c in &combos {
        analyses::zmax::check_x0(c.x0)?;
    }
    let e = &args.ensemble;
    if !(1..=analyses::sweep::ensemble::MAX_SEEDS).contains(&e.seeds) {
        return Err(Error::bad_input(format!("--seeds must be in 1..={}, got {}", analyses::sweep::ensemble::MAX_SEEDS, e.seeds)));
    }
    let jitter = e.jitter();
    jitter.check().map_err(Error::bad_input)?;
    if jitter.mu > 0.0 || jitter.start_m > 0.0 {
        return Err(Error::bad_input(
            "zmax: --jitter-mu and --jitter-start are for sweeps; its seeds move the sensor noise, --jitter-f-n-ref and --jitter-delay",
        ));
    }
    if e.seeds > 1 && combos.iter().all(|c| c.setting == Setting::Ideal) {
        return Err(Error::bad_input("--seeds: the ideal setting has no noise (exact measurements); seeds are for the sampled one"));
    }
    for sign in [-1.0, 1.0] {
        let mut t = base.clone();
        t.controller.f_n_ref += sign * jitter.f_n_ref_n;
        t.timing.delta_s += sign * jitter.delay_s;
        t.validate().map_err(|err| {
            Error::bad_input(format!(
                "--jitter-f-n-ref {} N / --jitter-delay {} s take the scenario out of its range: {err}",
                jitter.f_n_ref_n, jitter.delay_s
            ))
        })?;
    }
    let mut jobs = Vec::new();
    for combo in combos {
        let bracket = match &args.bracket {
            Some(s) => crate::arm::parse_range("bracket", s)?,
            None => default_bracket(&base, combo.x0)?,
        };
        sampled_scenario(&base, combo, bracket.1, &criteria)?;
        analyses::ideal::build(&analyses::zmax::ideal_setup(&base, combo, bracket.1, &criteria)).map_err(Error::from)?;
        jobs.push((combo, bracket));
    }
    let seeded = (1..e.seeds)
        .flat_map(|k| jobs.iter().enumerate().filter(|(_, (c, _))| c.setting == Setting::Sampled).map(move |(j, _)| (j, k)))
        .collect();
    Ok(Plan { base, criteria, jobs, seeded, seeds: e.seeds, jitter })
}

/// The rows of `trials.csv`: every trial of every search, in order.
pub fn trial_rows(summary: &ZmaxSummary) -> Vec<TrialRow<'_>> {
    summary.trials.iter().map(TrialRow).collect()
}

/// The validity counters summed over every trial of every search.
fn trials_validity(searches: &[Search]) -> plant::Validity {
    let mut v = plant::Validity::default();
    for t in searches.iter().flat_map(|s| &s.trials) {
        v.add(&t.validity);
    }
    v
}

/// The keys each trial sets: `--set` of one of them is refused.
const TRIAL_KEYS: [(&str, &str); 4] = [
    ("controller.kind", "--controller (or --all)"),
    ("plant.x0", "--x0 (or --all)"),
    ("controller.target_z_t", "the bisection"),
    ("timing.duration_s", "--duration"),
];

/// `summary.json` (with `zmax.csv`'s rows) of the `searches` of `plan`, which
/// took `wall_s` s.
pub fn summary(args: &ZmaxArgs, plan: Plan, searches: &[Search], wall_s: f64) -> ZmaxSummary {
    let n = plan.jobs.len().min(searches.len());
    let (nominal, seeded) = searches.split_at(n);
    let seed_rows: Vec<SeedRow> = nominal
        .iter()
        .filter(|s| plan.seeds > 1 && s.combination.setting == Setting::Sampled)
        .map(|s| SeedRow::of(0, s))
        .chain(plan.seeded.iter().zip(seeded).map(|(&(_, k), s)| SeedRow::of(k, s)))
        .collect();
    let distributions = ZmaxDistribution::of_rows(&seed_rows, plan.seeds);
    let samples = samples_note(&plan);
    let Plan { base, criteria, .. } = plan;
    let searches = nominal;
    let rows: Vec<ZmaxRow> = searches
        .iter()
        .map(|s| ZmaxRow::of(s, p_zero_end(&base, s.combination.x0, s.bracket), theta1_fold(s.combination.x0, s.bracket)))
        .collect();
    ZmaxSummary {
        results: rows,
        trials: searches.iter().flat_map(|s| s.trials.iter().cloned()).collect(),
        criteria,
        tol_m: args.tol,
        definition: DEFINITION,
        paper: PAPER,
        plant_params: base.plant.params(),
        gains: ZmaxGains {
            pid: base.controller.pid,
            hybrid_kp: base.controller.hybrid.kp,
            hybrid_kd: base.controller.hybrid.kd,
            hybrid_ki_x0d: base.controller.hybrid_ki(PaperX0::D),
            hybrid_ki_x0u: base.controller.hybrid_ki(PaperX0::U),
        },
        validity: {
            let mut v = trials_validity(searches);
            v.add(&trials_validity(seeded));
            v
        },
        base_scenario: base,
        samples,
        seeds: seed_rows,
        distributions,
        wall_s,
    }
}

/// What the sampled searches' results are drawn from (`summary.json`'s `samples`).
fn samples_note(plan: &Plan) -> String {
    let noise = plan.base.sensors.seed;
    if plan.seeds == 1 {
        format!(
            "one sample: the sampled searches run at sensor-noise seed {noise} (a sampled trial near its limit may lift off at one seed \
             and not at another); --seeds N bisects once per seed and gives Z_t,sliding's median and spread"
        )
    } else {
        format!(
            "{} seeds per sampled case: sensor-noise seeds {noise} to {} (jitter: {}), one bisection per seed; `results` holds seed 0's, \
             `distributions` the spread over the seeds; the ideal cases have no noise (one search)",
            plan.seeds,
            noise.wrapping_add(plan.seeds as u64 - 1),
            plan.jitter.describe()
        )
    }
}

/// Runs every search of `plan` ([`Plan::searches`]: the nominal ones in `jobs`'
/// order, then the seeded ones) in parallel (rayon's global pool), calling
/// `progress` with the number of trials done (a search that ends early, a
/// bracket end deciding, reports the trials it did not need); a search stopped by
/// `stop` ends with [`analyses::AnalysisError::Interrupted`].
///
/// # Errors
/// The first search's error, in `plan`'s order.
pub fn run_searches(
    plan: &Plan,
    tol: f64,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Search>, analyses::AnalysisError> {
    plan.searches()
        .par_iter()
        .map(|(base, combo, bracket)| {
            let (combo, bracket) = (*combo, *bracket);
            let s = search_until(base, combo, bracket, tol, &plan.criteria, stop, |_| progress(1));
            if let Ok(s) = &s {
                progress(u64::from(max_trials(bracket.0, bracket.1, tol)).saturating_sub(s.trials.len() as u64));
            }
            s
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect()
}
