//! A run shown live in Foxglove: the Foxglove SDK's WebSocket server on a
//! local address, advertising the channels of `trace.mcap` (the table's own,
//! [`tables::mcap::RowEncoder`], and the view's, [`crate::ArmView`]) and
//! sending each row's messages, with the same bytes, as the run makes it.
//!
//! The run is paced: row `t` is sent no earlier than `(t - t_0) / rate` s of
//! wall time after the first row (`rate` 1: real time; 0.1: ten times slower),
//! so a viewer sees the motion at a speed it can follow; the rows themselves
//! (and the files) do not depend on the pacing or on any viewer. The server's
//! clock (`Time` capability) follows the rows' simulated time. A viewer that
//! falls behind loses messages (the SDK's bounded queue per client), the run
//! never waits for one.
//!
//! Nor does its end: [`LiveServer::close`] (and the drop) tells every viewer the
//! run is over (a status message, then the WebSocket close frame) and waits at
//! most a grace time for them to take it; a viewer that has stopped reading (its
//! connection full, the SDK's writer blocked on it for good) is then dropped: its
//! connection is cut, and the caller is told how many were.

use std::{
    net::SocketAddr,
    sync::{
        Arc,
        atomic::{AtomicBool, AtomicUsize, Ordering},
    },
    time::{Duration, Instant},
};

mod relay;

pub use relay::PUBLISHED_V1;

use foxglove::{
    Context, RawChannel, Schema, WebSocketServerHandle,
    websocket::{Capability, ChannelView, Client, ServerListener, Status},
};
use tables::mcap::{ChannelSpec, McapRows, McapView, RowEncoder, log_time_ns};

/// Why a live server could not start.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// The WebSocket server could not bind or start.
    #[error("live view: the Foxglove WebSocket server could not start on {addr}: {what}")]
    Start {
        /// The address asked for.
        addr: SocketAddr,
        /// What the SDK said.
        what: String,
    },
    /// A channel could not be made (a bug of the channel list).
    #[error("live view: channel {topic}: {what}")]
    Channel {
        /// The channel's topic.
        topic: String,
        /// What the SDK said.
        what: String,
    },
    /// The pacing rate is not a positive finite number.
    #[error("live view: the rate must be a positive number (1 is real time), not {0}")]
    Rate(f64),
}

/// The warning for a server on `at` when `at` is not a loopback address: it
/// serves the run, unauthenticated, to whoever can reach this machine on that
/// address (`0.0.0.0`, `::`: every interface). `None` for `127.0.0.0/8` and `::1`.
pub fn exposure_warning(at: SocketAddr) -> Option<String> {
    let ip = at.ip();
    (!ip.is_loopback()).then(|| {
        let which = if ip.is_unspecified() { "every network interface of this machine" } else { "the network" };
        format!(
            "live: ws://{at} serves the run to {which}, without authentication: anyone who can reach this machine there can \
             watch it; --live 127.0.0.1:PORT keeps it on this machine"
        )
    })
}

/// The Foxglove WebSocket server of a live run, its channels and its pace.
pub struct LiveServer {
    // Kept: the channels belong to it.
    _context: Arc<Context>,
    server: Option<WebSocketServerHandle>,
    /// The address viewers connect to: the published protocol's name in front of the SDK's.
    relay: relay::Relay,
    channels: Vec<Arc<RawChannel>>,
    rate: Option<f64>,
    /// The wall clock and the simulated time of the first row.
    origin: Option<(std::time::Instant, f64)>,
    /// When the server's clock was last sent ([`TIME_EVERY`]).
    last_time: Option<Instant>,
    /// The viewers' subscriptions and connections so far.
    counts: Arc<Counts>,
}

/// What the server's listener counts: the viewers' subscriptions
/// ([`LiveServer::wait_for_viewer`]), and their connections made and ended
/// ([`LiveServer::close`]: a viewer whose connection has not ended is still
/// being served).
#[derive(Default)]
struct Counts {
    subscriptions: AtomicUsize,
    connected: AtomicUsize,
    disconnected: AtomicUsize,
}

impl Counts {
    /// Viewers connected whose connection has not ended.
    fn open(&self) -> usize {
        self.connected.load(Ordering::SeqCst).saturating_sub(self.disconnected.load(Ordering::SeqCst))
    }
}

/// The server's listener: [`Counts`].
struct Listener(Arc<Counts>);

impl ServerListener for Listener {
    fn on_subscribe(&self, _client: Client, _channel: ChannelView) {
        self.0.subscriptions.fetch_add(1, Ordering::SeqCst);
    }

    fn on_client_connect(&self) {
        self.0.connected.fetch_add(1, Ordering::SeqCst);
    }

    fn on_client_disconnect(&self) {
        self.0.disconnected.fetch_add(1, Ordering::SeqCst);
    }
}

/// What closing a [`LiveServer`] did ([`LiveServer::close`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Closed {
    /// Viewers connected when the close began.
    pub viewers: usize,
    /// Of those, the viewers that had not taken the close within the grace time
    /// (or by a stop): their connections were cut.
    pub dropped: usize,
}

impl Closed {
    /// What stderr says of a close that dropped viewers after `grace` (`signalled`:
    /// cut short by Ctrl-C or SIGTERM); `None` when every viewer took it.
    pub fn note(self, signalled: bool, grace: Duration) -> Option<String> {
        (self.dropped > 0).then(|| {
            if signalled {
                return format!(
                    "live: the run was stopped by a signal: {} of {} viewer(s) cut without waiting for them to take the close",
                    self.dropped, self.viewers
                );
            }
            format!(
                "live: dropped {} of {} viewer(s) that did not take the server's close within {} s of the run's end \
                 (stopped reading: the connection full); the connection was cut",
                self.dropped,
                self.viewers,
                grace.as_secs_f64()
            )
        })
    }
}

/// The status message every viewer is sent before the close frame.
pub const CLOSING_STATUS: &str = "painleve: the run has ended; the server closes";

/// The least wall time between two of the server's clock messages (`Time`): 20 ms.
/// The SDK sends them on a viewer's control queue, which drops the viewer when full
/// (its `message_backlog_size`), where data messages only lose the oldest: one a row
/// (a thousand a simulated second) dropped a viewer that read a message a millisecond
/// within a second of a run at `--live-rate 4`. 50 a second is more than the app's
/// clock needs.
pub const TIME_EVERY: Duration = Duration::from_millis(20);

/// The time between the status message and the stop, within the grace: 50 ms.
const STATUS_PAUSE: Duration = Duration::from_millis(50);

impl LiveServer {
    /// Starts the server on `addr` (port 0: any free port, [`LiveServer::addr`]
    /// tells which) with `channels`, paced at `rate` (1: real time; `None`: not
    /// paced, for a run the wall clock already paces), with `backlog` messages
    /// queued per viewer (the SDK's `message_backlog_size`, 1024 by default: a
    /// viewer further behind loses the oldest data messages).
    ///
    /// # Errors
    /// [`LiveError::Rate`] for a rate that is not positive and finite;
    /// [`LiveError::Start`] when the address cannot be bound;
    /// [`LiveError::Channel`] when a channel cannot be made.
    pub fn start(addr: SocketAddr, channels: &[ChannelSpec], rate: Option<f64>, backlog: usize) -> Result<Self, LiveError> {
        if let Some(rate) = rate
            && !(rate.is_finite() && rate > 0.0)
        {
            return Err(LiveError::Rate(rate));
        }
        let context = Context::new();
        let counts = Arc::new(Counts::default());
        let made = channels
            .iter()
            .map(|c| {
                context
                    .channel_builder(c.topic.clone())
                    .message_encoding(c.message_encoding.clone())
                    .schema(Schema::new(c.schema_name.clone(), c.schema_encoding.clone(), c.schema.clone()))
                    .build_raw()
                    .map_err(|e| LiveError::Channel { topic: c.topic.clone(), what: e.to_string() })
            })
            .collect::<Result<Vec<_>, _>>()?;
        // The SDK's server on a loopback port of its own; viewers reach it through the
        // relay on `addr` (`relay`: `foxglove.websocket.v1` accepted as the SDK's v1).
        let server = context
            .websocket_server()
            .name(concat!("painleve sil-host ", env!("CARGO_PKG_VERSION")))
            .bind(std::net::Ipv4Addr::LOCALHOST.to_string(), 0)
            .capabilities([Capability::Time])
            .message_backlog_size(backlog)
            .listener(Arc::new(Listener(Arc::clone(&counts))))
            .start_blocking()
            .map_err(|e| LiveError::Start { addr, what: e.to_string() })?;
        let upstream = SocketAddr::from((std::net::Ipv4Addr::LOCALHOST, server.port()));
        let relay = relay::Relay::start(addr, upstream).map_err(|e| LiveError::Start { addr, what: e.to_string() })?;
        Ok(Self { _context: context, server: Some(server), relay, channels: made, rate, origin: None, last_time: None, counts })
    }

    /// The address the server listens on (its port the one bound).
    pub fn addr(&self, asked: SocketAddr) -> SocketAddr {
        SocketAddr::new(asked.ip(), self.relay.addr().port())
    }

    /// How many viewers are connected.
    pub fn viewers(&self) -> usize {
        self.server.as_ref().map_or(0, WebSocketServerHandle::client_count)
    }

    /// Waits at most `timeout` for a viewer to subscribe to a channel, then
    /// `settle` more for its other subscriptions (the Foxglove app subscribes
    /// to a layout's topics one after the other), so that the run's first
    /// messages reach it; returns early when `stop` is set. Whether a viewer came.
    pub fn wait_for_viewer(&self, timeout: Duration, settle: Duration, stop: &AtomicBool) -> bool {
        let deadline = std::time::Instant::now() + timeout;
        while self.counts.subscriptions.load(Ordering::SeqCst) == 0 {
            if std::time::Instant::now() >= deadline || stop.load(Ordering::Relaxed) {
                return false;
            }
            // Polled: the SDK calls the listener on its own runtime's thread.
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(settle);
        true
    }

    /// Waits until the row at `t` (s) is due ([`LiveServer`]'s pacing; a time
    /// already past is not waited for) and sets the server's clock to it (at most
    /// every [`TIME_EVERY`] of wall time).
    pub fn pace(&mut self, t: f64) {
        let (wall0, t0) = *self.origin.get_or_insert((std::time::Instant::now(), t));
        let due = self.rate.map_or(0.0, |rate| (t - t0) / rate);
        if due.is_finite() && due > 0.0 {
            let elapsed = wall0.elapsed().as_secs_f64();
            if due > elapsed {
                std::thread::sleep(Duration::from_secs_f64(due - elapsed));
            }
        }
        if let Some(s) = &self.server
            && self.last_time.is_none_or(|at| at.elapsed() >= TIME_EVERY)
        {
            self.last_time = Some(Instant::now());
            s.broadcast_time(log_time_ns(t));
        }
    }

    /// Sends `bytes` on channel `index` (of the list given to
    /// [`LiveServer::start`]) with log time `t` (s).
    pub fn send(&self, index: usize, t: f64, bytes: &[u8]) {
        if let Some(c) = self.channels.get(index) {
            c.log_with_meta(bytes, foxglove::PartialMetadata { log_time: Some(log_time_ns(t)) });
        }
    }

    /// Closes the server: every viewer is sent [`CLOSING_STATUS`] and, 50 ms
    /// later, the WebSocket close frame, and the server's tasks are waited for
    /// at most `grace` from the call (or until `stop` is set: a signal). A
    /// viewer that has not taken the close by then (it stopped reading: its
    /// connection is full) is dropped, its connection cut without the frame.
    /// Returns at most `grace` (plus the 20 ms of one check) after it is called.
    /// A second call does nothing.
    pub fn close(&mut self, grace: Duration, stop: &AtomicBool) -> Closed {
        let Some(server) = self.server.take() else { return Closed::default() };
        let deadline = Instant::now() + grace;
        let closed = self.close_server(server, deadline, stop);
        // The viewers' side of the relay: the close passed on, each viewer given the
        // rest of the grace to take it; one that stopped reading is cut then.
        let cut = self.relay.finish(deadline, stop);
        Closed { viewers: closed.viewers, dropped: closed.dropped.max(cut).min(closed.viewers) }
    }

    fn close_server(&mut self, server: WebSocketServerHandle, deadline: Instant, stop: &AtomicBool) -> Closed {
        let viewers = server.client_count();
        if viewers > 0 {
            server.publish_status(Status::info(CLOSING_STATUS));
            // The stop ends each viewer's writer at once, the status queued or
            // not: a moment for the writers of the viewers that read to send it
            // (microseconds; a writer blocked on a full connection never will).
            std::thread::sleep(STATUS_PAUSE.min(deadline.saturating_duration_since(Instant::now())));
        }
        let handle = server.stop();
        // The SDK's runtime runs the tasks; this one only keeps the time. Without
        // a runtime (never seen) the tasks are let go: the process's end cuts them.
        let Ok(clock) = tokio::runtime::Builder::new_current_thread().enable_time().build() else {
            handle.detach_all();
            return Closed { viewers, dropped: self.counts.open() };
        };
        let done = clock.block_on(async {
            let mut wait = std::pin::pin!(handle.wait());
            loop {
                if tokio::time::timeout(Duration::from_millis(20), &mut wait).await.is_ok() {
                    return true;
                }
                if Instant::now() >= deadline || stop.load(Ordering::Relaxed) {
                    // Dropping the wait drops the shutdown handle, which aborts
                    // the tasks still running: their connections are closed.
                    return false;
                }
            }
        });
        Closed { viewers, dropped: if done { 0 } else { self.counts.open().min(viewers) } }
    }
}

/// The grace time of a [`LiveServer`] closed by its drop (not by [`LiveServer::close`]).
pub const DROP_GRACE: Duration = Duration::from_secs(1);

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.close(DROP_GRACE, &AtomicBool::new(false));
    }
}

/// A table's rows shown live: its own channels and its view's, row by row, on
/// a [`LiveServer`] (one server may show several tables: `simulate`'s samples
/// and events).
pub struct LiveTable<T: McapRows + 'static> {
    encoder: RowEncoder<T>,
    view: Box<dyn McapView<T>>,
    /// The index of the table's first channel on the server, and of its view's.
    first: usize,
    view_first: usize,
}

impl<T: McapRows + 'static> LiveTable<T> {
    /// `T`'s table with `view`: its channels (the table's groups, then the
    /// view's) appended to `channels`, the list the server is started with.
    ///
    /// # Errors
    /// [`LiveError::Channel`] when `T`'s groups are inconsistent (a bug of the row type).
    pub fn new(view: Box<dyn McapView<T>>, channels: &mut Vec<ChannelSpec>) -> Result<Self, LiveError> {
        let encoder = RowEncoder::<T>::new().map_err(|what| LiveError::Channel { topic: T::TABLE.into(), what })?;
        let first = channels.len();
        channels.extend_from_slice(encoder.channels());
        let view_first = channels.len();
        channels.extend(view.channels());
        Ok(Self { encoder, view, first, view_first })
    }

    /// `T`'s table alone (no view of its own: the frames of a run): its channels
    /// appended to `channels`.
    ///
    /// # Errors
    /// As [`LiveTable::new`].
    pub fn without_view(channels: &mut Vec<ChannelSpec>) -> Result<Self, LiveError> {
        Self::new(Box::new(NoView), channels)
    }

    /// Waits until `row` is due on `server` and sends its messages: the table's, then the view's.
    pub fn push(&mut self, server: &mut LiveServer, row: &T)
    where
        T: Clone,
    {
        let columns = T::columns(std::slice::from_ref(row));
        let t = self.encoder.time(&columns, 0);
        server.pace(t);
        let (first, view_first) = (self.first, self.view_first);
        self.encoder.encode(&columns, 0, &mut |c, bytes| server.send(first + c, t, bytes));
        self.view.messages(row, &mut |c, bytes| server.send(view_first + c, t, bytes));
    }
}

/// The view of a table shown alone ([`LiveTable::without_view`]): no channel, no message.
struct NoView;

impl<T> McapView<T> for NoView {
    fn channels(&self) -> Vec<ChannelSpec> {
        Vec::new()
    }

    fn messages(&mut self, _row: &T, _emit: &mut dyn FnMut(usize, &[u8])) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The note names the dropped viewers, and nothing is said when none was.
    #[test]
    fn the_note_says_how_many_viewers_were_dropped() {
        let grace = Duration::from_secs(1);
        assert_eq!(Closed { viewers: 2, dropped: 0 }.note(false, grace), None);
        let note = Closed { viewers: 2, dropped: 1 }.note(false, grace).unwrap();
        assert!(note.starts_with("live: dropped 1 of 2 viewer(s)") && note.contains("within 1 s"), "{note}");
        let note = Closed { viewers: 1, dropped: 1 }.note(true, grace).unwrap();
        assert!(note.contains("stopped by a signal") && note.contains("1 of 1 viewer(s)"), "{note}");
    }

    /// Only a loopback address is served without a warning.
    #[test]
    fn a_non_loopback_address_is_warned_of() {
        for quiet in ["127.0.0.1:8765", "127.0.0.2:1", "[::1]:8765"] {
            assert_eq!(exposure_warning(quiet.parse().unwrap()), None, "{quiet}");
        }
        let every = exposure_warning("0.0.0.0:8765".parse().unwrap()).unwrap();
        assert!(every.contains("ws://0.0.0.0:8765") && every.contains("every network interface"), "{every}");
        assert!(exposure_warning("[::]:1".parse().unwrap()).unwrap().contains("every network interface"));
        let lan = exposure_warning("192.168.1.5:8765".parse().unwrap()).unwrap();
        assert!(lan.contains("to the network") && lan.contains("127.0.0.1"), "{lan}");
    }
}
