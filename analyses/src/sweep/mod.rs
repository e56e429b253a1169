//! The two-parameter brute-force bifurcation diagram (docs/model.md experiments 3 and
//! 7, paper Figs. 3 and 9): a grid in `(mu, v_belt)` (and optionally in the impact
//! law and its coefficient `e_n`), several initial conditions in contact, a
//! transient then a record window per run, and the paper's persistent-bouncing
//! indicator `max theta1_dot > 0` over the record window.
//!
//! - [`SweepSpec`]: what a sweep computes (stored as `sweep.json` in its folder);
//!   the runs are numbered by [`SweepSpec::run_at`] in a fixed order, so shards,
//!   resumed sweeps and merges agree on every run's index;
//! - [`run`]: one run (open loop, or closed loop with the firmware step in-process);
//!   how it ended and its row ([`run::Outcome`], [`run::RunRow`], in `outcome.rs`);
//! - [`Shard`]: the runs dealt to the shards of a sweep;
//! - [`summary`]: critical `mu` and belt-speed bands of persistent bouncing.
//!
//! The sweep's folder (journal, resume, merge) and its figures are the command
//! line's (`sil-host`'s `sweep` module).

pub mod axis;
pub mod cells;
pub mod ensemble;
pub mod extrema;
mod outcome;
pub mod run;
mod shard;
pub mod summary;

use firmware::ControllerKind;
use nalgebra::Vector2;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use shared::{ElbowBranch, Params, kinematics::inverse_kinematics};

use plant::impact::{ImpactLaw, IwcRule};
use plant::initial::{self, PaperX0};
use plant::moreau_jean::SingularRule;
use rig::scenario::Scenario;

pub use axis::Axis;
pub use ensemble::{Draw, Jitter, Proportion};
pub use shard::{Assignment, Shard};

/// Version of the `sweep.json` layout; a folder of another version is not resumed.
/// Version 2: the IWC rule as a dimension, validity counters and the `invalid`
/// outcome in every row. Version 3: closed-loop outcomes (`lift_off`,
/// `target_not_reached`) and the `target_error_m` column. Version 4: the `jams`
/// column (issue 24's dynamic jams, resolved by a tangential impact). Version 5:
/// the `bouncing` column named for what it is (`theta1_dot_over_threshold`) and
/// the energy ledger's columns (issue 53). Version 6: the `seed` column and the
/// spec's `seeds` and `jitter` (issue 82's ensembles).
pub const FORMAT: u32 = 6;

/// What drives the arm during a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SweepController {
    /// Open loop, `u = 0` (docs/model.md experiment 3).
    None,
    /// The hybrid force/motion controller (experiment 6's; experiment 7).
    Hybrid,
    /// The joint-space PID (experiment 5's).
    Pid,
}

impl SweepController {
    /// The controller that drives the arm; `None` in open loop.
    pub fn kind(self) -> Option<ControllerKind> {
        match self {
            Self::None => None,
            Self::Hybrid => Some(ControllerKind::Hybrid),
            Self::Pid => Some(ControllerKind::Pid),
        }
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Hybrid => "hybrid",
            Self::Pid => "pid",
        }
    }
}

/// Everything that determines a sweep's results (`sweep.json`). Two folders with
/// equal specs hold runs of the same sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// Layout version ([`FORMAT`]).
    pub format: u32,
    /// Friction coefficients `mu`.
    pub mu: Axis,
    /// Belt speeds `v_belt`, m/s.
    pub v_belt: Axis,
    /// Impact-without-collision rules (outermost loop).
    pub iwc_rules: Vec<IwcRule>,
    /// Impact laws.
    pub impact_laws: Vec<ImpactLaw>,
    /// Restitution coefficients `e_n`.
    pub e_n: Vec<f64>,
    /// The paper's initial conditions used (written by name: `x0a`, `x0d`, `x0u`).
    #[serde(with = "ic_names")]
    pub paper_ics: Vec<PaperX0>,
    /// Number of random initial conditions in contact ([`SweepSpec::initial_conditions`]).
    pub random_ics: usize,
    /// Seed of the random initial conditions.
    pub seed: u64,
    /// Transient, s (not recorded).
    pub transient_s: f64,
    /// Record window after the transient, s.
    pub record_s: f64,
    /// What drives the arm.
    pub controller: SweepController,
    /// Closed loop: the paper's continuous-time controller with exact measurements
    /// instead of the firmware sampled as on the MCU.
    pub ideal: bool,
    /// Closed loop: the scenario whose controller, timing and sensor sections are
    /// used (its plant section is replaced per run); `None` in open loop.
    pub scenario: Option<Scenario>,
    /// Persistent bouncing is flagged when `max theta1_dot` over the record window
    /// exceeds this, rad/s (the paper: 0; see [`run`]).
    pub threshold: f64,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Integrator absolute tolerance.
    pub atol: f64,
    /// The arm's parameters (paper Table I: `m`, `l`, `sigma`, `k`, `h`,
    /// `alpha0`, `g`); each run's `mu` and `v_belt` replace these. In closed loop
    /// they equal the scenario's `[plant]`. Absent from older `sweep.json`
    /// files: the paper's.
    #[serde(default = "Params::paper")]
    pub params: Params<f64>,
    /// Closed loop: the firmware's friction estimate as a multiple of each run's
    /// `mu` (`mu_hat = mu_hat_factor mu`; 1, the default, is the paper's controller,
    /// which knows `mu`). `sil-host sensitivity` varies it.
    #[serde(default = "unit", skip_serializing_if = "is_unit")]
    pub mu_hat_factor: f64,
    /// What a slide does at the singular point `p = b = 0` (`plant::SimConfig::singular`;
    /// written only when it is not the default, `leave`).
    #[serde(default, skip_serializing_if = "is_leave")]
    pub singular: SingularRule,
    /// Runs per grid point and initial condition ([`ensemble`]): seed 0 the
    /// nominal run, seeds `1..` the sensor noise's next seeds and the [`Jitter`]'s
    /// draws (written only when not 1).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub seeds: usize,
    /// The bounds of what seeds `1..` jitter (written only when one is set).
    #[serde(default, skip_serializing_if = "Jitter::is_none")]
    pub jitter: Jitter,
}

/// One initial condition of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InitialCondition {
    /// `x0a`, `x0d`, `x0u`, or `r1`, `r2`, ... for the random ones.
    pub name: String,
    /// `[theta1, theta1_dot, theta2, theta2_dot]`, rad and rad/s (before the plant's
    /// projection onto the belt).
    pub x0: [f64; 4],
    /// Elbow branch (`up` or `down`).
    pub branch: ElbowBranch,
    /// Height of the tip above the belt as given, m (negative: inside it; the plant
    /// projects it onto the belt at the same `z_t` and branch).
    pub height_above_belt: f64,
}

/// One run: a grid point, an initial condition and a seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunKey {
    /// Index in the sweep's order (0-based).
    pub index: usize,
    /// The seed's number (`0..seeds`; [`ensemble::Draw`]).
    pub seed: usize,
    /// Impact-without-collision rule.
    pub iwc: IwcRule,
    /// Impact law.
    pub impact_law: ImpactLaw,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Index of `mu` on its axis.
    pub i_mu: usize,
    /// Friction coefficient.
    pub mu: f64,
    /// Index of `v_belt` on its axis.
    pub i_v: usize,
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Index of the initial condition.
    pub i_ic: usize,
}

/// Largest belt tangential reach of the tip used for random initial conditions, as a
/// fraction of the reach `sqrt((2 l)^2 - H^2)` (away from the singular straight arm).
pub const RANDOM_REACH_FRACTION: f64 = 0.9;

impl SweepSpec {
    /// The paper's experiment 3 grid: `mu` 0.1 to 1 by 0.1, `v_belt` -1 to -0.1 by
    /// 0.005, `x0a` and `x0d`, 250 s + 50 s, open loop, Newton with `e_n = 0.2`.
    pub fn paper() -> Self {
        Self {
            format: FORMAT,
            mu: Axis { start: 0.1, stop: 1.0, step: 0.1 },
            v_belt: Axis { start: -1.0, stop: -0.1, step: 0.005 },
            iwc_rules: vec![IwcRule::Restitution],
            impact_laws: vec![ImpactLaw::Newton],
            e_n: vec![0.2],
            paper_ics: vec![PaperX0::A, PaperX0::D],
            random_ics: 0,
            seed: 1,
            transient_s: 250.0,
            record_s: 50.0,
            controller: SweepController::None,
            ideal: false,
            scenario: None,
            threshold: DEFAULT_THRESHOLD,
            rtol: 1e-9,
            atol: 1e-11,
            params: Params::paper(),
            mu_hat_factor: 1.0,
            singular: SingularRule::Leave,
            seeds: 1,
            jitter: Jitter::default(),
        }
    }

    /// The initial conditions: the paper's named ones, then `random_ics` random ones
    /// in contact, drawn from `seed` (ChaCha8): the tip on the belt at `z_t` uniform
    /// within [`RANDOM_REACH_FRACTION`] of the reach, a random elbow branch, at rest
    /// (like the paper's). The same list is used at every grid point.
    pub fn initial_conditions(&self) -> Vec<InitialCondition> {
        let params = self.params;
        let mut out: Vec<InitialCondition> = self
            .paper_ics
            .iter()
            .map(|x| x.condition())
            .map(|ic| {
                let x0 = initial::deg_to_state(ic.deg);
                let info = initial::describe_projection(&params, x0);
                InitialCondition { name: ic.name.into(), x0, branch: info.branch, height_above_belt: info.height_above_belt }
            })
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let reach = ((2.0 * params.l).powi(2) - params.h * params.h).sqrt() * RANDOM_REACH_FRACTION;
        for i in 0..self.random_ics {
            let z_t: f64 = rng.random_range(-reach..reach);
            let branch = if rng.random_bool(0.5) { ElbowBranch::Up } else { ElbowBranch::Down };
            // Within the reach by construction, so the inverse kinematics exists.
            let q = inverse_kinematics(params.l, &Vector2::new(z_t, -params.h), branch).unwrap_or_else(|_| Vector2::zeros());
            out.push(InitialCondition { name: format!("r{}", i + 1), x0: [q[0], 0.0, q[1], 0.0], branch, height_above_belt: 0.0 });
        }
        out
    }

    /// Number of initial conditions.
    pub fn n_ics(&self) -> usize {
        self.paper_ics.len() + self.random_ics
    }

    /// Number of runs: seeds x IWC rules x laws x `e_n` x `mu` x `v_belt` x initial conditions.
    pub fn n_runs(&self) -> usize {
        self.seeds * self.runs_per_seed()
    }

    /// Runs of one seed: IWC rules x laws x `e_n` x `mu` x `v_belt` x initial
    /// conditions (the grid's cells).
    pub fn runs_per_seed(&self) -> usize {
        self.iwc_rules.len() * self.impact_laws.len() * self.e_n.len() * self.mu.len() * self.v_belt.len() * self.n_ics()
    }

    /// What seed `k` changes ([`ensemble::Draw::of`] from the spec's `seed` and `jitter`).
    pub fn draw(&self, k: usize) -> Draw {
        Draw::of(self.seed, &self.jitter, k)
    }

    /// Simulated time of one run, s.
    pub fn run_duration(&self) -> f64 {
        self.transient_s + self.record_s
    }

    /// Run `index` (`< n_runs`): the initial condition varies fastest, then `v_belt`,
    /// `mu`, `e_n`, the impact law, the IWC rule, and the seed slowest (so a sweep
    /// with one rule numbers its runs as before the rule was a dimension, and seed
    /// 0's runs are numbered as a sweep of one seed).
    pub fn run_at(&self, index: usize) -> RunKey {
        let (n_ic, n_v, n_mu, n_e) = (self.n_ics(), self.v_belt.len(), self.mu.len(), self.e_n.len());
        let n_law = self.impact_laws.len();
        let per_seed = self.runs_per_seed();
        let seed = index / per_seed;
        let index_in_seed = index % per_seed;
        let i_ic = index_in_seed % n_ic;
        let r = index_in_seed / n_ic;
        let i_v = r % n_v;
        let r = r / n_v;
        let i_mu = r % n_mu;
        let r = r / n_mu;
        let i_e = r % n_e;
        let r = r / n_e;
        let i_law = r % n_law;
        let i_iwc = r / n_law;
        RunKey {
            index,
            seed,
            iwc: self.iwc_rules[i_iwc],
            impact_law: self.impact_laws[i_law],
            e_n: self.e_n[i_e],
            i_mu,
            mu: self.mu.value(i_mu),
            i_v,
            v_belt: self.v_belt.value(i_v),
            i_ic,
        }
    }

    /// Checks ranges (axes, lists, windows, tolerances, the initial conditions'
    /// names, a closed-loop scenario present exactly when closed loop).
    ///
    /// # Errors
    /// A message naming the option.
    pub fn validate(&self) -> Result<(), String> {
        self.mu.check("mu", 10_000)?;
        self.v_belt.check("v-belt", 100_000)?;
        if self.mu.start < 0.0 {
            return Err(format!("--mu must be >= 0, got {}", self.mu.start));
        }
        if self.v_belt.start < -5.0 || self.v_belt.stop > 5.0 {
            return Err("--v-belt must lie within +-5 m/s".into());
        }
        if self.impact_laws.is_empty() || self.e_n.is_empty() || self.iwc_rules.is_empty() {
            return Err("--impact-law, --e-n and --iwc need at least one value".into());
        }
        if let Some(e) = self.e_n.iter().find(|e| !(e.is_finite() && (0.0..=1.0).contains(*e))) {
            return Err(format!("--e-n values must be in [0, 1], got {e}"));
        }
        if self.n_ics() == 0 {
            return Err("no initial conditions: give --ics or --random-ics".into());
        }
        if !(self.transient_s.is_finite() && self.transient_s >= 0.0 && self.record_s.is_finite() && self.record_s > 0.0) {
            return Err(format!("--transient must be >= 0 and --record > 0, got {} and {}", self.transient_s, self.record_s));
        }
        if self.run_duration() > 1e5 {
            return Err("--transient + --record must be at most 1e5 s".into());
        }
        if !(self.threshold.is_finite() && self.threshold >= 0.0) {
            return Err(format!("--threshold must be finite and >= 0, got {}", self.threshold));
        }
        for (name, v) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(v.is_finite() && v > 0.0 && v <= 0.1) {
                return Err(format!("--{name} must be in (0, 0.1], got {v}"));
            }
        }
        if (self.controller == SweepController::None) != self.scenario.is_none() {
            return Err("a scenario is used exactly in closed loop".into());
        }
        rig::scenario::validate_arm("plant", &Params { mu: 0.0, v_belt: 0.0, ..self.params }).map_err(|e| e.to_string())?;
        if let Some(s) = &self.scenario {
            let arm = |p: Params<f64>| Params { mu: 0.0, v_belt: 0.0, ..p };
            if arm(s.plant.params()) != arm(self.params) {
                return Err("the sweep's arm parameters differ from its scenario's [plant] section".into());
            }
        }
        if !(self.mu_hat_factor.is_finite() && (0.5..=2.0).contains(&self.mu_hat_factor)) {
            return Err(format!("mu_hat factor {} must be in [0.5, 2]", self.mu_hat_factor));
        }
        if self.ideal && self.controller == SweepController::None {
            return Err("--ideal needs --controller hybrid or pid".into());
        }
        if !(1..=ensemble::MAX_SEEDS).contains(&self.seeds) {
            return Err(format!("--seeds must be in 1..={}, got {}", ensemble::MAX_SEEDS, self.seeds));
        }
        self.jitter.check()?;
        let deterministic = self.controller == SweepController::None || self.ideal;
        if deterministic && (self.jitter.f_n_ref_n > 0.0 || self.jitter.delay_s > 0.0) {
            return Err(
                "--jitter-f-n-ref and --jitter-delay are for the sampled closed loop (--controller hybrid or pid, without --ideal)".into(),
            );
        }
        if deterministic && self.seeds > 1 && self.jitter.mu == 0.0 && self.jitter.start_m == 0.0 {
            return Err(format!(
                "--seeds {}: the {} has no noise, so its seeds differ only by their jitter: give --jitter-mu and/or --jitter-start \
                 (the resolution within which an outcome on a boundary shows, e.g. --jitter-mu 0.001 --jitter-start 1e-4)",
                self.seeds,
                if self.ideal { "ideal closed loop" } else { "open loop" }
            ));
        }
        if self.mu.start - self.jitter.mu < 0.0 {
            return Err(format!("--jitter-mu {} would take mu {} below 0", self.jitter.mu, self.mu.start));
        }
        if self.jitter.start_m > 0.0 {
            for ic in self.initial_conditions() {
                let tip = shared::kinematics::tip_position(self.params.l, &Vector2::new(ic.x0[0], ic.x0[2]));
                for sign in [-1.0, 1.0] {
                    let z = Vector2::new(tip[0] + sign * self.jitter.start_m, -self.params.h);
                    if inverse_kinematics(self.params.l, &z, ic.branch).is_err() {
                        return Err(format!(
                            "--jitter-start {} m moves {}'s tip out of the arm's reach (z_t {:.4} m)",
                            self.jitter.start_m, ic.name, z[0]
                        ));
                    }
                }
            }
        }
        if let (Some(s), false) = (&self.scenario, self.jitter.f_n_ref_n == 0.0 && self.jitter.delay_s == 0.0) {
            // The runs' scenarios at the jitter's extremes (the runaway limits off, as the runs have them).
            for sign in [-1.0, 1.0] {
                let mut t = s.clone();
                t.controller.runaway_limits = false;
                t.controller.f_n_ref += sign * self.jitter.f_n_ref_n;
                t.timing.delta_s += sign * self.jitter.delay_s;
                t.validate().map_err(|e| {
                    format!(
                        "--jitter-f-n-ref {} N / --jitter-delay {} s take the scenario out of its range: {e}",
                        self.jitter.f_n_ref_n, self.jitter.delay_s
                    )
                })?;
            }
        }
        if self.n_runs() > 50_000_000 {
            return Err(format!("{} runs: at most 5e7", self.n_runs()));
        }
        Ok(())
    }
}

fn unit() -> f64 {
    1.0
}

fn is_unit(x: &f64) -> bool {
    *x == 1.0
}

fn one() -> usize {
    1
}

fn is_one(x: &usize) -> bool {
    *x == 1
}

fn is_leave(x: &SingularRule) -> bool {
    *x == SingularRule::Leave
}

/// Default indicator threshold, rad/s. The paper flags `max theta1_dot > 0`; in
/// steady sliding the arm is at rest to rounding and `theta1_dot` sits at about
/// 5e-15 rad/s, so an exact `> 0` would flag resting arms at random.
pub const DEFAULT_THRESHOLD: f64 = 1e-6;

/// `sweep.json` names the paper's initial conditions `x0a`, `x0d`, `x0u`
/// ([`PaperX0::parse`] reads them back; an unknown name is an error).
mod ic_names {
    use plant::initial::PaperX0;
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(ics: &[PaperX0], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(ics.iter().map(|x| x.condition().name))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<PaperX0>, D::Error> {
        Vec::<String>::deserialize(d)?
            .iter()
            .map(|n| PaperX0::parse(n).ok_or_else(|| D::Error::custom(format!("unknown initial condition `{n}` (x0a, x0d or x0u)"))))
            .collect()
    }
}

#[cfg(test)]
#[path = "sweep_tests.rs"]
mod tests;
