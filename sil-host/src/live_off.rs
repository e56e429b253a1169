//! `--live` in a build without the feature `live` (sil-host/Cargo.toml): the same
//! interface as the server's module (`live.rs`), whose `start` refuses `--live`
//! with the feature to build with (bad input, exit 2) and otherwise starts
//! nothing. The live types are uninhabited: no value of them is ever made.

use experiments::{
    settings::LiveArgs,
    simulate::summary::{EventRow, TraceRow},
};
use rig::record::PeriodRecord;

use crate::error::CliError;

/// `Ok(None)` without `--live`, else the error naming the feature `live`.
fn refuse(args: &LiveArgs) -> Result<(), CliError> {
    match args.live {
        None => Ok(()),
        Some(_) => Err(crate::features::missing("live", "--live")),
    }
}

/// A closing server (none in this build).
pub enum Closing {}

impl Closing {
    /// Never called: no server was started.
    pub fn finish(self) {
        match self {}
    }
}

/// A closed-loop run shown live (none in this build).
pub enum LiveRun {}

impl LiveRun {
    /// `Ok(None)` without `--live`.
    ///
    /// # Errors
    /// [`CliError::BadInput`] (exit 2) with `--live`: the feature `live` is not built.
    pub fn start(args: &LiveArgs, _scenario: &rig::scenario::Scenario, _realtime: bool) -> Result<Option<Self>, CliError> {
        refuse(args).map(|()| None)
    }

    /// Never called.
    pub fn push(&mut self, _r: &PeriodRecord) {
        match *self {}
    }

    /// Never called.
    pub fn push_frame(&mut self, _f: &rig::frames::FrameRow) {
        match *self {}
    }

    /// Never called.
    pub fn close(self) -> Closing {
        match self {}
    }
}

/// An open-loop simulation shown live (none in this build).
pub enum LiveSimulation {}

impl LiveSimulation {
    /// `Ok(None)` without `--live`.
    ///
    /// # Errors
    /// [`CliError::BadInput`] (exit 2) with `--live`: the feature `live` is not built.
    pub fn start(args: &LiveArgs, _plant: &shared::params::Params<f64>) -> Result<Option<Self>, CliError> {
        refuse(args).map(|()| None)
    }

    /// Never called.
    pub fn push(&mut self, _rows: &[TraceRow], _events: &[EventRow]) {
        match *self {}
    }

    /// Never called.
    pub fn close(self) -> Closing {
        match self {}
    }
}
