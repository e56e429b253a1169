//! The one observer of a closed-loop run both fronts use (issue 83): what every
//! front keeps of a run (the plant's validity counters and energy ledger, the
//! run's page `trace.html` as the records and events come) in [`Gather`], and
//! what a front does with the rest (stream the trace to disk, keep the frames in
//! memory, move a progress bar, stop on Ctrl-C) in its [`RunSink`].
//!
//! `rig::run_loop`, `rig::stream_loop` and the PIL and board links call the
//! [`rig::RunObserver`] methods; [`Gather`] is that observer, so a new front or a
//! new hook changes one implementation.

use figures::trace_page::TracePage;
use rig::{Exchange, RunObserver, record::PeriodRecord};
use shared::wire::{GroundTruth, SensorFrame};

/// What a front does with a run as it goes, beyond what [`Gather`] keeps. Every
/// method defaults to doing nothing (and going on); `()` keeps nothing.
pub trait RunSink {
    /// The firmware's answer to `frame`, with the ground truth of the same
    /// instant ([`rig::RunObserver::on_answer`]): a front that keeps the frames
    /// table makes its row here (`rig::frames::FrameRow::of`).
    fn answer(&mut self, _frame: &SensorFrame, _truth: &GroundTruth, _exchange: &Exchange) {}

    /// A period's record as soon as it is made ([`rig::RunObserver::on_record`]).
    fn record(&mut self, _record: &PeriodRecord) {}

    /// After period `k` of `n`; `false` stops the run (`rig::RunError::Interrupted`).
    fn period(&mut self, _k: usize, _n: usize) -> bool {
        true
    }
}

impl RunSink for () {}

/// A sink that keeps every period's frame and answer in memory (the frames
/// table, `rig::frames::FrameRow`): a run held whole, as the Python package
/// returns it. Grows with the run (one row a period).
#[derive(Debug, Clone, Default)]
pub struct KeepFrames(pub Vec<rig::frames::FrameRow>);

impl RunSink for KeepFrames {
    fn answer(&mut self, frame: &SensorFrame, truth: &GroundTruth, exchange: &Exchange) {
        self.0.push(rig::frames::FrameRow::of(frame, truth, exchange));
    }
}

/// The observer of a closed-loop run: the validity counters and the energy
/// ledger at its end, the run's page (when one is asked for) from its records and
/// events, and the front's [`RunSink`] for the rest.
#[derive(Debug)]
pub struct Gather<S> {
    /// The front's part.
    pub sink: S,
    /// The plant's validity counters at the end of the run (also after a failure).
    pub validity: plant::Validity,
    /// The plant's energy ledger at the end of the run.
    pub ledger: plant::Ledger,
    /// The run's page (`trace.html`), gathered in memory that does not grow with
    /// the run; `None`: no page.
    pub page: Option<TracePage>,
}

impl<S: RunSink> Gather<S> {
    /// An observer that hands `sink` the records, answers and periods and, with
    /// `page`, draws the run's page.
    pub fn new(sink: S, page: Option<TracePage>) -> Self {
        Self { sink, validity: plant::Validity::default(), ledger: plant::Ledger::default(), page }
    }
}

impl<S: RunSink> RunObserver for Gather<S> {
    fn on_answer(&mut self, frame: &SensorFrame, truth: &GroundTruth, exchange: &Exchange) {
        self.sink.answer(frame, truth, exchange);
    }

    fn on_events(&mut self, events: &[plant::PlantEvent]) {
        if let Some(page) = &mut self.page {
            events.iter().for_each(|e| page.event(e.into()));
        }
    }

    fn on_record(&mut self, r: &PeriodRecord) {
        self.sink.record(r);
        if let Some(page) = &mut self.page {
            page.push(&r.into());
        }
    }

    fn on_period(&mut self, k: usize, n: usize) -> bool {
        self.sink.period(k, n)
    }

    fn on_finished(&mut self, validity: &plant::Validity) {
        self.validity = *validity;
    }

    fn on_ledger(&mut self, ledger: &plant::Ledger) {
        self.ledger = *ledger;
    }
}
