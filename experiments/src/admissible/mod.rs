//! The admissible configurations of the tip on the belt (docs/model.md
//! experiment 2, paper Table II), computed by [`analyses::admissible`]: the
//! settings' check, the computation and `admissible.json`'s document.

use crate::{error::Error, settings::AdmissibleArgs};
use analyses::admissible::{AdmissibleReport, compute_for};

pub mod summary;
use summary::json_report;

/// Checks the options and computes the admissible configurations (what
/// `sil-host admissible` writes), without writing anything.
///
/// # Errors
/// [`crate::error::Error::Analysis`] or [`crate::error::Error::Analysis`] (exit 2) for a bad `mu` or `--set`.
pub fn compute(args: &AdmissibleArgs) -> Result<AdmissibleReport, Error> {
    let params = crate::arm::arm_params(&args.set, "admissible", &["l", "h"], args.mu, shared::Params::<f64>::paper().v_belt)?;
    Ok(compute_for(params, analyses::admissible::SCAN_STEPS)?)
}

/// `admissible.json` (also what `--json` prints), listing `files`.
///
/// # Errors
/// [`Error::Io`] when it cannot be serialised.
pub fn document(report: &AdmissibleReport, files: &[String]) -> Result<String, Error> {
    serde_json::to_string_pretty(&json_report(report, files))
        .map_err(|e| Error::Io { path: "admissible.json".into(), source: std::io::Error::other(e) })
}
