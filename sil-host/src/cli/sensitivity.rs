//! The arguments of `sensitivity` (the headline results under each open choice).

use std::path::PathBuf;

use clap::Args;

use super::common::{OutputArgs, StrictArgs};

/// `sil-host sensitivity`.
#[derive(Debug, Clone, Args)]
pub struct SensitivityArgs {
    /// Size of the study: `quick` (coarse grids, short windows, Z_t,sliding to 4 mm)
    /// or `paper` (experiment 3's grid, 250 s + 50 s, Z_t,sliding to 1 mm).
    #[arg(long, value_enum, default_value = "quick")]
    pub size: analyses::sensitivity::Size,
    /// Base scenario (the arm's parameters, gains, f_n*, mu, v_belt for Z_t,sliding;
    /// the sampled firmware's settings); default: the embedded default scenario.
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Change one key of the base scenario (repeatable; as for `run`). Refused: the
    /// keys the study varies or sets per run.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}
