//! A recorded run, read back for a replay: the scenario as run (its
//! `summary.json`'s `scenario_used`) and every period's frame and answer (its
//! frames table, [`rig::frames::read_frames`]), each [`FrameRow`] bit for bit as
//! the run wrote it.
//!
//! Every file is read as a regular file within its bound (`tables::input`:
//! [`tables::input::SUMMARY`], [`tables::input::RECORDING`]), and a recording
//! is held to its summary and to the scenario the replay runs (issue 80): a
//! frames table with no rows, fewer or more rows than the summary's `periods`,
//! a last row cut mid-line, or frames of another rate, length or initial state
//! than the scenario's is bad input (exit 2) saying so, never "identical" nor a
//! firmware divergence.

use std::path::{Path, PathBuf};

use rig::{
    frames::{FrameRow, FramesError},
    scenario::Scenario,
    setup::RunSetup,
};

use crate::error::Error;

/// A run's folder, read.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The folder.
    pub folder: PathBuf,
    /// The scenario the run ran (after its own `--set`s).
    pub scenario: Scenario,
    /// The file the frames came from.
    pub source: PathBuf,
    /// Every period's frame and answer, in order.
    pub rows: Vec<FrameRow>,
}

/// The frames' errors as the experiments' ([`Error::BadInput`], exit 2; a
/// file its reader refuses as the table error it is).
impl From<FramesError> for Error {
    fn from(e: FramesError) -> Self {
        match e {
            FramesError::Table(e) => e.into(),
            e @ (FramesError::NotRecorded { .. } | FramesError::NotTheTable { .. } | FramesError::NotBuilt { .. }) => {
                Self::BadInput(e.to_string())
            }
        }
    }
}

impl Recording {
    /// Reads the run in folder `dir` (the `--out` folder of `sil-host run` or
    /// `pil`, or a folder `painleve`'s `Result.save` wrote).
    ///
    /// # Errors
    /// [`Error::BadInput`] (exit 2): `dir` is not a run's folder (no
    /// `summary.json`, or one without the scenario), it holds no frames (a run
    /// of a `sil-host` before replay), a file is not a regular file within its
    /// bound, a frames file is not the table (a column missing or of another
    /// kind, a value out of its wire type's range, an answer not named), holds
    /// no row, or holds another number of rows than the summary's `periods`
    /// (cut off, or another run's); the readers' own errors for a file that
    /// does not parse.
    pub fn read(dir: &Path) -> Result<Self, Error> {
        let bad = |what: String| Error::bad_input(format!("{}: {what}", dir.display()));
        if !dir.is_dir() {
            return Err(bad("no such folder (give the --out folder of a `sil-host run` or `pil`)".into()));
        }
        let summary_path = dir.join("summary.json");
        let text = match tables::input::read_to_string(&summary_path, tables::input::SUMMARY) {
            Ok(text) => text,
            Err(e) if e.is_not_found() => {
                return Err(bad("no summary.json: not the folder of a `sil-host run` or `pil`".into()));
            }
            Err(e) => return Err(e.into()),
        };
        let summary: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(format!("summary.json is not JSON ({e})")))?;
        let used = summary.get("scenario_used").ok_or_else(|| {
            bad("summary.json has no `scenario_used`: not the folder of a closed-loop run (`sil-host run` or `pil`)".into())
        })?;
        let scenario: Scenario = serde_json::from_value(used.clone())
            .map_err(|e| bad(format!("summary.json's `scenario_used` is not a scenario this sil-host reads ({e})")))?;
        let (source, rows) = rig::frames::read_frames(dir)?;
        let named = |what: String| Error::bad_input(format!("{}: {what}", source.display()));
        if rows.is_empty() {
            return Err(named(
                "no frames: a header only (the run wrote none, or the file was cut off); nothing to replay, which is not \"identical\""
                    .into(),
            ));
        }
        // The run's own count: a table cut off (a disk full, a copy stopped) or
        // another run's frames beside this summary.
        if let Some(periods) = summary.get("periods").and_then(serde_json::Value::as_u64)
            && periods != rows.len() as u64
        {
            return Err(named(format!(
                "{} rows, but the run's summary.json says it ran {periods} periods: {}",
                rows.len(),
                if (rows.len() as u64) < periods {
                    "the recording is cut off (truncated)"
                } else {
                    "the frames are not this run's (another recording beside its summary)"
                }
            )));
        }
        Ok(Self { folder: dir.to_path_buf(), scenario, source, rows })
    }

    /// Holds the recording's frames to the scenario of `setup`, the one the
    /// replay configures the firmware from (the recorded one after `--set`):
    /// the frames' spacing is its control period (`timing.rate_hz`), there are
    /// no more of them than it runs (`timing.duration_s`), and the first
    /// frame's state is its plant's initial state (`plant.x0`).
    ///
    /// # Errors
    /// [`Error::BadInput`] (exit 2) naming the setting that differs: the
    /// recording is of another scenario, which would replay as a divergence of
    /// the firmware.
    pub fn check_scenario(&self, setup: &RunSetup) -> Result<(), Error> {
        let s = setup.scenario();
        let mismatch = |what: String| {
            Error::bad_input(format!(
                "{}: the recording is not of the scenario the replay runs (`{}`, summary.json's `scenario_used` after any --set): {what}",
                self.source.display(),
                s.name
            ))
        };
        let period_us = s.timing.period().as_us();
        if let Some(w) = self.rows.windows(2).find(|w| w[1].t_us - w[0].t_us != period_us as i64) {
            let step = w[1].t_us - w[0].t_us;
            return Err(mismatch(format!(
                "timing.rate_hz: its frames are {step} us apart (period {} to {}), the scenario's control period is {period_us} us \
                 (timing.rate_hz = {})",
                w[0].seq, w[1].seq, s.timing.rate_hz
            )));
        }
        let periods = s.timing.periods();
        if self.rows.len() as u64 > periods {
            return Err(mismatch(format!(
                "timing.duration_s: it holds {} periods, the scenario runs {periods} (timing.duration_s = {})",
                self.rows.len(),
                s.timing.duration_s
            )));
        }
        let first = &self.rows[0];
        let recorded = [first.theta1, first.theta1_dot, first.theta2, first.theta2_dot];
        let initial = setup.plant().state();
        if first.seq == 0 && recorded != initial {
            return Err(mismatch(format!(
                "plant.x0: its first frame's state (theta1, theta1_dot, theta2, theta2_dot) is {recorded:?}, the scenario's initial \
                 state (plant.x0 = \"{}\") is {initial:?}",
                s.plant.x0.letter()
            )));
        }
        Ok(())
    }
}
