//! The arguments of `report` (every experiment in one page).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use experiments::settings::{OutputArgs, StrictArgs};

/// How big the report's experiments are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReportSize {
    /// Coarse grids and short windows: under 2 minutes on an idle 2-core machine
    /// into a fresh `--out` folder (69 to 100 s wall), 2.5 minutes while other work loads
    /// it (141 s at a load of 5); about half when the folder holds a previous
    /// report's sweeps, which resume.
    Quick,
    /// The paper's grids and windows (hours on a 2-core machine).
    Paper,
}

/// `sil-host report`.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Size of the experiments.
    #[arg(long, value_enum, default_value = "quick")]
    pub size: ReportSize,
    /// Also write the page, stamped with date, commit and machine, to this Markdown
    /// file (the repository keeps it in docs/results.md), its figures (SVG) copied to
    /// `figures/` beside it; other files in that `figures/` are removed.
    #[arg(long, value_name = "FILE.md")]
    pub results: Option<PathBuf>,
    /// Runs per cell of the sampled closed loop's experiments (the hybrid sweep and
    /// its saturation edge, the sampled Z_t,sliding, the sensitivity study's
    /// closed-loop rows): sensor-noise seeds, each result then a fraction with its
    /// Wilson 95 % interval (the sampled loop is a random process where it
    /// saturates). 1: one sample, as a single run of each command gives.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub seeds: usize,
    /// Exit status on model violations in any experiment.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Output folder and JSON switch (`--out` defaults to `out/`; the page is `report.md` there).
    #[command(flatten)]
    pub output: OutputArgs,
}
