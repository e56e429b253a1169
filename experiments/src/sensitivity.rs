//! The sensitivity study (docs/analyses.md): the paper's results under every open
//! modelling choice, run by [`analyses::sensitivity`]; the check of its base
//! scenario and threads, and its summary.

use analyses::sensitivity::Study;
use serde::Serialize;

use crate::{error::Error, settings::SensitivityArgs};

/// The keys the study varies or sets per run: `--set` of one of them is refused.
const STUDY_KEYS: [(&str, &str); 13] = [
    ("plant.impact_law", "the study (impact law)"),
    ("plant.e_n", "the study (e_n)"),
    ("plant.iwc", "the study (IWC rule)"),
    ("controller.friction", "the study (friction term)"),
    ("controller.move_time_s", "the study (move time)"),
    ("controller.mu_hat", "the study (mu_hat mismatch)"),
    ("timing.rate_hz", "the study (control rate)"),
    ("sensors.encoder_bits", "the study (encoder bits)"),
    ("sensors.load_noise_n", "the study (load-cell noise)"),
    ("plant.x0", "the study (each experiment's initial conditions)"),
    ("controller.kind", "the study (each experiment's controller)"),
    ("controller.target_z_t", "the study (Z_t,sliding's bisection)"),
    ("timing.duration_s", "the study (each experiment's windows)"),
];

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The study.
    pub study: Study,
    /// The base scenario.
    pub base_scenario: rig::scenario::Scenario,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// Worker threads.
    pub threads: usize,
    /// Files written.
    pub files: Vec<String>,
}

/// Checks `sil-host sensitivity`'s options: the base scenario (`--scenario` or
/// the embedded default, with `--set`) and the worker threads (`--threads`, one
/// per core by default).
///
/// # Errors
/// [`crate::error::Error::Analysis`] or [`crate::error::Error::Analysis`] (exit 2).
pub fn prepare(args: &SensitivityArgs) -> Result<(rig::scenario::Scenario, usize), Error> {
    rig::overrides::check_keys(&args.set, &STUDY_KEYS).map_err(rig::scenario::ScenarioError::from)?;
    crate::scenario::refuse_board_overrides(&args.set, "the sensitivity study (the firmware in-process)")?;
    let base = crate::scenario::read_scenario(args.scenario.as_deref(), &args.set)?;
    base.validate()?;
    if args.threads == Some(0) {
        return Err(Error::bad_input("--threads must be >= 1"));
    }
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    Ok((base, threads))
}
