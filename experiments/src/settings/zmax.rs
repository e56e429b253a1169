//! The arguments of `zmax` (`Z_t,sliding` by bisection).

use std::path::PathBuf;

use super::common::{OutputArgs, StrictArgs};
use super::values::NumberList;

/// `sil-host zmax`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct ZmaxArgs {
    /// Controller (ignored with --all).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "hybrid"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub controller: firmware::ControllerKind,
    /// Initial condition (ignored with --all).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "d"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub x0: plant::initial::PaperX0,
    /// The paper's ideal controllers (continuous time, exact measurements, no
    /// saturation) instead of the sampled firmware (ignored with --all).
    #[cfg_attr(feature = "clap", arg(long))]
    pub ideal: bool,
    /// All eight cases (pid/hybrid x x0d/x0u x ideal/sampled), in parallel, as a table.
    #[cfg_attr(feature = "clap", arg(long))]
    pub all: bool,
    /// Bisection tolerance on z_t*, m.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-3))]
    pub tol: f64,
    /// Targets searched, m: LO,HI. Default: from the initial tip position
    /// (z_t* = start) to 1 mm short of the end of the reachable belt.
    #[cfg_attr(feature = "clap", arg(long, value_name = "LO,HI", allow_hyphen_values = true))]
    pub bracket: Option<NumberList>,
    /// Run length of a trial, s (the move takes the scenario's move_time_s, 2 s).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 10.0))]
    pub duration: f64,
    /// Largest |z_t - z_t*| over the settle window for the tip to count as having got
    /// to the target, m: Z_t,sliding is the largest target the tip slides to, within
    /// this, with no lift-off (5 mm, the closed-loop sweep's target tolerance).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 5e-3))]
    pub reach_tol: f64,
    /// Largest |z_t - z_t*| over the settle window for the target to count as
    /// tracked, m: the tracking limit is the largest target tracked (at most --reach-tol).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1e-3))]
    pub settle_tol: f64,
    /// The last part of the run where the tip must be within --reach-tol and --settle-tol, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1.0))]
    pub settle_window: f64,
    /// Impact-without-collision rule of the base scenario (`plant.iwc`): `restitution`
    /// or `plastic`; default: the scenario's.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::option"))]
    pub iwc: Option<plant::impact::IwcRule>,
    /// Lift-off criterion, m: 0 counts any departure from the belt (located exactly);
    /// a gap > 0 counts a lift-off only when the tip rises more than this above the
    /// belt at a sample (0 to 0.1 m).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0))]
    pub lift_off_gap: f64,
    /// Base scenario of the sampled setting (rate, sensors, the arm's parameters,
    /// mu, v_belt, gains, f_n*, move time, ...); its controller, initial condition,
    /// target and run length are set per trial, and K'_I when it does not give
    /// controller.hybrid.ki (the paper's: 650 from x0d, 0 from x0u). The ideal
    /// setting takes the plant's parameters, the gains, f_n*, the move time and the
    /// plant settings from it. Default: the embedded default scenario.
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE.toml"))]
    pub scenario: Option<PathBuf>,
    /// The sampled searches over sensor-noise seeds (each seed its own bisection):
    /// `Z_t,sliding` as a distribution. --jitter-mu and --jitter-start are for sweeps.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub ensemble: super::EnsembleArgs,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Change one key of the base scenario, e.g. `--set plant.m=0.24
    /// --set controller.hybrid.kp=800 --set controller.hybrid.ki=300` (repeatable;
    /// KEY=VALUE as for `run`). The ideal and the sampled trials use the plant's
    /// parameters and the gains it gives; without `controller.hybrid.ki` K'_I is
    /// the paper's per initial condition. Refused: the keys each trial sets
    /// (controller.kind, plant.x0, controller.target_z_t, timing.duration_s).
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}
