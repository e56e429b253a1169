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

use std::{
    net::SocketAddr,
    sync::{
        Arc,
        atomic::{AtomicUsize, Ordering},
    },
    time::Duration,
};

use foxglove::{
    Context, RawChannel, Schema, WebSocketServerHandle,
    websocket::{Capability, ChannelView, Client, ServerListener},
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

/// The Foxglove WebSocket server of a live run, its channels and its pace.
pub struct LiveServer {
    // Kept: the channels belong to it.
    _context: Arc<Context>,
    server: Option<WebSocketServerHandle>,
    channels: Vec<Arc<RawChannel>>,
    rate: Option<f64>,
    /// The wall clock and the simulated time of the first row.
    origin: Option<(std::time::Instant, f64)>,
    /// Subscriptions made by viewers so far.
    subscriptions: Arc<AtomicUsize>,
}

/// Counts the viewers' subscriptions ([`LiveServer::wait_for_viewer`]).
struct Subscriptions(Arc<AtomicUsize>);

impl ServerListener for Subscriptions {
    fn on_subscribe(&self, _client: Client, _channel: ChannelView) {
        self.0.fetch_add(1, Ordering::SeqCst);
    }
}

impl LiveServer {
    /// Starts the server on `addr` (port 0: any free port, [`LiveServer::addr`]
    /// tells which) with `channels`, paced at `rate` (1: real time; `None`: not
    /// paced, for a run the wall clock already paces).
    ///
    /// # Errors
    /// [`LiveError::Rate`] for a rate that is not positive and finite;
    /// [`LiveError::Start`] when the address cannot be bound;
    /// [`LiveError::Channel`] when a channel cannot be made.
    pub fn start(addr: SocketAddr, channels: &[ChannelSpec], rate: Option<f64>) -> Result<Self, LiveError> {
        if let Some(rate) = rate
            && !(rate.is_finite() && rate > 0.0)
        {
            return Err(LiveError::Rate(rate));
        }
        let context = Context::new();
        let subscriptions = Arc::new(AtomicUsize::new(0));
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
        let server = context
            .websocket_server()
            .name(concat!("painleve sil-host ", env!("CARGO_PKG_VERSION")))
            .bind(addr.ip().to_string(), addr.port())
            .capabilities([Capability::Time])
            .listener(Arc::new(Subscriptions(Arc::clone(&subscriptions))))
            .start_blocking()
            .map_err(|e| LiveError::Start { addr, what: e.to_string() })?;
        Ok(Self { _context: context, server: Some(server), channels: made, rate, origin: None, subscriptions })
    }

    /// The address the server listens on (its port the one bound).
    pub fn addr(&self, asked: SocketAddr) -> SocketAddr {
        SocketAddr::new(asked.ip(), self.server.as_ref().map_or(asked.port(), WebSocketServerHandle::port))
    }

    /// How many viewers are connected.
    pub fn viewers(&self) -> usize {
        self.server.as_ref().map_or(0, WebSocketServerHandle::client_count)
    }

    /// Waits at most `timeout` for a viewer to subscribe to a channel, then
    /// `settle` more for its other subscriptions (the Foxglove app subscribes
    /// to a layout's topics one after the other), so that the run's first
    /// messages reach it; returns early when `stop` is set. Whether a viewer came.
    pub fn wait_for_viewer(&self, timeout: Duration, settle: Duration, stop: &std::sync::atomic::AtomicBool) -> bool {
        let deadline = std::time::Instant::now() + timeout;
        while self.subscriptions.load(Ordering::SeqCst) == 0 {
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
    /// already past is not waited for) and sets the server's clock to it.
    pub fn pace(&mut self, t: f64) {
        let (wall0, t0) = *self.origin.get_or_insert((std::time::Instant::now(), t));
        let due = self.rate.map_or(0.0, |rate| (t - t0) / rate);
        if due.is_finite() && due > 0.0 {
            let elapsed = wall0.elapsed().as_secs_f64();
            if due > elapsed {
                std::thread::sleep(Duration::from_secs_f64(due - elapsed));
            }
        }
        if let Some(s) = &self.server {
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
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        if let Some(s) = self.server.take() {
            // The shutdown waits for the server's tasks; nothing to report.
            s.stop().wait_blocking();
        }
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
