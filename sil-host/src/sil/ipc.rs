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
use shared::wire::{ActuatorCommand, FirmwareTelemetry, GroundTruth, SensorFrame};

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

/// A process's iceoryx2 node, after removing the stale resources of dead nodes.
///
/// # Errors
/// [`IpcError`] when the node cannot be created.
pub fn node(role: Role, rig: &str) -> Result<Node<ipc::Service>, IpcError> {
    // The rig reports its own errors; iceoryx2's warnings (no config file: defaults used) are noise here.
    set_log_level(LogLevel::Error);
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

/// The state of the node `role` of rig `rig`.
pub fn peer_state(role: Role, rig: &str) -> PeerState {
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
                    l.timed_wait(|_| {}, deadline - now).map_err(|e| err("wait", e))?;
                }
                _ => std::thread::yield_now(),
            }
        }
    }
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
            node,
        })
    }
}

/// How a real-time control loop was set up by [`prepare_realtime`] (reported in
/// `summary.json`).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct RealtimeSetup {
    /// The CPU the loop's thread is pinned to; `None` when not pinned.
    pub cpu: Option<usize>,
    /// Its `SCHED_FIFO` priority; `None` under the normal scheduler.
    pub fifo_priority: Option<u8>,
    /// What could not be set up as the scenario asked (the run goes on without it).
    pub warnings: Vec<String>,
    /// The thread's CPUs before pinning, for [`leave_realtime`].
    #[serde(skip)]
    previous_cpus: Vec<usize>,
}

impl RealtimeSetup {
    /// One line for people: `CPU 1, SCHED_FIFO 10`.
    pub fn describe(&self) -> String {
        let cpu = self.cpu.map_or("any CPU".to_string(), |c| format!("CPU {c}"));
        let sched = self.fifo_priority.map_or("normal scheduler".to_string(), |p| format!("SCHED_FIFO {p}"));
        format!("{cpu}, {sched}")
    }
}

/// Undoes [`prepare_realtime`] on the calling thread: the normal scheduler and
/// the CPUs it had before (what the plant does after the run: writing the
/// outputs is no real-time work). Memory stays locked. Never fails.
pub fn leave_realtime(setup: &RealtimeSetup) {
    #[cfg(target_os = "linux")]
    // SAFETY: as in prepare_realtime; the mask and param are owned by this frame.
    unsafe {
        if setup.fifo_priority.is_some() {
            let param = libc::sched_param { sched_priority: 0 };
            libc::sched_setscheduler(0, libc::SCHED_OTHER, &param);
        }
        if setup.cpu.is_some() && !setup.previous_cpus.is_empty() {
            let mut mask: libc::cpu_set_t = std::mem::zeroed();
            for &c in &setup.previous_cpus {
                libc::CPU_SET(c, &mut mask);
            }
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mask);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = setup;
}

/// The CPUs the calling thread may run on (its affinity mask).
#[cfg(target_os = "linux")]
fn allowed_cpus() -> std::io::Result<Vec<usize>> {
    // SAFETY: a zeroed cpu_set_t owned here, of the size passed; pid 0 is the
    // calling thread.
    unsafe {
        let mut mask: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut mask) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok((0..libc::CPU_SETSIZE as usize).filter(|&c| libc::CPU_ISSET(c, &mask)).collect())
    }
}

/// Real-time runs: sets up the calling thread (the control loop) as the
/// scenario's `[rig]` asks: 1 us timer slack instead of the default 50 us (sleeps
/// end when asked), memory locked (no page fault mid-period), pinned to
/// `rig.realtime_cpu` and scheduled `SCHED_FIFO` at `rig.realtime_fifo_priority`.
///
/// Why one CPU for both processes: the plant publishes a frame and blocks for the
/// command, which hands the core straight to the firmware and back, a few
/// microseconds each way; on two CPUs the answer waits for the other core to wake
/// up, which on this virtual machine takes up to milliseconds tens of times a
/// minute. Why `SCHED_FIFO` is safe here: neither loop busy-waits for more than
/// `rig.spin_us` a period, far below the kernel's real-time throttling (95 % of
/// each second); a busy-waiting FIFO loop would be throttled 50 ms every second.
///
/// Never fails: what the kernel refuses (no privilege, no such CPU) is a warning
/// in the result. Linux only; elsewhere it only reports that nothing was set.
pub fn prepare_realtime(rig: &super::scenario::RigSection) -> RealtimeSetup {
    let mut setup = RealtimeSetup::default();
    #[cfg(target_os = "linux")]
    // SAFETY: prctl(PR_SET_TIMERSLACK) takes one integer; mlockall takes flags;
    // sched_{get,set}affinity get a properly sized cpu_set_t owned by this frame;
    // sched_setscheduler gets a valid sched_param. pid 0 is the calling thread.
    unsafe {
        libc::prctl(libc::PR_SET_TIMERSLACK, 1000 as libc::c_ulong, 0 as libc::c_ulong, 0 as libc::c_ulong, 0 as libc::c_ulong);
        if libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) != 0 {
            setup.warnings.push(format!("mlockall: {}", std::io::Error::last_os_error()));
        }
        let pin = rig.realtime_pin().unwrap_or(super::scenario::CpuPin::None);
        match allowed_cpus() {
            Ok(cpus) => setup.previous_cpus = cpus,
            Err(e) => setup.warnings.push(format!("sched_getaffinity: {e}")),
        }
        let cpu = match pin {
            super::scenario::CpuPin::None => None,
            super::scenario::CpuPin::Cpu(c) => Some(c),
            super::scenario::CpuPin::Last => setup.previous_cpus.last().copied(),
        };
        if let Some(c) = cpu {
            let mut mask: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(c, &mut mask);
            if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mask) == 0 {
                setup.cpu = Some(c);
            } else {
                setup.warnings.push(format!("cannot pin the control loop to CPU {c}: {}", std::io::Error::last_os_error()));
            }
        }
        let prio = rig.realtime_fifo_priority;
        if prio > 0 {
            let param = libc::sched_param { sched_priority: i32::from(prio) };
            if libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) == 0 {
                setup.fifo_priority = Some(prio);
            } else {
                setup.warnings.push(format!(
                    "SCHED_FIFO priority {prio}: {} (running under the normal scheduler; set rig.realtime_fifo_priority = 0 to silence this)",
                    std::io::Error::last_os_error()
                ));
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = rig;
        setup.warnings.push("real-time set-up (pinning, SCHED_FIFO, memory locking) is Linux-only".into());
    }
    setup
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    fn cpus() -> Vec<usize> {
        allowed_cpus().unwrap()
    }

    #[test]
    fn a_real_time_loop_is_pinned_to_the_last_cpu_and_given_back_its_cpus() {
        // On a thread of its own: the set-up is per thread.
        std::thread::spawn(|| {
            let before = cpus();
            let rig = super::super::scenario::RigSection { realtime_fifo_priority: 0, ..Default::default() };
            let setup = prepare_realtime(&rig);
            assert_eq!(setup.cpu, before.last().copied(), "{:?}", setup.warnings);
            assert_eq!(cpus(), vec![before[before.len() - 1]]);
            assert_eq!(setup.fifo_priority, None);
            leave_realtime(&setup);
            assert_eq!(cpus(), before);
        })
        .join()
        .unwrap();
    }
}
