//! `--live [ADDR]`: a run shown live in the Foxglove app while it goes
//! ([`arm_view::LiveServer`]: the Foxglove SDK's WebSocket server, the channels
//! and bytes of `trace.mcap`, paced by `--live-rate`). `run` and `pil` show
//! their periods ([`LiveRun`]), `simulate` its samples and events
//! ([`LiveSimulation`]). The server starts before anything is written, so an
//! address in use is refused (exit 2) with nothing written. It closes when the
//! run's last period has been sent ([`LiveRun::close`]), while the outputs are
//! written: its viewers get [`CLOSE_GRACE`] to take the close, then a viewer that
//! has stopped reading is dropped and stderr says so ([`Closing::finish`]), so a
//! viewer never holds the process past its run by more than that.
//!
//! An address that is not a loopback one (`0.0.0.0`, a LAN address) serves the
//! run to the network: stderr says so with a warning ([`arm_view::live::exposure_warning`]).

use std::{net::SocketAddr, time::Duration};

use arm_view::{ArmGeometry, ArmView, Closed, EventLog, LiveServer, LiveTable};
use experiments::{
    settings::LiveArgs,
    simulate::summary::{EventRow, TraceRow},
};
use rig::{frames::FrameRow, record::PeriodRecord};

use crate::error::CliError;

/// Starts the server of `args` (if `--live` was given) with `channels`, paced
/// at the rate (`None` when `paced_by_clock`: a `--realtime` run), says where
/// on stderr, and waits `--live-wait` for a viewer.
fn start(args: &LiveArgs, channels: &[tables::mcap::ChannelSpec], paced_by_clock: bool) -> Result<Option<LiveServer>, CliError> {
    let Some((addr, rate, wait, backlog)) = args.checked().map_err(CliError::bad_input)? else { return Ok(None) };
    if paced_by_clock && rate != 1.0 {
        return Err(CliError::bad_input(format!("--live-rate {rate}: a --realtime run is paced by the wall clock (rate 1)")));
    }
    let server =
        LiveServer::start(addr, channels, (!paced_by_clock).then_some(rate), backlog).map_err(|e| CliError::bad_input(e.to_string()))?;
    let at: SocketAddr = server.addr(addr);
    eprintln!(
        "live: Foxglove WebSocket server on ws://{at} ({} simulated s per s); in the Foxglove app: Open connection > Foxglove WebSocket, layout docs/foxglove/layout.json",
        if paced_by_clock { 1.0 } else { rate }
    );
    crate::commands::warn(arm_view::live::exposure_warning(at));
    if wait > 0.0 {
        // The signal handler first: a Ctrl-C after the line below is seen.
        let stop = crate::cancel::stop_flag();
        eprintln!("live: waiting up to {wait} s for a viewer");
        if !server.wait_for_viewer(std::time::Duration::from_secs_f64(wait), std::time::Duration::from_millis(500), &stop) {
            // Ctrl-C or SIGTERM while waiting: the run stops after its first
            // period (the loop sees the same flag after it), so it does not "start" (issue 69).
            if stop.load(std::sync::atomic::Ordering::Relaxed) {
                eprintln!(
                    "live: stopped by a signal while waiting for a viewer (none had subscribed); the run stops after its first period and writes its outputs"
                );
            } else {
                eprintln!("live: no viewer subscribed within {wait} s; the run starts");
            }
        }
    }
    Ok(Some(server))
}

/// How long the viewers get, once a run has ended, to take the server's close
/// (its status message and the WebSocket close frame) before the ones still
/// connected are dropped: 1 s.
pub const CLOSE_GRACE: Duration = Duration::from_secs(1);

/// The close of a run's live server, under way (on a thread of its own) while
/// the run's outputs are written ([`LiveRun::close`]).
pub struct Closing(Option<std::thread::JoinHandle<Closed>>);

impl Closing {
    /// Starts closing `server` ([`LiveServer::close`] with [`CLOSE_GRACE`], cut
    /// short by Ctrl-C or SIGTERM) on a thread of its own.
    fn start(mut server: LiveServer) -> Self {
        let stop = crate::cancel::stop_flag();
        let viewers = server.viewers();
        if viewers > 0 && !stop.load(std::sync::atomic::Ordering::Relaxed) {
            eprintln!("live: the run has ended; {viewers} viewer(s) get {} s to take the server's close", CLOSE_GRACE.as_secs_f64());
        }
        // If no thread can be made, the closure (and the server in it) is
        // dropped: the drop closes it with the same grace, here.
        Self(std::thread::Builder::new().name("live-close".into()).spawn(move || server.close(CLOSE_GRACE, &stop)).ok())
    }

    /// Waits for the close (at most [`CLOSE_GRACE`] after it began) and says on
    /// stderr how many viewers it dropped, if any.
    pub fn finish(mut self) {
        if let Some(closed) = self.0.take().and_then(|t| t.join().ok())
            && let Some(note) = closed.note(crate::cancel::exit_code().is_some(), CLOSE_GRACE)
        {
            eprintln!("{note}");
        }
    }
}

impl Drop for Closing {
    /// Waits for the close (an error path: nothing to say).
    fn drop(&mut self) {
        if let Some(t) = self.0.take() {
            let _ = t.join();
        }
    }
}

/// A closed-loop run shown live: its periods' channels and the arm's, and its
/// frames' (`/wire/*`), as the file has them.
pub struct LiveRun {
    server: LiveServer,
    table: LiveTable<PeriodRecord>,
    frames: LiveTable<FrameRow>,
}

impl LiveRun {
    /// The live view of a run of `scenario` (the arm's geometry; the control law its
    /// `/log` names first, as the file's), if `args` asks for one.
    ///
    /// # Errors
    /// [`CliError`] (bad input, exit 2) for a bad rate or an address that cannot be served.
    pub fn start(args: &LiveArgs, scenario: &rig::scenario::Scenario, realtime: bool) -> Result<Option<Self>, CliError> {
        if args.live.is_none() {
            return Ok(None);
        }
        let mut channels = Vec::new();
        let view = ArmView::of_law(ArmGeometry::of(&rig::setup::plant_params(scenario)), scenario.law_in_words());
        let bad = |e: arm_view::LiveError| CliError::bad_input(e.to_string());
        let table = LiveTable::new(Box::new(view), &mut channels).map_err(bad)?;
        let frames = LiveTable::without_view(&mut channels).map_err(bad)?;
        Ok(start(args, &channels, realtime)?.map(|server| Self { server, table, frames }))
    }

    /// Sends period `k`'s frame and answer (before its record, as the file orders them).
    pub fn push_frame(&mut self, f: &FrameRow) {
        self.frames.push(&mut self.server, f);
    }

    /// Sends period `r` when it is due.
    pub fn push(&mut self, r: &PeriodRecord) {
        self.table.push(&mut self.server, r);
    }

    /// The run has ended: starts closing the server ([`Closing`]).
    pub fn close(self) -> Closing {
        Closing::start(self.server)
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

    /// The simulation has ended: starts closing the server ([`Closing`]).
    pub fn close(self) -> Closing {
        Closing::start(self.server)
    }
}
