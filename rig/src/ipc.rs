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
//!
//! Waiting: a bounded spin on the subscriber (cheap while the peer answers within
//! microseconds), then a blocking wait on the event service (so two processes
//! never both busy-wait on a 2-core machine). Every send notifies.
//!
//! Node names are `painleve-plant-R` and `painleve-firmware-R`; each side finds
//! out whether its peer died from iceoryx2's node monitoring, and removes the
//! stale resources of dead nodes (a killed run) before it opens the services.

use std::time::{Duration, Instant};

use iceoryx2::{
    node::NodeView,
    port::{listener::Listener, notifier::Notifier, publisher::Publisher, subscriber::Subscriber},
    prelude::*,
};
use shared::wire::{ActuatorCommand, FirmwareAnnouncement, FirmwareTelemetry, GroundTruth, SensorFrame};

/// Queue depth of every subscriber: a peer that stalls for this many periods
/// finds them all on waking (older ones are overwritten: safe overflow).
pub const QUEUE_DEPTH: usize = 64;

/// A transport failure, with what was being done.
#[derive(Debug, thiserror::Error)]
#[error("iceoryx2: {0}")]
pub struct IpcError(pub String);

fn err(what: &str, e: impl std::fmt::Debug) -> IpcError {
    IpcError(format!("{what}: {e:?}"))
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

fn service_name(rig: &str, topic: &str) -> Result<ServiceName, IpcError> {
    ServiceName::new(&format!("painleve/{rig}/{topic}")).map_err(|e| err("service name", e))
}

fn pubsub<T: std::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<ipc::Service>,
    rig: &str,
    topic: &str,
) -> Result<iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>, IpcError> {
    node.service_builder(&service_name(rig, topic)?)
        .publish_subscribe::<T>()
        .subscriber_max_buffer_size(QUEUE_DEPTH)
        .history_size(0)
        .enable_safe_overflow(true)
        .max_publishers(2)
        .max_subscribers(4)
        .max_nodes(6)
        .open_or_create()
        .map_err(|e| err(&format!("open service {topic}"), e))
}

fn publisher<T: std::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<ipc::Service>,
    rig: &str,
    topic: &str,
) -> Result<Publisher<ipc::Service, T, ()>, IpcError> {
    pubsub::<T>(node, rig, topic)?.publisher_builder().create().map_err(|e| err(&format!("publisher {topic}"), e))
}

fn subscriber<T: std::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<ipc::Service>,
    rig: &str,
    topic: &str,
) -> Result<Subscriber<ipc::Service, T, ()>, IpcError> {
    pubsub::<T>(node, rig, topic)?
        .subscriber_builder()
        .buffer_size(QUEUE_DEPTH)
        .create()
        .map_err(|e| err(&format!("subscriber {topic}"), e))
}

fn event(
    node: &Node<ipc::Service>,
    rig: &str,
    topic: &str,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, IpcError> {
    node.service_builder(&service_name(rig, topic)?)
        .event()
        .max_notifiers(2)
        .max_listeners(2)
        .max_nodes(6)
        .open_or_create()
        .map_err(|e| err(&format!("open event {topic}"), e))
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

/// A publisher with the notifier that wakes its peer.
pub struct Outbox<T: std::fmt::Debug + ZeroCopySend + 'static> {
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Option<Notifier<ipc::Service>>,
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Outbox<T> {
    /// Publishes `value` (a copy into shared memory) and wakes the peer.
    ///
    /// # Errors
    /// [`IpcError`] when sending fails.
    pub fn send(&self, value: T) -> Result<(), IpcError> {
        self.publisher.send_copy(value).map_err(|e| err("send", e))?;
        if let Some(n) = &self.notifier {
            n.notify().map_err(|e| err("notify", e))?;
        }
        Ok(())
    }
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
}

impl PlantPorts {
    /// Opens (or creates) the rig's services for the plant; `spin` is the bounded spin.
    ///
    /// # Errors
    /// [`IpcError`] when a node, service or port cannot be created.
    pub fn open(rig: &str, spin: Duration) -> Result<Self, IpcError> {
        let node = node(Role::Plant, rig)?;
        let frame_ready = event(&node, rig, "frame_ready")?;
        let command_ready = event(&node, rig, "command_ready")?;
        let frames_service = pubsub::<SensorFrame>(&node, rig, "sensor_frames")?;
        let commands_service = pubsub::<ActuatorCommand>(&node, rig, "actuator_commands")?;
        Ok(Self {
            frames: Outbox {
                publisher: frames_service.publisher_builder().create().map_err(|e| err("publisher sensor_frames", e))?,
                notifier: Some(frame_ready.notifier_builder().create().map_err(|e| err("notifier", e))?),
            },
            truth: Outbox { publisher: publisher(&node, rig, "ground_truth")?, notifier: None },
            commands: Inbox {
                subscriber: commands_service
                    .subscriber_builder()
                    .buffer_size(QUEUE_DEPTH)
                    .create()
                    .map_err(|e| err("subscriber actuator_commands", e))?,
                listener: Some(command_ready.listener_builder().create().map_err(|e| err("listener", e))?),
                spin,
            },
            telemetry: Inbox { subscriber: subscriber(&node, rig, "firmware_telemetry")?, listener: None, spin },
            announcements: Inbox { subscriber: subscriber(&node, rig, "firmware_announcement")?, listener: None, spin },
            frames_service,
            commands_service,
            node,
        })
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
    /// [`IpcError`] when a node, service or port cannot be created.
    pub fn open(rig: &str, spin: Duration) -> Result<Self, IpcError> {
        let node = node(Role::Firmware, rig)?;
        let frame_ready = event(&node, rig, "frame_ready")?;
        let command_ready = event(&node, rig, "command_ready")?;
        Ok(Self {
            frames: Inbox {
                subscriber: subscriber(&node, rig, "sensor_frames")?,
                listener: Some(frame_ready.listener_builder().create().map_err(|e| err("listener", e))?),
                spin,
            },
            commands: Outbox {
                publisher: publisher(&node, rig, "actuator_commands")?,
                notifier: Some(command_ready.notifier_builder().create().map_err(|e| err("notifier", e))?),
            },
            telemetry: Outbox { publisher: publisher(&node, rig, "firmware_telemetry")?, notifier: None },
            announcement: Outbox { publisher: publisher(&node, rig, "firmware_announcement")?, notifier: None },
            node,
        })
    }
}
