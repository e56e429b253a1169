//! The arguments of `sensitivity` (the headline results under each open choice).

use std::path::PathBuf;

use super::common::{OutputArgs, StrictArgs};

/// `sil-host sensitivity`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct SensitivityArgs {
    /// Size of the study: `quick` (coarse grids, short windows, Z_t,sliding to 4 mm)
    /// or `paper` (experiment 3's grid, 250 s + 50 s, Z_t,sliding to 1 mm).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "quick"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub size: analyses::sensitivity::Size,
    /// Base scenario (the arm's parameters, gains, f_n*, mu, v_belt for Z_t,sliding;
    /// the sampled firmware's settings); default: the embedded default scenario.
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE.toml"))]
    pub scenario: Option<PathBuf>,
    /// Change one key of the base scenario (repeatable; as for `run`). Refused: the
    /// keys the study varies or sets per run.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
    /// Worker threads (default: one per core).
    #[cfg_attr(feature = "clap", arg(long))]
    pub threads: Option<usize>,
    /// Runs per belt speed of the hybrid closed loop's sweeps: sensor-noise
    /// seeds, its rows then fractions with Wilson 95 % intervals (1: one sample).
    /// The open loop and the Z_t,sliding searches run once (`zmax --seeds` gives
    /// Z_t,sliding's spread).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1, value_name = "N"))]
    pub seeds: usize,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}
