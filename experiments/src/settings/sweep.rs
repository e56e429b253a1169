//! The arguments of `sweep` (the brute-force bifurcation diagram) and `merge`
//! (joining a sharded sweep's folders).

use std::path::PathBuf;

use super::common::StrictArgs;
use super::values::NumberList;

/// `sil-host sweep`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct SweepArgs {
    /// Friction coefficients: MIN,MAX (or one value), spaced by --mu-step.
    #[cfg_attr(feature = "clap", arg(long, default_value = "0.1,1", value_name = "MIN,MAX", allow_hyphen_values = true))]
    pub mu: NumberList,
    /// Spacing of --mu.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.1))]
    pub mu_step: f64,
    /// Belt speeds, m/s: MIN,MAX (or one value), spaced by --v-belt-step.
    #[cfg_attr(feature = "clap", arg(long, default_value = "-1,-0.1", value_name = "MIN,MAX", allow_hyphen_values = true))]
    pub v_belt: NumberList,
    /// Spacing of --v-belt, m/s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.005))]
    pub v_belt_step: f64,
    /// The paper's initial conditions to use (projected onto the belt at the same
    /// z_t and elbow branch): any of a, d, u, comma-separated; `none` for only random ones.
    #[cfg_attr(feature = "clap", arg(long, value_delimiter = ',', default_value = "a,d", value_name = "LIST"))]
    pub ics: Vec<String>,
    /// Random initial conditions in contact, added to --ics: the tip on the belt at
    /// z_t uniform within 90 % of the reach, a random elbow branch, at rest; the same
    /// ones at every grid point.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0, value_name = "N"))]
    pub random_ics: usize,
    /// Seed of the random initial conditions (and of the --jitter-* draws).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1))]
    pub seed: u64,
    /// Runs per grid point: the seeds and their jitter.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub ensemble: super::EnsembleArgs,
    /// Transient before the record window, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 250.0))]
    pub transient: f64,
    /// Record window, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 50.0))]
    pub record: f64,
    /// What drives the arm: `none` (open loop, u = 0; experiment 3), or the firmware's
    /// `hybrid` (experiment 7) or `pid` controller run in-process, sampled as on the
    /// MCU, with the scenario's references (experiment 6's by default).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "none"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub controller: analyses::sweep::SweepController,
    /// Closed loop: the paper's continuous-time controller with exact measurements
    /// instead of the sampled firmware.
    #[cfg_attr(feature = "clap", arg(long))]
    pub ideal: bool,
    /// Closed loop: scenario whose controller, timing and sensor sections are used
    /// (default: the embedded default, experiment 6's hybrid references). Its plant
    /// section is replaced per run (except the arm's parameters); mu_hat is set to
    /// each run's mu, and, unless it gives controller.hybrid.ki, K'_I to 0 from
    /// elbow-up initial conditions and 650 otherwise (the paper's gains).
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE.toml"))]
    pub scenario: Option<PathBuf>,
    /// Impact laws, comma-separated (each is a sweep dimension).
    #[cfg_attr(feature = "clap", arg(long, value_enum, value_delimiter = ',', default_value = "newton"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::list"))]
    pub impact_law: Vec<plant::impact::ImpactLaw>,
    /// Restitution coefficients e_n in [0, 1], comma-separated (each is a sweep dimension).
    #[cfg_attr(feature = "clap", arg(long, value_delimiter = ',', default_value = "0.2"))]
    pub e_n: Vec<f64>,
    /// Impact-without-collision rules, comma-separated (each is a sweep dimension):
    /// `restitution` (the tip is thrown off the belt), `plastic` (left stuck, v_n = 0;
    /// the rule to compare with a Moreau-Jean time-stepper such as Siconos, which
    /// leaves the tip on the belt: docs/plant.md "The impact without collision").
    #[cfg_attr(feature = "clap", arg(long, value_enum, value_delimiter = ',', default_value = "restitution"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::list"))]
    pub iwc: Vec<plant::impact::IwcRule>,
    /// Singular-point rule, where a slide reaches p = 0 and b = 0 with a finite
    /// normal force: `leave` (the tip leaves the belt) or `slide` (it slides on
    /// through the indeterminate region). docs/plant.md "The singular point".
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "leave"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub singular: plant::moreau_jean::SingularRule,
    /// Persistent bouncing is flagged when max theta1_dot over the record window
    /// exceeds this, rad/s. The paper's threshold is 0; an arm at rest shows
    /// theta1_dot ~ 5e-15 rad/s from rounding, hence the small default.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = analyses::sweep::DEFAULT_THRESHOLD))]
    pub threshold: f64,
    /// Relative tolerance of the integrator.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-9))]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-11))]
    pub atol: f64,
    /// Change one key, e.g. `--set plant.m=0.24` (repeatable; KEY=VALUE as for
    /// `run`). Open loop: only the arm's parameters (paper Table I: plant.m,
    /// plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g). Closed loop:
    /// any key of the scenario except those the sweep sets per run (plant.mu,
    /// plant.v_belt, plant.x0, plant.impact_law, plant.e_n, plant.rtol, plant.atol,
    /// controller.kind, controller.mu_hat, timing.duration_s). Part of the sweep's
    /// identity (sweep.json).
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Compute only shard K of N (0 <= K < N), for a cluster job array; join the
    /// shards' folders with `sil-host merge`. The runs are dealt to the shards so
    /// that each gets an equal share of every initial condition and `mu`
    /// (docs/analyses.md, "Cluster").
    #[cfg_attr(feature = "clap", arg(long, value_name = "K/N"))]
    pub shard: Option<String>,
    /// Compute at most N more runs, then write the outputs and stop (exit 0); run
    /// again to continue. For timing a subset, or sweeping in installments.
    #[cfg_attr(feature = "clap", arg(long, value_name = "N"))]
    pub limit: Option<usize>,
    /// Worker threads (default: all cores).
    #[cfg_attr(feature = "clap", arg(long))]
    pub threads: Option<usize>,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Folder of the sweep (created if missing; an existing sweep there is resumed).
    #[cfg_attr(feature = "clap", arg(long, default_value = "out/sweep", value_name = "DIR"))]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[cfg_attr(feature = "clap", arg(long))]
    pub json: bool,
}

/// `sil-host merge`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct MergeArgs {
    /// The shards' folders.
    #[cfg_attr(feature = "clap", arg(required = true, value_name = "DIR"))]
    pub dirs: Vec<PathBuf>,
    /// Write the outputs even if runs are missing (they are listed in the summary).
    #[cfg_attr(feature = "clap", arg(long))]
    pub allow_missing: bool,
    /// Folder of the merged sweep (a complete sweep folder, like an unsharded run's).
    #[cfg_attr(feature = "clap", arg(long, default_value = "out/sweep-merged", value_name = "DIR"))]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[cfg_attr(feature = "clap", arg(long))]
    pub json: bool,
}
