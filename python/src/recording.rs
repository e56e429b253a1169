//! What a run's `trace.mcap` is made of, kept with its `Result` so that
//! `Result.write_mcap(path)` writes the command line's bytes: the typed rows of
//! the run (a `simulate`'s samples and events with the batches the command line
//! sends them in, a closed-loop run's period records and frames) and the arm's geometry
//! for the Foxglove view (`arm_view`).

use std::path::PathBuf;

use arm_view::{ArmGeometry, ArmView, EventLog};
use experiments::simulate::summary::{EventRow, TraceRow};
use pyo3::{exceptions::PyOSError, prelude::*};
use rig::{frames::FrameRow, record::PeriodRecord};
use tables::mcap::{McapPair, McapPairStream, McapView};

/// The rows of one run, as its `trace.mcap` holds them.
enum Rows {
    /// `sil-host simulate`'s two tables: every sample and every event, and
    /// where each batch the command line writes ends (`(samples, events)`,
    /// counted from the start): the first sample with the start-up events,
    /// then one batch per chunk of the open loop.
    OpenLoop { trace: Vec<TraceRow>, events: Vec<EventRow>, batches: Vec<(usize, usize)> },
    /// `sil-host run`'s trace and frames: one record, one frame and answer per control period.
    ClosedLoop { records: Vec<PeriodRecord>, frames: Vec<FrameRow> },
}

/// A run's rows kept for its MCAP file (`painleve.Result.write_mcap`). Held in
/// the result's `extras["recording"]`; its memory is the rows' (about 0.1 KB a sample,
/// 0.2 KB a period), beside the NumPy columns.
#[pyclass(module = "painleve._painleve", name = "Recording", frozen)]
pub struct Recording {
    geometry: ArmGeometry,
    /// A closed-loop run's control law in words (`rig::scenario::Scenario::law_in_words`), for the `/log`.
    law: Option<String>,
    rows: Rows,
}

impl Recording {
    /// An open-loop run (`simulate`): its samples, events and batch ends.
    pub fn open_loop(geometry: ArmGeometry, trace: Vec<TraceRow>, events: Vec<EventRow>, batches: Vec<(usize, usize)>) -> Self {
        Self { geometry, law: None, rows: Rows::OpenLoop { trace, events, batches } }
    }

    /// A closed-loop run (`run`, `run_controller`) of the control law `law` (in
    /// words, `rig::scenario::Scenario::law_in_words`): its period records, its frames and answers.
    pub fn closed_loop(geometry: ArmGeometry, law: String, records: Vec<PeriodRecord>, frames: Vec<FrameRow>) -> Self {
        Self { geometry, law: Some(law), rows: Rows::ClosedLoop { records, frames } }
    }

    /// Writes the file at `path`, as `sil-host` writes `trace.mcap` for the same run,
    /// whole or not at all and never through a link ([`rig::private_files::write_replacing`]).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        rig::private_files::write_replacing(&path, |_, file| {
            self.write_to(path.clone(), file).map_err(|e| PyOSError::new_err(e.to_string()))
        })
    }

    /// Writes the file's bytes into `file` (`path` names it in error messages).
    fn write_to(&self, path: PathBuf, file: std::fs::File) -> Result<(), tables::Error> {
        match &self.rows {
            Rows::OpenLoop { trace, events, batches } => {
                let views = (
                    Some(Box::new(ArmView::new(self.geometry)) as Box<dyn McapView<TraceRow>>),
                    Some(Box::new(EventLog::default()) as Box<dyn McapView<EventRow>>),
                );
                let mut pair = McapPair::<TraceRow, EventRow>::new(path, file, views)?;
                let mut from = (0, 0);
                for &(rows, evs) in batches {
                    pair.send(&trace[from.0..rows], &events[from.1..evs])?;
                    from = (rows, evs);
                }
                pair.finish()
            }
            Rows::ClosedLoop { records, frames } => {
                let view = match &self.law {
                    Some(law) => ArmView::of_law(self.geometry, law.clone()),
                    None => ArmView::new(self.geometry),
                };
                let views = (Some(Box::new(view) as Box<dyn McapView<PeriodRecord>>), None);
                let mut stream = McapPairStream::<PeriodRecord, FrameRow>::new(path, file, views)?;
                // In the command line's order: a period's frame and answer, then its record.
                for k in 0..records.len().max(frames.len()) {
                    if let Some(f) = frames.get(k) {
                        stream.push_b(*f);
                    }
                    if let Some(r) = records.get(k) {
                        stream.push_a(*r)?;
                    }
                }
                stream.finish()
            }
        }
    }
}

#[pymethods]
impl Recording {
    /// Writes the run's MCAP file at `path` (a file name), the bytes `sil-host`
    /// writes as `trace.mcap` for the same run.
    ///
    /// Written whole or not at all, never through a link: a temporary file in
    /// the same folder renamed to `path`, which replaces a link there, not its
    /// target ([`rig::private_files::write_replacing`], docs/python.md).
    ///
    /// Raises:
    ///     OSError: the file cannot be created or written (its subclass by the
    ///         OS's error where the error is the OS's: `FileNotFoundError`, ...).
    fn write_mcap(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.write(path))
    }

    fn __repr__(&self) -> String {
        match &self.rows {
            Rows::OpenLoop { trace, events, .. } => format!("Recording(open loop: {} samples, {} events)", trace.len(), events.len()),
            Rows::ClosedLoop { records, .. } => format!("Recording(closed loop: {} periods)", records.len()),
        }
    }
}

/// Writes `data` as the file `path`, whole or not at all and never through a
/// link, as `sil-host` writes its outputs ([`rig::private_files::write_replacing`]:
/// a temporary file in the same folder, renamed to `path`; a link at `path` is
/// replaced, its target left as it was): `Result.write_page`, and `write_mcap`
/// of a loaded folder. The GIL is released while it writes.
///
/// # Errors
/// `OSError` (its subclass by the OS's error: `FileNotFoundError`,
/// `PermissionError`, `IsADirectoryError`, ...) naming `path`.
#[pyfunction]
pub fn write_file(py: Python<'_>, path: PathBuf, data: &[u8]) -> PyResult<()> {
    py.detach(|| {
        rig::private_files::write_replacing(&path, |_, mut file| {
            use std::io::Write;
            file.write_all(data).map_err(|e| std::io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display())))
        })
    })
    .map_err(PyErr::from)
}

/// The recording of a closed-loop run's folder (`sil-host run` or `pil` `--out`,
/// `Result.write_csv`/`write_arrow`): its period records (`trace.csv`,
/// `trace.arrow`), its frames (`frames.csv`, `frames.arrow`; none in a folder
/// written before them), the arm's geometry from `summary.json`'s `plant_params` and
/// its `law`, so that `Result.write_mcap` of a loaded CSV or Arrow folder writes the
/// bytes the command line's `--format mcap` writes for the same run.
///
/// # Errors
/// `ValueError`: no `summary.json` with `plant_params`, or no trace; a table its
/// reader refuses (naming the file, the row and the column).
#[pyfunction]
pub fn recording_of_run(py: Python<'_>, folder: PathBuf) -> PyResult<Recording> {
    use pyo3::exceptions::PyValueError;
    py.detach(|| {
        let bad = |what: String| PyValueError::new_err(format!("{}: {what}", folder.display()));
        let text = tables::input::read_to_string(&folder.join("summary.json"), tables::input::SUMMARY).map_err(|e| bad(e.to_string()))?;
        let summary: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(format!("summary.json: {e}")))?;
        let params: shared::Params<f64> =
            serde_json::from_value(summary["plant_params"].clone()).map_err(|e| bad(format!("summary.json's plant_params: {e}")))?;
        let law = summary["law"].as_str().map(String::from);
        let records = rig::frames::read_table::<PeriodRecord>(&folder, "trace").map_err(|e| bad(e.to_string()))?;
        let (_, records) = records.ok_or_else(|| bad("no trace.csv, trace.arrow or trace.mcap".into()))?;
        let frames =
            rig::frames::read_table::<FrameRow>(&folder, "frames").map_err(|e| bad(e.to_string()))?.map(|(_, f)| f).unwrap_or_default();
        let geometry = ArmGeometry::of(&params);
        Ok(Recording { geometry, law, rows: Rows::ClosedLoop { records, frames } })
    })
}
