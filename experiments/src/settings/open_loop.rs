//! The arguments of the open-loop commands, on the plant alone: `simulate`,
//! `admissible`, `modes` and `poincare`.

use super::common::{LiveArgs, OutputArgs, StrictArgs};
use super::values::NumberList;

/// `sil-host simulate`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct SimulateArgs {
    /// Initial condition: one of the paper's (projected onto the belt).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "a", conflicts_with = "x0_deg"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub x0: plant::initial::PaperX0,
    /// Initial condition in degrees and degrees per second: th1,th1dot,th2,th2dot.
    /// A tip up to 1 mm inside the belt is projected onto it; deeper is an error.
    #[cfg_attr(feature = "clap", arg(long, value_name = "TH1,TH1DOT,TH2,TH2DOT", allow_hyphen_values = true))]
    pub x0_deg: Option<NumberList>,
    /// Friction coefficient mu (>= 0).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.6))]
    pub mu: f64,
    /// Belt speed v_belt, m/s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = -0.4, allow_hyphen_values = true))]
    pub v_belt: f64,
    /// Impact law at touchdown and for impacts without collision.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "newton"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub impact_law: plant::impact::ImpactLaw,
    /// Restitution coefficient e_n in [0, 1] (of the velocity for Newton, of the impulse
    /// for Poisson, of the normal work for energetic).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.2))]
    pub e_n: f64,
    /// Simulated time, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 10.0))]
    pub duration: f64,
    /// Sampling period of the trace, s (events are written at their exact times in the events table).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-3))]
    pub sample_dt: f64,
    /// Format of the trace and events tables: `csv` (trace.csv, events.csv), `arrow`
    /// (trace.arrow, events.arrow: Arrow IPC files, typed columns with the floats'
    /// bits, for pandas.read_feather, polars.read_ipc, pyarrow; painleve.load reads
    /// both) or `mcap` (trace.mcap, both tables in one file for Foxglove and ROS 2
    /// tools: channels /state, /contact, /events of protobuf messages with their schemas (FileDescriptorSets),
    /// and the arm in Foxglove's own schemas: /tf (FrameTransforms), /scene
    /// (SceneUpdate), /log (Log, the events); log times in ns of simulated time;
    /// docs/rig.md "Outputs", "Foxglove").
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "csv"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub format: tables::TableFormat,
    /// Do not write trace.html (the arm animated beside the trace's plots; docs/rig.md
    /// "The animated page"). Gathering it costs about 0.6 s of CPU per million samples
    /// (a 1000 s `run --in-process`: 4.4 s against 3.8 s; 6 MB more peak memory).
    #[cfg_attr(feature = "clap", arg(long))]
    pub no_page: bool,
    /// The simulation shown live in Foxglove (its samples and events as they are
    /// computed, paced by --live-rate).
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub live: LiveArgs,
    /// Relative tolerance of the integrator.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-9))]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-11))]
    pub atol: f64,
    /// Largest integrator step, s. `simulate`'s default is the arm's own cap (2 ms for
    /// the paper's arm, scaled by its fastest rate), whatever the sampling; a value here
    /// replaces it: larger (1e3: no cap, the tolerances alone set the steps, and `rtol`
    /// moves the path) or smaller (the accuracy contract's references; docs/architecture.md
    /// "The contract on the path"). Elsewhere the default is no cap.
    #[cfg_attr(feature = "clap", arg(long, value_name = "S"))]
    pub max_step: Option<f64>,
    /// Impact-without-collision rule: `restitution` (the law's restitution throws the
    /// tip off the belt: from x0a at v_belt = -0.5 m/s with v_n = 0.018 m/s) or
    /// `plastic` (the tip is left stuck tangentially, v_n = 0). Moreau-Jean
    /// time-steppers with Newton's law, Siconos among them, leave the tip on the belt
    /// at the impact: to compare with one, run with `--iwc plastic` (docs/plant.md
    /// "The impact without collision").
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "restitution"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub iwc: plant::impact::IwcRule,
    /// Singular-point rule, where a slide reaches p = 0 and b = 0 with a finite
    /// normal force: `leave` (the tip leaves the belt, the flight solution) or
    /// `slide` (it slides on through the indeterminate region). docs/plant.md.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "leave"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub singular: plant::moreau_jean::SingularRule,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.m=0.24 --set plant.h=0.35`: KEYS plant.m, plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g. Repeatable;
    /// the defaults are the paper's. Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}

/// `sil-host admissible`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct AdmissibleArgs {
    /// Friction coefficient mu (>= 0).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.6, allow_hyphen_values = true))]
    pub mu: f64,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.l=0.25 --set plant.h=0.35`: KEYS plant.l, plant.h. Repeatable;
    /// the defaults are the paper's. Only these change where p > 0 (m scales p; the rest do not enter it). Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}

/// `sil-host modes`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct ModesArgs {
    /// Friction coefficient mu (>= 0).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.6, allow_hyphen_values = true))]
    pub mu: f64,
    /// Belt speed v_belt, m/s (sets the sign of z_r_dot, hence which p applies).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = -0.4, allow_hyphen_values = true))]
    pub v_belt: f64,
    /// Elbow branch for theta2 (the tip is put on the belt on this branch).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "down"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub branch: shared::ElbowBranch,
    /// theta1 range in degrees: MIN,MAX.
    #[cfg_attr(feature = "clap", arg(long, default_value = "-90,90", value_name = "MIN,MAX", allow_hyphen_values = true))]
    pub theta1_deg: NumberList,
    /// theta1_dot range in rad/s: MIN,MAX.
    #[cfg_attr(feature = "clap", arg(long, default_value = "-10,10", value_name = "MIN,MAX", allow_hyphen_values = true))]
    pub theta1_dot: NumberList,
    /// Grid points along each axis.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 400))]
    pub grid: usize,
    /// Which root of cos(theta2) = H/l - cos(theta1) to use. `auto`: the one on
    /// `--branch` (minus for down, plus for up); points whose configuration is then
    /// not on `--branch` are unreachable (theta1 < -25.98 deg for down, > 25.98 deg for up).
    /// `plus`/`minus`: that root over the whole theta1 range, `--branch` ignored; the
    /// elbow branch then changes at the straight arm (`plus` holds x0a, `minus` x0u
    /// and x0d) and is written per point in modes.csv. Default `plus`: the root through
    /// the paper's x0a, which crosses the Painlevé region (paper Fig. 2).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "plus"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub theta2_sign: analyses::modes::Theta2Sign,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.m=0.24 --set plant.h=0.35`: KEYS plant.m, plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g. Repeatable;
    /// the defaults are the paper's. Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}

/// `sil-host poincare`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct PoincareArgs {
    /// Friction coefficient mu (>= 0).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.6))]
    pub mu: f64,
    /// Initial condition: one of the paper's (projected onto the belt).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "a", conflicts_with = "x0_deg"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub x0: plant::initial::PaperX0,
    /// Initial condition in degrees and degrees per second: th1,th1dot,th2,th2dot.
    #[cfg_attr(feature = "clap", arg(long, value_name = "TH1,TH1DOT,TH2,TH2DOT", allow_hyphen_values = true))]
    pub x0_deg: Option<NumberList>,
    /// Belt-speed range, m/s: MIN,MAX (both ends included), or one speed. The default covers
    /// the band where the open loop from x0a keeps bouncing at mu = 0.6 (found
    /// with this command over [-1, -0.1] in steps of 0.02, then 0.002: from about
    /// -0.864 to -0.310 m/s, with steady sliding interleaved between -0.864 and
    /// -0.782), with steady sliding at both ends.
    #[cfg_attr(feature = "clap", arg(long, default_value = "-0.90,-0.30", value_name = "MIN,MAX|V", allow_hyphen_values = true))]
    pub v_belt: NumberList,
    /// Grid step of v_belt, m/s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.002))]
    pub v_step: f64,
    /// Transient discarded before recording, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 250.0))]
    pub transient: f64,
    /// Record window, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 50.0))]
    pub record: f64,
    /// Tolerance on section points (theta1 and theta2, rad) for the period and the
    /// count of distinct points.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-4))]
    pub tol: f64,
    /// Largest period looked for.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 32))]
    pub max_period: usize,
    /// Hysteresis of the section, rad/s: an upward crossing counts only after
    /// theta1_dot went below minus this (steady sliding has theta1_dot = 0 to
    /// about 1e-11 rad/s of rounding noise, which must not count as motion).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-6))]
    pub section_depth: f64,
    /// An aperiodic motion is chaotic when its largest Lyapunov exponent per
    /// section crossing, less twice its standard error, exceeds this.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.01))]
    pub chaos_threshold: f64,
    /// Crossings averaged in the Lyapunov estimate (0: no estimate).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 200))]
    pub lyap_iterations: usize,
    /// Crossings discarded first in the Lyapunov estimate.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 20))]
    pub lyap_skip: usize,
    /// Separation of the two trajectories after each renormalisation (state norm,
    /// rad and rad/s).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-7))]
    pub lyap_d0: f64,
    /// Impact law at touchdown and for impacts without collision.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "newton"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub impact_law: plant::impact::ImpactLaw,
    /// Restitution coefficient e_n in [0, 1].
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.2))]
    pub e_n: f64,
    /// Relative tolerance of the integrator.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-9))]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-11))]
    pub atol: f64,
    /// Worker threads (default: one per core).
    #[cfg_attr(feature = "clap", arg(long))]
    pub threads: Option<usize>,
    /// Impact-without-collision rule: `restitution` (the law's restitution throws the
    /// tip off the belt: from x0a at v_belt = -0.5 m/s with v_n = 0.018 m/s) or
    /// `plastic` (the tip is left stuck tangentially, v_n = 0). Moreau-Jean
    /// time-steppers with Newton's law, Siconos among them, leave the tip on the belt
    /// at the impact: to compare with one, run with `--iwc plastic` (docs/plant.md
    /// "The impact without collision").
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "restitution"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub iwc: plant::impact::IwcRule,
    /// Singular-point rule, where a slide reaches p = 0 and b = 0 with a finite
    /// normal force: `leave` (the tip leaves the belt, the flight solution) or
    /// `slide` (it slides on through the indeterminate region). docs/plant.md.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "leave"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub singular: plant::moreau_jean::SingularRule,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.m=0.24 --set plant.h=0.35`: KEYS plant.m, plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g. Repeatable;
    /// the defaults are the paper's. Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}
