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

use std::{net::SocketAddr, sync::Arc, time::Duration};

use foxglove::{Context, RawChannel, Schema, WebSocketServerHandle, websocket::Capability};
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
    rate: f64,
    /// The wall clock and the simulated time of the first row.
    origin: Option<(std::time::Instant, f64)>,
}

impl LiveServer {
    /// Starts the server on `addr` (port 0: any free port, [`LiveServer::addr`]
    /// tells which) with `channels`, paced at `rate` (1: real time).
    ///
    /// # Errors
    /// [`LiveError::Rate`] for a rate that is not positive and finite;
    /// [`LiveError::Start`] when the address cannot be bound;
    /// [`LiveError::Channel`] when a channel cannot be made.
    pub fn start(addr: SocketAddr, channels: &[ChannelSpec], rate: f64) -> Result<Self, LiveError> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(LiveError::Rate(rate));
        }
        let context = Context::new();
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
            .start_blocking()
            .map_err(|e| LiveError::Start { addr, what: e.to_string() })?;
        Ok(Self { _context: context, server: Some(server), channels: made, rate, origin: None })
    }

    /// The address the server listens on (its port the one bound).
    pub fn addr(&self, asked: SocketAddr) -> SocketAddr {
        SocketAddr::new(asked.ip(), self.server.as_ref().map_or(asked.port(), WebSocketServerHandle::port))
    }

    /// How many viewers are connected.
    pub fn viewers(&self) -> usize {
        self.server.as_ref().map_or(0, WebSocketServerHandle::client_count)
    }

    /// Waits until the row at `t` (s) is due ([`LiveServer`]'s pacing) and
    /// sets the server's clock to it.
    pub fn pace(&mut self, t: f64) {
        let (wall0, t0) = *self.origin.get_or_insert((std::time::Instant::now(), t));
        let due = (t - t0) / self.rate;
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

/// A table's rows shown live: its own channels and its view's, row by row.
pub struct LiveTable<T: McapRows + 'static> {
    server: LiveServer,
    encoder: RowEncoder<T>,
    view: Box<dyn McapView<T>>,
    /// The index of the view's first channel.
    view_first: usize,
}

impl<T: McapRows + 'static> LiveTable<T> {
    /// Starts a server on `addr`, paced at `rate`, with `T`'s channels and `view`'s.
    ///
    /// # Errors
    /// [`LiveError`] as [`LiveServer::start`]; [`LiveError::Channel`] when
    /// `T`'s groups are inconsistent (a bug of the row type).
    pub fn start(addr: SocketAddr, rate: f64, view: Box<dyn McapView<T>>) -> Result<Self, LiveError> {
        let encoder = RowEncoder::<T>::new().map_err(|what| LiveError::Channel { topic: T::TABLE.into(), what })?;
        let mut channels = encoder.channels().to_vec();
        let view_first = channels.len();
        channels.extend(view.channels());
        let server = LiveServer::start(addr, &channels, rate)?;
        Ok(Self { server, encoder, view, view_first })
    }

    /// The server (its address, its viewers).
    pub fn server(&self) -> &LiveServer {
        &self.server
    }

    /// Waits until `row` is due and sends its messages: the table's, then the view's.
    pub fn push(&mut self, row: &T)
    where
        T: Clone,
    {
        let columns = T::columns(std::slice::from_ref(row));
        let t = self.encoder.time(&columns, 0);
        self.server.pace(t);
        let server = &self.server;
        self.encoder.encode(&columns, 0, &mut |c, bytes| server.send(c, t, bytes));
        let first = self.view_first;
        self.view.messages(row, &mut |c, bytes| server.send(first + c, t, bytes));
    }
}
