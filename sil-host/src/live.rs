//! `--live [ADDR]`: a run shown live in the Foxglove app while it goes
//! ([`arm_view::LiveServer`]: the Foxglove SDK's WebSocket server, the channels
//! and bytes of `trace.mcap`, paced by `--live-rate`). `run` and `pil` show
//! their periods ([`LiveRun`]), `simulate` its samples and events
//! ([`LiveSimulation`]). The server starts before anything is written, so an
//! address in use is refused (exit 2) with nothing written; it stops when the
//! run's outputs are done.

use std::net::SocketAddr;

use arm_view::{ArmGeometry, ArmView, EventLog, LiveServer, LiveTable};
use experiments::{
    settings::LiveArgs,
    simulate::summary::{EventRow, TraceRow},
};
use rig::record::PeriodRecord;

use crate::error::CliError;

/// Starts the server of `args` (if `--live` was given) with `channels`, paced
/// at the rate (`None` when `paced_by_clock`: a `--realtime` run), says where
/// on stderr, and waits `--live-wait` for a viewer.
fn start(args: &LiveArgs, channels: &[tables::mcap::ChannelSpec], paced_by_clock: bool) -> Result<Option<LiveServer>, CliError> {
    let Some((addr, rate, wait)) = args.checked().map_err(CliError::bad_input)? else { return Ok(None) };
    if paced_by_clock && rate != 1.0 {
        return Err(CliError::bad_input(format!("--live-rate {rate}: a --realtime run is paced by the wall clock (rate 1)")));
    }
    let server = LiveServer::start(addr, channels, (!paced_by_clock).then_some(rate)).map_err(|e| CliError::bad_input(e.to_string()))?;
    let at: SocketAddr = server.addr(addr);
    eprintln!(
        "live: Foxglove WebSocket server on ws://{at} ({} simulated s per s); in the Foxglove app: Open connection > Foxglove WebSocket, layout docs/foxglove/layout.json",
        if paced_by_clock { 1.0 } else { rate }
    );
    if wait > 0.0 {
        eprintln!("live: waiting up to {wait} s for a viewer");
        let stop = crate::cancel::stop_flag();
        if !server.wait_for_viewer(std::time::Duration::from_secs_f64(wait), std::time::Duration::from_millis(500), &stop) {
            eprintln!("live: no viewer subscribed within {wait} s; the run starts");
        }
    }
    Ok(Some(server))
}

/// A closed-loop run shown live: its periods' channels and the arm's.
pub struct LiveRun {
    server: LiveServer,
    table: LiveTable<PeriodRecord>,
}

impl LiveRun {
    /// The live view of a run of `plant` (its geometry), if `args` asks for one.
    ///
    /// # Errors
    /// [`CliError`] (bad input, exit 2) for a bad rate or an address that cannot be served.
    pub fn start(args: &LiveArgs, plant: &shared::params::Params<f64>, realtime: bool) -> Result<Option<Self>, CliError> {
        if args.live.is_none() {
            return Ok(None);
        }
        let mut channels = Vec::new();
        let table = LiveTable::new(Box::new(ArmView::new(ArmGeometry::of(plant))), &mut channels)
            .map_err(|e| CliError::bad_input(e.to_string()))?;
        Ok(start(args, &channels, realtime)?.map(|server| Self { server, table }))
    }

    /// Sends period `r` when it is due.
    pub fn push(&mut self, r: &PeriodRecord) {
        self.table.push(&mut self.server, r);
    }
}

/// An open-loop simulation shown live: its samples' channels and the arm's,
/// its events' and their log.
pub struct LiveSimulation {
    server: LiveServer,
    trace: LiveTable<TraceRow>,
    events: LiveTable<EventRow>,
}

impl LiveSimulation {
    /// The live view of a simulation of `plant` (its geometry), if `args` asks for one.
    ///
    /// # Errors
    /// [`CliError`] (bad input, exit 2) for a bad rate or an address that cannot be served.
    pub fn start(args: &LiveArgs, plant: &shared::params::Params<f64>) -> Result<Option<Self>, CliError> {
        if args.live.is_none() {
            return Ok(None);
        }
        let bad = |e: arm_view::LiveError| CliError::bad_input(e.to_string());
        let mut channels = Vec::new();
        let trace = LiveTable::new(Box::new(ArmView::new(ArmGeometry::of(plant))), &mut channels).map_err(bad)?;
        let events = LiveTable::new(Box::new(EventLog::default()), &mut channels).map_err(bad)?;
        Ok(start(args, &channels, false)?.map(|server| Self { server, trace, events }))
    }

    /// Sends `rows` and `events` (each in order of time) interleaved by time,
    /// each when it is due; on a tie the sample first.
    pub fn push(&mut self, rows: &[TraceRow], events: &[EventRow]) {
        let (mut i, mut j) = (0, 0);
        while i < rows.len() || j < events.len() {
            if i == rows.len() || (j < events.len() && events[j].t < rows[i].t) {
                self.events.push(&mut self.server, &events[j]);
                j += 1;
            } else {
                self.trace.push(&mut self.server, &rows[i]);
                i += 1;
            }
        }
    }
}
