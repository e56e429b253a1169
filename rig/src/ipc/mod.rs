//! The iceoryx2 services of the rig (zero-copy shared memory between the plant
//! process and the firmware process), and how each side waits.
//!
//! Services of a rig named `R` (default `painleve-<pid>` of the plant process;
//! `--rig NAME` to attach by hand), publish-subscribe unless said:
//!
//! | service | payload (type name) | from -> to |
//! |---|---|---|
//! | `painleve/R/sensor_frames` | `painleve::SensorFrame` | plant -> firmware |
//! | `painleve/R/actuator_commands` | `painleve::ActuatorCommand` | firmware -> plant |
//! | `painleve/R/firmware_telemetry` | `painleve::FirmwareTelemetry` | firmware -> plant, monitors |
//! | `painleve/R/ground_truth` | `painleve::GroundTruth` | plant -> monitors |
//! | `painleve/R/firmware_announcement` | `painleve::FirmwareAnnouncement` | firmware -> plant (handshake) |
//! | `painleve/R/frame_ready`, `painleve/R/command_ready` | events | wake a blocked peer |
//! | `painleve/R/ground_truth`, `painleve/R/firmware_telemetry` | events | wake monitors |
//!
//! Waiting: a bounded spin on the subscriber (cheap while the peer answers within
//! microseconds), then a blocking wait on the event service (so two processes
//! never both busy-wait on a 2-core machine). Every send notifies.
//!
//! Monitors (any iceoryx2 client that subscribes to `ground_truth` or
//! `firmware_telemetry`) may start before or after the rig: the services'
//! attributes and what the rig needs of them are in [`crate::services`]. The
//! plant never waits for a monitor unless the run asks for it ([`MonitorPolicy`]);
//! the firmware never does.
//!
//! Node names are `painleve-plant-R` and `painleve-firmware-R`; each side finds
//! out whether its peer died from iceoryx2's node monitoring, and removes the
//! stale resources of dead nodes (a killed run) before it opens the services.

use std::{
    sync::{Arc, Mutex, PoisonError},
    time::{Duration, Instant},
};

use iceoryx2::{
    node::NodeView,
    port::{BackpressureAction, BackpressureInfo, listener::Listener, notifier::Notifier, publisher::Publisher, subscriber::Subscriber},
    prelude::*,
};
use shared::wire::{ActuatorCommand, FirmwareAnnouncement, FirmwareTelemetry, GroundTruth, SensorFrame};

pub use super::services::QUEUE_DEPTH;
use super::services::{Incompatible, LINK_EVENT, MONITOR_EVENT, Needs, ServiceError, Topic, open_event, open_pubsub, service_name};

/// A transport failure, with what was being done.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// iceoryx2 failed.
    #[error("iceoryx2: {0}")]
    Transport(String),
    /// A service another process created lacks what this run needs (bad set-up,
    /// not a fault of the link: the message names the attribute and the value).
    #[error(transparent)]
    Incompatible(#[from] Incompatible),
}

impl From<ServiceError> for IpcError {
    fn from(e: ServiceError) -> Self {
        match e {
            ServiceError::Incompatible(i) => Self::Incompatible(i),
            ServiceError::Other(m) => Self::Transport(m),
        }
    }
}

fn err(what: &str, e: impl std::fmt::Debug) -> IpcError {
    IpcError::Transport(format!("{what}: {e:?}"))
}

/// Which end of the link a process is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The plant (`sil-host run`).
    Plant,
    /// The firmware (`sil-host firmware`).
    Firmware,
}

impl Role {
    /// The node name of this role in rig `rig`.
    pub fn node_name(self, rig: &str) -> String {
        match self {
            Self::Plant => format!("painleve-plant-{rig}"),
            Self::Firmware => format!("painleve-firmware-{rig}"),
        }
    }
}

/// The default rig name of a plant process.
pub fn default_rig_name() -> String {
    format!("painleve-{}", std::process::id())
}

/// Checks a rig name: letters, digits, `-` and `_`, 1 to 40 characters.
///
/// # Errors
/// A message naming the bad name.
pub fn check_rig_name(rig: &str) -> Result<(), String> {
    let ok = !rig.is_empty() && rig.len() <= 40 && rig.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if ok { Ok(()) } else { Err(format!("rig name {rig:?}: use 1 to 40 letters, digits, '-' or '_'")) }
}

/// The rig reports its own errors; iceoryx2's warnings (no config file: defaults
/// used) are noise here.
fn quiet() {
    set_log_level(LogLevel::Error);
}

/// A process's iceoryx2 node, after removing the stale resources of dead nodes.
///
/// # Errors
/// [`IpcError`] when the node cannot be created.
pub fn node(role: Role, rig: &str) -> Result<Node<ipc::Service>, IpcError> {
    quiet();
    let name = NodeName::new(&role.node_name(rig)).map_err(|e| err("node name", e))?;
    let node = NodeBuilder::new()
        .name(&name)
        // The rig handles SIGINT/SIGTERM itself (it writes what it recorded).
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| err("create node", e))?;
    // A killed run leaves its node's resources behind: clean them so that they
    // never block this run's services.
    let _ = node.try_cleanup_dead_nodes();
    Ok(node)
}

/// What iceoryx2's node monitoring says about the peer of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerState {
    /// Its process runs.
    Alive,
    /// Its process died without cleaning up (killed).
    Dead,
    /// No node of that name (never started, or exited cleanly).
    Absent,
}

/// The process id of a live node `role` of rig `rig` other than this process's,
/// if there is one: the rig is then in use in that role (issue 15: one plant and
/// one firmware per rig). Two processes starting within the same instant can both
/// see it free; a rig name per run (the default) avoids that.
pub fn live_owner(role: Role, rig: &str) -> Option<i64> {
    quiet();
    let wanted = role.node_name(rig);
    let me = i64::from(std::process::id());
    let mut owner = None;
    let _ = Node::<ipc::Service>::list(Config::global_config(), |node| {
        if let NodeState::Alive(v) = &node
            && v.details().as_ref().is_some_and(|d| d.name().as_str() == wanted)
        {
            let pid = v.id().pid::<ipc::Service>().map_or(-1, |p| i64::from(p.value()));
            if pid != me {
                owner = Some(pid);
                return CallbackProgression::Stop;
            }
        }
        CallbackProgression::Continue
    });
    owner
}

/// The state of the node `role` of rig `rig`.
pub fn peer_state(role: Role, rig: &str) -> PeerState {
    quiet();
    let wanted = role.node_name(rig);
    let mut state = PeerState::Absent;
    let _ = Node::<ipc::Service>::list(Config::global_config(), |node| {
        let (details, found) = match &node {
            NodeState::Alive(v) => (v.details(), PeerState::Alive),
            NodeState::Dead(v) => (v.details(), PeerState::Dead),
            _ => return CallbackProgression::Continue,
        };
        if details.as_ref().is_some_and(|d| d.name().as_str() == wanted) {
            // An alive node of the name wins over a dead one of an earlier run.
            if found == PeerState::Alive || state == PeerState::Absent {
                state = found;
            }
        }
        CallbackProgression::Continue
    });
    state
}

fn pubsub<T: std::fmt::Debug + ZeroCopySend + 'static>(node: &Node<ipc::Service>, rig: &str, topic: Topic) -> Result<PubSub<T>, IpcError> {
    Ok(open_pubsub::<T>(node, rig, topic, &topic.needs(), "the rig")?)
}

/// A publisher that never waits for a full subscriber: on a service without safe
/// overflow it discards the sample for that subscriber (with safe overflow the
/// service overwrites the subscriber's oldest one).
fn publisher<T: std::fmt::Debug + ZeroCopySend + 'static>(
    service: &PubSub<T>,
    topic: Topic,
) -> Result<Publisher<ipc::Service, T, ()>, IpcError> {
    service
        .publisher_builder()
        .backpressure_strategy(BackpressureStrategy::DiscardData)
        .create()
        .map_err(|e| err(&format!("publisher {}", topic.name()), e))
}

fn subscriber<T: std::fmt::Debug + ZeroCopySend + 'static>(
    service: &PubSub<T>,
    topic: Topic,
) -> Result<Subscriber<ipc::Service, T, ()>, IpcError> {
    service.subscriber_builder().buffer_size(QUEUE_DEPTH).create().map_err(|e| err(&format!("subscriber {}", topic.name()), e))
}

fn notifier(
    node: &Node<ipc::Service>,
    rig: &str,
    name: &str,
    attributes: &super::services::EventAttributes,
) -> Result<Notifier<ipc::Service>, IpcError> {
    open_event(node, rig, name, attributes)?.notifier_builder().create().map_err(|e| err(&format!("notifier {name}"), e))
}

fn listener(node: &Node<ipc::Service>, rig: &str, name: &str) -> Result<Listener<ipc::Service>, IpcError> {
    open_event(node, rig, name, &LINK_EVENT)?.listener_builder().create().map_err(|e| err(&format!("listener {name}"), e))
}

/// A subscriber with its wake-up listener: bounded spin, then a blocking wait.
pub struct Inbox<T: std::fmt::Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<ipc::Service, T, ()>,
    /// `None`: the inbox is only polled (the message always precedes another one).
    listener: Option<Listener<ipc::Service>>,
    spin: Duration,
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
enum Wake {
    /// Nobody (the message always precedes another one that wakes).
    Nobody,
    /// The peer process: a failed notification is a transport failure.
    Peer(Notifier<ipc::Service>),
    /// Monitors: best effort (a monitor that died must not stop the run).
    Monitors(Notifier<ipc::Service>),
}

/// A publisher with the notifier that wakes its peer or its monitors.
pub struct Outbox<T: std::fmt::Debug + ZeroCopySend + 'static> {
    publisher: Publisher<ipc::Service, T, ()>,
    wake: Wake,
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Outbox<T> {
    /// Publishes `value` (a copy into shared memory) and wakes the peer or the
    /// monitors. On `ground_truth` with [`MonitorPolicy::lossless`] this waits
    /// while a monitor's buffer is full, up to [`MonitorPolicy::timeout`].
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
    fn send_counted(&self, value: T) -> Result<usize, IpcError> {
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

/// What the plant does for monitors, the subscribers of `ground_truth`
/// (`sil-host run --monitors N`; docs/rig.md, "Monitors").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MonitorPolicy {
    /// Monitors to wait for before period 0 (up to `rig.connect_timeout_s`).
    pub wait_for: usize,
    /// Lockstep: a sample that finds a monitor's buffer full waits for room
    /// instead of being discarded for that monitor, so a monitor receives every
    /// sample; the run goes at the pace of the slowest monitor.
    pub lossless: bool,
    /// How long one sample waits for a full monitor before that monitor is given
    /// up (never waited for again: it then loses what finds its buffer full).
    pub timeout: Duration,
}

impl Default for MonitorPolicy {
    /// No monitor waited for, none ever waits the plant, 2 s.
    fn default() -> Self {
        Self { wait_for: 0, lossless: false, timeout: Duration::from_secs(2) }
    }
}

/// What monitors cost the run so far.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MonitorCounts {
    /// Monitors given up ([`MonitorPolicy::lossless`] only): a sample waited
    /// [`MonitorPolicy::timeout`] for room in their buffer (dead, stopped, or too
    /// slow), or found the buffer of a monitor not yet connected to the plant's
    /// publisher full (see [`PlantPorts::publish_truth`]).
    pub given_up: u32,
    /// Samples a subscribed monitor did not receive (one per monitor per
    /// sample): discarded for a given-up monitor, or (real time) for a monitor
    /// whose buffer was full. Exact when `ground_truth` has no safe overflow, as
    /// the rig creates it; with safe overflow (a service a monitor created with
    /// iceoryx2's defaults) the oldest queued sample is replaced unseen, which no
    /// count can know.
    pub samples_dropped: u64,
}

#[derive(Debug, Default)]
struct MonitorState {
    given_up_ports: Vec<u128>,
    /// The most subscribers found unreached by one sample so far: monitors that
    /// subscribed before the plant's publisher existed and have not received since.
    unreached_max: usize,
    counts: MonitorCounts,
}

/// The `ground_truth` publisher of a lossless run: iceoryx2 retries a full
/// subscriber (yielding, then sleeping) and asks this handler each time whether
/// to go on; past the timeout the monitor is given up, and from then on a sample
/// that finds its buffer full is discarded for it at once.
fn lossless_publisher(
    service: &PubSub<GroundTruth>,
    full_name: String,
    timeout: Duration,
    state: Arc<Mutex<MonitorState>>,
) -> Result<Publisher<ipc::Service, GroundTruth, ()>, IpcError> {
    service
        .publisher_builder()
        .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
        .set_backpressure_handler(move |info: &BackpressureInfo| {
            let mut st = state.lock().unwrap_or_else(PoisonError::into_inner);
            if st.given_up_ports.contains(&info.receiver_port_id) {
                st.counts.samples_dropped += 1;
                return BackpressureAction::DiscardData;
            }
            if info.elapsed_time < timeout {
                return BackpressureAction::Retry;
            }
            st.given_up_ports.push(info.receiver_port_id);
            st.counts.given_up += 1;
            st.counts.samples_dropped += 1;
            eprintln!(
                "rig: a monitor of {full_name} took no sample for {} s with its buffer full (dead, stopped or too slow): \
                 it is no longer waited for, and loses the samples that find its buffer full",
                timeout.as_secs_f64()
            );
            BackpressureAction::DiscardData
        })
        .create()
        .map_err(|e| err("publisher ground_truth", e))
}

type PubSub<T> = iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>;

/// The plant process's ports.
pub struct PlantPorts {
    /// Its node (kept alive while the ports are).
    pub node: Node<ipc::Service>,
    frames_service: PubSub<SensorFrame>,
    commands_service: PubSub<ActuatorCommand>,
    /// Sensor frames to the firmware.
    pub frames: Outbox<SensorFrame>,
    /// Ground truth to monitors.
    pub truth: Outbox<GroundTruth>,
    /// Commands from the firmware.
    pub commands: Inbox<ActuatorCommand>,
    /// Telemetry from the firmware.
    pub telemetry: Inbox<FirmwareTelemetry>,
    /// The firmware's announcement (the handshake before period 0).
    pub announcements: Inbox<FirmwareAnnouncement>,
    truth_service: PubSub<GroundTruth>,
    /// `ground_truth` keeps a history for late subscribers (set by whichever
    /// process created the service): every sample is then published.
    truth_history: bool,
    /// Kept open so that the event exists as long as the service does.
    _telemetry_event: iceoryx2::service::port_factory::event::PortFactory<ipc::Service>,
    monitors: Arc<Mutex<MonitorState>>,
    /// [`MonitorPolicy::lossless`].
    lossless: bool,
    /// `ground_truth`'s full service name, for messages.
    truth_name: String,
}

impl PlantPorts {
    /// Opens (or creates) the rig's services for the plant; `spin` is the bounded
    /// spin; `monitors` says what a full monitor costs.
    ///
    /// # Errors
    /// [`IpcError::Incompatible`] when a service another process created lacks
    /// what the plant needs (with `monitors.lossless`: `ground_truth` without safe
    /// overflow); [`IpcError::Transport`] when a node, service or port cannot be
    /// created.
    pub fn open(rig: &str, spin: Duration, monitors: &MonitorPolicy) -> Result<Self, IpcError> {
        let node = node(Role::Plant, rig)?;
        let frames_service = pubsub::<SensorFrame>(&node, rig, Topic::SensorFrames)?;
        let commands_service = pubsub::<ActuatorCommand>(&node, rig, Topic::ActuatorCommands)?;
        // The telemetry's wake-up event before its service (the firmware notifies it):
        // a monitor that finds the service finds the event too.
        let telemetry_event = open_event(&node, rig, Topic::FirmwareTelemetry.name(), &MONITOR_EVENT)?;
        let telemetry_service = pubsub::<FirmwareTelemetry>(&node, rig, Topic::FirmwareTelemetry)?;
        let announcement_service = pubsub::<FirmwareAnnouncement>(&node, rig, Topic::FirmwareAnnouncement)?;
        let truth_needs = Needs {
            no_safe_overflow: monitors.lossless,
            min_subscribers: monitors.wait_for,
            min_nodes: monitors.wait_for + 1,
            ..Topic::GroundTruth.needs()
        };
        let who = if monitors.lossless { "`run --monitors` in lockstep" } else { "`run --monitors`" };
        let truth_service = open_pubsub::<GroundTruth>(&node, rig, Topic::GroundTruth, &truth_needs, who)?;
        let state = Arc::new(Mutex::new(MonitorState::default()));
        let truth_publisher = if monitors.lossless {
            lossless_publisher(&truth_service, service_name(rig, Topic::GroundTruth.name()), monitors.timeout, Arc::clone(&state))?
        } else {
            publisher(&truth_service, Topic::GroundTruth)?
        };
        // The event last, after the publisher: a monitor that waits for the event
        // before it subscribes (docs/rig.md, "Monitors") subscribes to a service
        // whose publisher exists, and is connected to it at once. One that
        // subscribed earlier is connected only by its next `receive` (iceoryx2), and
        // may lose what finds its buffer full until then ([`Self::publish_truth`]).
        let truth_wake = Wake::Monitors(notifier(&node, rig, Topic::GroundTruth.name(), &MONITOR_EVENT)?);
        Ok(Self {
            frames: Outbox {
                publisher: publisher(&frames_service, Topic::SensorFrames)?,
                wake: Wake::Peer(notifier(&node, rig, "frame_ready", &LINK_EVENT)?),
            },
            truth: Outbox { publisher: truth_publisher, wake: truth_wake },
            commands: Inbox {
                subscriber: subscriber(&commands_service, Topic::ActuatorCommands)?,
                listener: Some(listener(&node, rig, "command_ready")?),
                spin,
            },
            telemetry: Inbox { subscriber: subscriber(&telemetry_service, Topic::FirmwareTelemetry)?, listener: None, spin },
            announcements: Inbox { subscriber: subscriber(&announcement_service, Topic::FirmwareAnnouncement)?, listener: None, spin },
            frames_service,
            commands_service,
            truth_history: truth_service.static_config().history_size() > 0,
            truth_service,
            _telemetry_event: telemetry_event,
            monitors: state,
            lossless: monitors.lossless,
            truth_name: service_name(rig, Topic::GroundTruth.name()),
            node,
        })
    }

    /// Publishes a ground-truth sample to the monitors and wakes them
    /// ([`Outbox::send`]), unless none is subscribed and the service keeps no
    /// history: then nobody could ever receive it, and the loan, copy and
    /// notification (about 1700 instructions, a tenth of a lockstep period's
    /// plant side) are skipped. A monitor that subscribes later gets the samples
    /// from then on, as it would anyway.
    ///
    /// # Errors
    /// As [`Outbox::send`].
    ///
    /// Every subscriber the sample did not reach is counted in
    /// [`MonitorCounts::samples_dropped`]. Besides a given-up monitor (counted by
    /// the lossless publisher's handler) and, in real time, a full buffer, that is
    /// a monitor that subscribed in the instant between the rig's creating the
    /// service and its publisher, and has not called `receive` since: iceoryx2
    /// connects a subscriber to a publisher that appeared later only in its next
    /// `receive`, and discards for an unconnected subscriber whose buffer is full
    /// at once, without asking the lossless handler. Such a monitor, when
    /// [`MonitorPolicy::lossless`], is given up at once: it has taken no sample
    /// since it subscribed, and the plant cannot wait for it.
    pub fn publish_truth(&self, truth: GroundTruth) -> Result<(), IpcError> {
        let subscribers = self.truth_service.dynamic_config().number_of_subscribers();
        if !self.truth_history && subscribers == 0 {
            return Ok(());
        }
        let handled_before = self.monitor_counts().samples_dropped;
        let delivered = self.truth.send_counted(truth)?;
        // A subscriber that left during the send must not count as unreached (one
        // that came during it may have been reached or not: not counted either).
        let subscribers = subscribers.min(self.truth_service.dynamic_config().number_of_subscribers());
        let mut st = self.monitors.lock().unwrap_or_else(PoisonError::into_inner);
        let discarded_by_handler = usize::try_from(st.counts.samples_dropped - handled_before).unwrap_or(usize::MAX);
        let unreached = subscribers.saturating_sub(delivered.saturating_add(discarded_by_handler));
        if unreached > 0 {
            st.counts.samples_dropped += unreached as u64;
            if self.lossless && unreached > st.unreached_max {
                let new = unreached - st.unreached_max;
                st.unreached_max = unreached;
                st.counts.given_up += u32::try_from(new).unwrap_or(u32::MAX);
                eprintln!(
                    "rig: {new} monitor(s) of {} subscribed before the plant's publisher existed and have taken no sample \
                     since, and their buffer is full: they are no longer waited for, and lose the samples that find \
                     their buffer full",
                    self.truth_name
                );
            }
        }
        Ok(())
    }

    /// Monitors subscribed to `ground_truth` now.
    pub fn monitors(&self) -> usize {
        self.truth_service.dynamic_config().number_of_subscribers()
    }

    /// What monitors cost the run so far.
    pub fn monitor_counts(&self) -> MonitorCounts {
        self.monitors.lock().unwrap_or_else(PoisonError::into_inner).counts.clone()
    }

    /// Whether a firmware is connected: it subscribes to the frames and publishes commands.
    pub fn firmware_connected(&self) -> bool {
        self.frames_service.dynamic_config().number_of_subscribers() >= 1
            && self.commands_service.dynamic_config().number_of_publishers() >= 1
    }
}

/// The firmware process's ports.
pub struct FirmwarePorts {
    /// Its node.
    pub node: Node<ipc::Service>,
    /// Frames from the plant.
    pub frames: Inbox<SensorFrame>,
    /// Commands to the plant.
    pub commands: Outbox<ActuatorCommand>,
    /// Telemetry to the plant and monitors.
    pub telemetry: Outbox<FirmwareTelemetry>,
    /// Its announcement, sent when the plant's handshake frame arrives.
    pub announcement: Outbox<FirmwareAnnouncement>,
}

impl FirmwarePorts {
    /// Opens (or creates) the rig's services for the firmware.
    ///
    /// # Errors
    /// [`IpcError::Incompatible`] when a service another process created lacks
    /// what the firmware needs; [`IpcError::Transport`] when a node, service or
    /// port cannot be created.
    pub fn open(rig: &str, spin: Duration) -> Result<Self, IpcError> {
        let node = node(Role::Firmware, rig)?;
        let telemetry_wake = Wake::Monitors(notifier(&node, rig, Topic::FirmwareTelemetry.name(), &MONITOR_EVENT)?);
        let frames_service = pubsub::<SensorFrame>(&node, rig, Topic::SensorFrames)?;
        let commands_service = pubsub::<ActuatorCommand>(&node, rig, Topic::ActuatorCommands)?;
        let telemetry_service = pubsub::<FirmwareTelemetry>(&node, rig, Topic::FirmwareTelemetry)?;
        let announcement_service = pubsub::<FirmwareAnnouncement>(&node, rig, Topic::FirmwareAnnouncement)?;
        Ok(Self {
            frames: Inbox {
                subscriber: subscriber(&frames_service, Topic::SensorFrames)?,
                listener: Some(listener(&node, rig, "frame_ready")?),
                spin,
            },
            commands: Outbox {
                publisher: publisher(&commands_service, Topic::ActuatorCommands)?,
                wake: Wake::Peer(notifier(&node, rig, "command_ready", &LINK_EVENT)?),
            },
            telemetry: Outbox { publisher: publisher(&telemetry_service, Topic::FirmwareTelemetry)?, wake: telemetry_wake },
            announcement: Outbox { publisher: publisher(&announcement_service, Topic::FirmwareAnnouncement)?, wake: Wake::Nobody },
            node,
        })
    }
}
