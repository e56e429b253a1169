//! How each side waits and wakes the other: an [`Inbox`] (a subscriber with its
//! wake-up listener: a bounded spin, then a blocking wait) and an [`Outbox`] (a
//! publisher with the notifier that wakes the peer or the monitors), and the
//! ports they are made of.

use std::time::{Duration, Instant};

use iceoryx2::{
    port::{listener::Listener, notifier::Notifier, publisher::Publisher, subscriber::Subscriber},
    prelude::*,
};

use super::error::{IpcError, err};
use crate::services::{EventAttributes, LINK_EVENT, QUEUE_DEPTH, Topic, open_event, open_pubsub};

pub(super) type PubSub<T> = iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>;

pub(super) fn pubsub<T: std::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<ipc::Service>,
    rig: &str,
    topic: Topic,
) -> Result<PubSub<T>, IpcError> {
    Ok(open_pubsub::<T>(node, rig, topic, &topic.needs(), "the rig")?)
}

/// A publisher that never waits for a full subscriber: on a service without safe
/// overflow it discards the sample for that subscriber (with safe overflow the
/// service overwrites the subscriber's oldest one).
pub(super) fn publisher<T: std::fmt::Debug + ZeroCopySend + 'static>(
    service: &PubSub<T>,
    topic: Topic,
) -> Result<Publisher<ipc::Service, T, ()>, IpcError> {
    service
        .publisher_builder()
        .backpressure_strategy(BackpressureStrategy::DiscardData)
        .create()
        .map_err(|e| err(&format!("publisher {}", topic.name()), e))
}

pub(super) fn subscriber<T: std::fmt::Debug + ZeroCopySend + 'static>(
    service: &PubSub<T>,
    topic: Topic,
) -> Result<Subscriber<ipc::Service, T, ()>, IpcError> {
    service.subscriber_builder().buffer_size(QUEUE_DEPTH).create().map_err(|e| err(&format!("subscriber {}", topic.name()), e))
}

pub(super) fn notifier(
    node: &Node<ipc::Service>,
    rig: &str,
    name: &str,
    attributes: &EventAttributes,
) -> Result<Notifier<ipc::Service>, IpcError> {
    open_event(node, rig, name, attributes)?.notifier_builder().create().map_err(|e| err(&format!("notifier {name}"), e))
}

pub(super) fn listener(node: &Node<ipc::Service>, rig: &str, name: &str) -> Result<Listener<ipc::Service>, IpcError> {
    open_event(node, rig, name, &LINK_EVENT)?.listener_builder().create().map_err(|e| err(&format!("listener {name}"), e))
}

/// A subscriber with its wake-up listener: bounded spin, then a blocking wait.
pub struct Inbox<T: std::fmt::Debug + ZeroCopySend + 'static> {
    pub(super) subscriber: Subscriber<ipc::Service, T, ()>,
    /// `None`: the inbox is only polled (the message always precedes another one).
    pub(super) listener: Option<Listener<ipc::Service>>,
    pub(super) spin: Duration,
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Inbox<T> {
    /// The next message, if one is queued.
    ///
    /// # Errors
    /// [`IpcError`] when receiving fails.
    pub fn try_next(&self) -> Result<Option<T>, IpcError> {
        Ok(self.subscriber.receive().map_err(|e| err("receive", e))?.map(|s| *s))
    }

    /// Waits until a message arrives or `deadline` passes: spins for the bounded
    /// spin time, then blocks on the event service. A message that is there when
    /// the deadline is found passed is returned (the caller judges lateness).
    ///
    /// # Errors
    /// [`IpcError`] when receiving or waiting fails.
    pub fn next_before(&self, deadline: Instant) -> Result<Option<T>, IpcError> {
        let start = Instant::now();
        loop {
            if let Some(v) = self.try_next()? {
                return Ok(Some(v));
            }
            let now = Instant::now();
            if now >= deadline {
                // One last look: this process may have been descheduled between the
                // poll above and the clock read, while the message arrived.
                return self.try_next();
            }
            match &self.listener {
                Some(l) if now - start >= self.spin => {
                    wait_readable(l, deadline - now)?;
                    // Consume the wake-ups that came (the messages are read above).
                    match l.try_wait(|_| {}) {
                        Ok(_) | Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => {}
                        Err(e) => return Err(err("wait", e)),
                    }
                }
                _ => std::thread::yield_now(),
            }
        }
    }
}

/// Blocks until `listener` has a wake-up to read or `timeout` passes, on the
/// listener's file descriptor with `ppoll`, whose timeout is a high-resolution
/// timer. iceoryx2's own `Listener::timed_wait` sets `SO_RCVTIMEO` on its socket,
/// which the kernel rounds up to whole scheduler ticks (4 to 8 ms measured here
/// for a 0.3 ms wait): a stalled peer in real time then cost the plant 8 ms per
/// 1 ms period (issue 15). A signal (SIGSTOP then SIGCONT: Ctrl-Z and `fg`, a
/// debugger) interrupts the wait: not an error, the caller looks again.
///
/// # Errors
/// [`IpcError`] when `ppoll` fails otherwise.
fn wait_readable(listener: &Listener<ipc::Service>, timeout: Duration) -> Result<(), IpcError> {
    // SAFETY: the descriptor is only polled, while `listener` (its owner) is borrowed.
    let fd = unsafe { listener.file_descriptor().native_handle() };
    let mut pfd = libc::pollfd { fd, events: libc::POLLIN, revents: 0 };
    let ts = libc::timespec {
        tv_sec: timeout.as_secs().min(i32::MAX as u64) as libc::time_t,
        tv_nsec: libc::c_long::from(timeout.subsec_nanos() as i32),
    };
    // SAFETY: one valid pollfd, a valid timespec, no signal mask change.
    let r = unsafe { libc::ppoll(&mut pfd, 1, &ts, std::ptr::null()) };
    if r < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(err("wait", e));
        }
    }
    Ok(())
}

/// Whom an [`Outbox`]'s notifier wakes.
pub(super) enum Wake {
    /// Nobody (the message always precedes another one that wakes).
    Nobody,
    /// The peer process: a failed notification is a transport failure.
    Peer(Notifier<ipc::Service>),
    /// Monitors: best effort (a monitor that died must not stop the run).
    Monitors(Notifier<ipc::Service>),
}

/// A publisher with the notifier that wakes its peer or its monitors.
pub struct Outbox<T: std::fmt::Debug + ZeroCopySend + 'static> {
    pub(super) publisher: Publisher<ipc::Service, T, ()>,
    pub(super) wake: Wake,
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Outbox<T> {
    /// Publishes `value` (a copy into shared memory) and wakes the peer or the
    /// monitors. On `ground_truth` with
    /// [`MonitorPolicy::lossless`](super::MonitorPolicy::lossless) this waits
    /// while a monitor's buffer is full, up to
    /// [`MonitorPolicy::timeout`](super::MonitorPolicy::timeout).
    ///
    /// # Errors
    /// [`IpcError`] when sending, or waking the peer, fails.
    pub fn send(&self, value: T) -> Result<(), IpcError> {
        self.send_counted(value).map(|_| ())
    }

    /// [`Outbox::send`], returning the number of subscribers whose buffer took
    /// the sample (iceoryx2's count of recipients: a subscriber whose full buffer
    /// discarded it is not one).
    ///
    /// # Errors
    /// As [`Outbox::send`].
    pub(super) fn send_counted(&self, value: T) -> Result<usize, IpcError> {
        let delivered = self.publisher.send_copy(value).map_err(|e| err("send", e))?;
        match &self.wake {
            Wake::Nobody => {}
            Wake::Peer(n) => {
                n.notify().map_err(|e| err("notify", e))?;
            }
            Wake::Monitors(n) => {
                let _ = n.notify();
            }
        }
        Ok(delivered)
    }
}
