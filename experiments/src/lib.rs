//! The paper's experiments as a library, under both fronts: the `sil-host`
//! command line parses its flags into these settings and prints and writes what
//! they compute; the Python package `painleve` does the same from its keyword
//! arguments and returns NumPy tables. Neither front computes anything itself.
//!
//! Per experiment (docs/model.md's numbering): its settings ([`settings`], clap
//! arguments behind the `clap` feature), its check (`prepare`, `plan`,
//! `validated`, `compute`), the loop both fronts run (one copy:
//! [`simulate::OpenLoop`], [`poincare::analyse_grid`], [`sweep::run_all`],
//! [`zmax::run_searches`]; the closed loop is [`rig::run_loop`], the study
//! [`analyses::sensitivity::run`]), its typed summary and rows. Shared: the
//! error ([`Error`], wrapping [`analyses::AnalysisError`]), the outcome
//! ([`Done`]) and the sweep's folder ([`sweep::store`]); the row types declare
//! their columns for the `tables` crate, which writes and reads the files.

#![warn(missing_docs)]

pub mod admissible;
pub mod arm;
pub mod counters;
pub mod done;
pub mod error;
pub mod firmware_process;
pub mod modes;
pub mod poincare;
pub mod replay;
pub mod run;
pub mod run_observer;
pub mod scenario;
pub mod sensitivity;
pub mod settings;
pub mod simulate;
pub mod sweep;
pub mod zmax;

pub use done::Done;
pub use error::Error;

/// The declarations of the tables the project writes as CSV (the CSV reader
/// matches a file's header against them: `painleve.read_csv`, `painleve.load`):
/// `trace.csv` and `events.csv` of `simulate`, `trace.csv` of `run` and `pil`,
/// `sweep.csv` and `runs.csv`, `section.csv`, `classes.csv`, `zmax.csv`,
/// `trials.csv`, `sensitivity.csv` and `modes.csv`. Each header names one table
/// (tested).
pub const DECLARED: &[tables::Declaration] = &[
    tables::Declaration::of::<simulate::summary::TraceRow>(),
    tables::Declaration::of::<simulate::summary::EventRow>(),
    tables::Declaration::of::<rig::record::PeriodRecord>(),
    tables::Declaration::of::<rig::frames::FrameRow>(),
    tables::Declaration::of::<analyses::sweep::run::RunRow>(),
    tables::Declaration::of::<poincare::summary::SectionRow>(),
    tables::Declaration::of::<poincare::summary::ClassRow<'static>>(),
    tables::Declaration::of::<zmax::summary::ZmaxRow>(),
    tables::Declaration::of::<zmax::summary::TrialRow<'static>>(),
    tables::Declaration::of::<analyses::sensitivity::Row>(),
    tables::Declaration::of::<modes::summary::CsvRow>(),
];

/// A rayon pool of `threads` worker threads, for an experiment's runs.
///
/// # Errors
/// [`Error`] (bad input, exit 2) when the threads cannot be started.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool, Error> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::bad_input(format!("cannot start {threads} worker threads: {e}")))
}

#[cfg(test)]
mod tests {
    /// No two tables the project writes have the same header, so a file's header
    /// names its declaration.
    #[test]
    fn each_header_names_one_declaration() {
        for (i, d) in super::DECLARED.iter().enumerate() {
            assert!(super::DECLARED[..i].iter().all(|e| e.names != d.names), "{:?}", d.names);
            assert_eq!(d.names.len(), d.kinds.len());
        }
    }
}
