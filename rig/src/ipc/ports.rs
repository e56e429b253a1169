//! The rig's services and ports of each side: the plant's ([`PlantPorts`]:
//! frames out, commands, telemetry and the announcement in, ground truth to
//! monitors) and the firmware's ([`FirmwarePorts`]).

use std::{
    sync::{Arc, Mutex, PoisonError},
    time::Duration,
};

use iceoryx2::prelude::*;
use shared::wire::{ActuatorCommand, FirmwareAnnouncement, FirmwareTelemetry, GroundTruth, SensorFrame};

use super::{
    error::IpcError,
    mailbox::{Inbox, Outbox, PubSub, Wake, listener, notifier, publisher, pubsub, subscriber},
    monitors::{MonitorCounts, MonitorPolicy, MonitorState, lossless_publisher},
    peers::{Role, node},
};
use crate::services::{LINK_EVENT, MONITOR_EVENT, Needs, Topic, open_event, open_pubsub, service_name};

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
