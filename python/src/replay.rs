//! `painleve.replay`: `sil-host replay DIR --link in-process` (docs/rig.md
//! "Replay"): a recorded run's frames through the firmware step linked into
//! this process, every answer compared with the recorded one bit for bit. The
//! reading, the comparison and the verdict are the command line's own
//! ([`experiments::replay`]); the other links (iceoryx2, the board twin, the
//! emulated board, PIL) are the command line's, which spawns or loads them.

use std::{path::PathBuf, time::Instant};

use pyo3::{prelude::*, types::PyDict};

use experiments::{
    Error as CliError,
    replay::{Recording, ReplaySummary},
};
use rig::{FaultPlan, FirmwareLink, in_process::InProcessLink, overrides::Override};

use crate::cli::cli_error;
use crate::convert::{Outcome, to_py};
use crate::work::{self, Control};

/// `painleve.replay`: the run in `folder` replayed in-process with the
/// overrides `set` (`KEY=VALUE`), every period compared with `all`.
///
/// # Errors
/// `PainleveError` (exit code 2) for a folder that is not a run's, a recording
/// of another scenario, a bad override or a link other than `in-process`
/// (naming the command that has it); a divergence is the result's `failure`
/// (exit code 1), not an error.
#[pyfunction]
#[pyo3(signature = (folder, set, all, link, progress=None))]
pub fn replay<'py>(
    py: Python<'py>,
    folder: PathBuf,
    set: Vec<String>,
    all: bool,
    link: String,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let fail = |e: CliError| cli_error(py, &e);
    if link != "in-process" {
        return Err(fail(CliError::bad_input(format!(
            "link `{link}`: painleve replays in-process only; the command line's `sil-host replay` replays over the {link} link"
        ))));
    }
    let overrides: Vec<Override> = set
        .iter()
        .map(|s| s.parse::<Override>().map_err(|e| CliError::bad_input(format!("set `{s}`: {e}"))))
        .collect::<Result<_, _>>()
        .map_err(fail)?;
    let rec = Recording::read(&folder).map_err(fail)?;
    let scenario = rec.scenario.with_overrides(&overrides).map_err(|e| fail(e.into()))?;
    let setup = experiments::run::setup(scenario).map_err(fail)?;
    rec.check_scenario(&setup).map_err(fail)?;
    let started = Instant::now();
    let mut link = InProcessLink::new(&setup).map_err(|e| fail(CliError::from(e)))?;
    let transport = link.transport().to_string();
    let plan = FaultPlan::new(&setup.scenario().faults, setup.scenario().timing.period());
    let (rec_ref, link_ref, plan_ref) = (&rec, &mut link, &plan);
    let comparison = work::run(py, progress.as_ref(), "replay", "periods", move |c: &Control| {
        let n = rec_ref.rows.len() as u64;
        experiments::replay::replay(rec_ref, link_ref, plan_ref, all, &mut |_| {}, &mut |done| {
            if done.is_multiple_of(100) {
                c.set(done as u64, n);
            }
            !c.stopped()
        })
    })?;
    let (summary, failure) = ReplaySummary::of(&rec, comparison, set, transport, started.elapsed().as_secs_f64());
    let (message, code) = match failure {
        Some(e) => (Some(e.to_string()), e.exit_code()),
        None => (None, 0),
    };
    Outcome::new(py, "replay", to_py(py, &summary)?)?.failure(message, code).map(Outcome::done)
}
