//! A closed-loop run streamed to its output folder, as `run` and `pil` make it:
//! every period's row to `trace.csv` (and its frame and answer to `frames.csv`,
//! [`RunTables`]) as it is made, the summary's statistics and
//! the figure's decimated curves, in memory that does not grow with the run.

use std::{
    sync::atomic::{AtomicBool, Ordering},
    time::Instant,
};

use crate::{error::CliError, output::OutputSet, run_tables::RunTables};
use experiments::run_observer::{Gather, RunSink};
use figures::plot;
use figures::trace_page::{PageInfo, TracePage};
use plant::Validity;
use rig::{
    FirmwareLink,
    record::{PeriodRecord, RunError},
    setup::RunSetup,
    stats::RunStats,
    stream_loop,
};

/// Runs `setup` over `link` as `run` and `pil` do, keeping nothing that grows
/// with the run: every period's row goes to the trace of `out` in `files.format` as it
/// is made (`trace.csv.partial` or `trace.arrow.partial`, flushed every 1 ms of
/// wall time, an Arrow record batch per flush, so a plant killed outright keeps
/// every period up to the last flush), the summary's figures are
/// accumulated ([`RunStats`]) and the figure's curves decimated
/// ([`plot::HistoryEnvelope`]); the progress bar moves every `every` periods,
/// Ctrl-C or SIGTERM stops the run. Returns those, why the run stopped early if
/// it did, the loop's wall-clock time (s) and the plant's validity counters; the
/// progress bar is cleared. With `files.page` every record also goes to the run's page
/// (`trace.html`, [`figures::trace_page`]: fixed memory too, returned to be written), and to `live`
/// (`--live`: the Foxglove WebSocket server, paced) when there is one. An MCAP
/// trace carries the arm's view ([`arm_view::ArmView`]).
///
/// # Errors
/// I/O errors of the trace file.
pub fn run_streamed(
    setup: &RunSetup,
    link: &mut dyn FirmwareLink,
    out: &mut OutputSet,
    progress: &indicatif::ProgressBar,
    every: usize,
    files: TraceFiles,
    live: Option<&mut crate::live::LiveRun>,
) -> Result<Streamed, CliError> {
    let stop = crate::cancel::stop_flag();
    #[cfg(feature = "formats")]
    let view: crate::output::View<PeriodRecord> = Some(Box::new(arm_view::ArmView::of_law(
        arm_view::ArmGeometry::of(&rig::setup::plant_params(setup.scenario())),
        setup.scenario().law_in_words(),
    )));
    #[cfg(not(feature = "formats"))]
    let view = std::marker::PhantomData;
    let mut trace = RunTables::new(out, files.format, std::time::Duration::from_millis(1), view)?;
    let started = Instant::now();
    /// Streams each record and answer, summarises the records, keeps a
    /// decimated copy, moves the bar, stops on Ctrl-C; the validity, ledger and
    /// page are [`Gather`]'s.
    struct Streaming<'a> {
        trace: &'a mut RunTables,
        progress: &'a indicatif::ProgressBar,
        every: usize,
        stop: &'a AtomicBool,
        stats: RunStats,
        history: plot::HistoryEnvelope,
        live: Option<&'a mut crate::live::LiveRun>,
    }
    impl RunSink for Streaming<'_> {
        fn answer(&mut self, frame: &shared::wire::SensorFrame, truth: &shared::wire::GroundTruth, exchange: &rig::Exchange) {
            let row = rig::frames::FrameRow::of(frame, truth, exchange);
            self.trace.push_frame(&row);
            if let Some(live) = self.live.as_deref_mut() {
                live.push_frame(&row);
            }
        }

        fn record(&mut self, r: &PeriodRecord) {
            self.trace.push_record(r);
            self.stats.push(r);
            self.history.push(&plot::HistorySample {
                t: r.t,
                z_t: r.z_t,
                z_t_ref: r.z_t_ref,
                f_n: r.f_n,
                u: [r.u1_cmd, r.u2_cmd],
                mode: r.mode,
            });
            if let Some(live) = self.live.as_deref_mut() {
                live.push(r);
            }
        }

        fn period(&mut self, k: usize, _n: usize) -> bool {
            if k.is_multiple_of(self.every) {
                self.progress.set_position(k as u64);
            }
            !self.stop.load(Ordering::Relaxed)
        }
    }
    let mut observer = Gather::new(
        Streaming {
            trace: &mut trace,
            progress,
            every,
            stop: &stop,
            stats: RunStats::default(),
            history: plot::HistoryEnvelope::default(),
            live,
        },
        files.page.then(|| TracePage::new(PageInfo::closed_loop(setup.scenario(), link.transport()))),
    );
    let (_, failure) = stream_loop(setup, link, &mut observer);
    let Gather { sink: Streaming { stats, history, .. }, validity, ledger, page } = observer;
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();
    trace.finish()?;
    Ok(Streamed { stats, history, failure, wall_s, validity, ledger, page })
}

/// What [`run_streamed`] returns: nothing in it grows with the run's length.
pub struct Streamed {
    /// The summary's figures over every period, up to the failure if there was one.
    pub stats: RunStats,
    /// The figure's curves, decimated.
    pub history: plot::HistoryEnvelope,
    /// Why the run stopped early, if it did.
    pub failure: Option<RunError>,
    /// Wall-clock time of the loop, s.
    pub wall_s: f64,
    /// The plant's validity counters at the end.
    pub validity: Validity,
    /// The plant's energy ledger at the end.
    pub ledger: plant::Ledger,
    /// The run's `trace.html`, gathered (fixed memory), to be written; `None`
    /// without [`TraceFiles::page`] (`--no-page`).
    pub page: Option<TracePage>,
}

/// What [`run_streamed`] writes of the trace as the run goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TraceFiles {
    /// The trace table's format (`--format`).
    pub format: tables::TableFormat,
    /// Whether to gather `trace.html` (not `--no-page`).
    pub page: bool,
}
