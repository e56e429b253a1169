//! The attributes of a rig's iceoryx2 services, and how a process opens them
//! (docs/rig.md, "Monitors").
//!
//! A service's attributes (buffer sizes, history, overflow, how many ports and
//! nodes) are fixed by whichever process creates it first. That may be a monitor
//! started before the rig, with iceoryx2's defaults (a subscriber buffer of 2,
//! the `open_or_create()` of iceoryx2's own examples). So the rig never asks
//! iceoryx2 to check attributes on opening (a mismatch would fail with an
//! iceoryx2 error that names neither the attribute nor the value): it opens the
//! service as it is, or creates it with [`Topic::attributes`], and then checks
//! only what it needs of it ([`Needs`]). What it needs is little where monitors
//! are concerned: the plant only publishes `ground_truth`, so any buffer a client
//! chose works; `firmware_telemetry` needs room for the plant's own queue of 64.
//! A service that lacks something is refused with [`Incompatible`], naming the
//! attribute, its value and the value to use.

use std::time::{Duration, Instant};

use iceoryx2::{
    prelude::*,
    service::{
        builder::{
            event::{EventCreateError, EventOpenError},
            publish_subscribe::{PublishSubscribeCreateError, PublishSubscribeOpenError},
        },
        port_factory::{event::PortFactory as EventFactory, publish_subscribe::PortFactory as PubSubFactory},
    },
};

/// Queue depth of the rig's own subscribers (frames, commands, telemetry, the
/// announcement): a peer that stalls for this many periods finds them all on
/// waking (older ones are overwritten: safe overflow).
pub const QUEUE_DEPTH: usize = 64;

/// The largest subscriber buffer a monitor may ask for on `ground_truth` and
/// `firmware_telemetry` (its buffer when it asks for none): 1024 samples, about
/// 1 s at 1 kHz in real time, 96 KiB of ground truth per monitor.
pub const MONITOR_QUEUE_DEPTH: usize = 1024;

/// How long opening a service may take while another process creates or removes
/// it (iceoryx2's own `open_or_create` waits likewise).
const OPEN_TIMEOUT: Duration = Duration::from_secs(5);

/// The rig's publish-subscribe services (`painleve/R/<name>`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Topic {
    /// `sensor_frames`: plant -> firmware.
    SensorFrames,
    /// `actuator_commands`: firmware -> plant.
    ActuatorCommands,
    /// `firmware_announcement`: firmware -> plant, once (the handshake).
    FirmwareAnnouncement,
    /// `firmware_telemetry`: firmware -> plant and monitors.
    FirmwareTelemetry,
    /// `ground_truth`: plant -> monitors.
    GroundTruth,
}

/// The attributes the rig creates a publish-subscribe service with (iceoryx2's
/// names; the table of docs/rig.md, "Monitors").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PubSubAttributes {
    /// Largest subscriber buffer, samples.
    pub subscriber_max_buffer_size: usize,
    /// Samples a subscriber receives on connecting (0: none).
    pub history_size: usize,
    /// A full subscriber buffer overwrites its oldest sample (true), or the
    /// publisher decides (false: the rig discards the new sample, or waits for
    /// room, see [`Needs::no_safe_overflow`]).
    pub enable_safe_overflow: bool,
    /// Most publishers.
    pub max_publishers: usize,
    /// Most subscribers.
    pub max_subscribers: usize,
    /// Most nodes (processes) that open the service.
    pub max_nodes: usize,
}

/// The attributes the rig creates an event service with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventAttributes {
    /// Most notifiers.
    pub max_notifiers: usize,
    /// Most listeners.
    pub max_listeners: usize,
    /// Most nodes.
    pub max_nodes: usize,
}

/// The attributes of the rig's own events (`frame_ready`, `command_ready`).
pub const LINK_EVENT: EventAttributes = EventAttributes { max_notifiers: 2, max_listeners: 2, max_nodes: 6 };

/// The attributes of the monitors' wake-up events (`ground_truth`,
/// `firmware_telemetry`, the names of the services they announce).
pub const MONITOR_EVENT: EventAttributes = EventAttributes { max_notifiers: 2, max_listeners: 8, max_nodes: 20 };

impl Topic {
    /// Every topic, in the order of the docs' table.
    pub const ALL: [Topic; 5] =
        [Self::SensorFrames, Self::ActuatorCommands, Self::FirmwareTelemetry, Self::GroundTruth, Self::FirmwareAnnouncement];

    /// The last part of the service name (`painleve/R/<name>`).
    pub fn name(self) -> &'static str {
        match self {
            Self::SensorFrames => "sensor_frames",
            Self::ActuatorCommands => "actuator_commands",
            Self::FirmwareAnnouncement => "firmware_announcement",
            Self::FirmwareTelemetry => "firmware_telemetry",
            Self::GroundTruth => "ground_truth",
        }
    }

    /// The payload's iceoryx2 type name (`shared::wire`).
    pub fn type_name(self) -> &'static str {
        match self {
            Self::SensorFrames => "painleve::SensorFrame",
            Self::ActuatorCommands => "painleve::ActuatorCommand",
            Self::FirmwareAnnouncement => "painleve::FirmwareAnnouncement",
            Self::FirmwareTelemetry => "painleve::FirmwareTelemetry",
            Self::GroundTruth => "painleve::GroundTruth",
        }
    }

    /// Whether monitors subscribe to it (it has a wake-up event of the same name).
    pub fn for_monitors(self) -> bool {
        matches!(self, Self::FirmwareTelemetry | Self::GroundTruth)
    }

    /// The attributes the rig creates the service with.
    ///
    /// `ground_truth` has no safe overflow: the plant decides per run what a full
    /// monitor costs (the sample, or a wait: `sil-host run --monitors`), which a
    /// safe-overflow service would decide for it. `firmware_telemetry` keeps safe
    /// overflow: the firmware never waits for anyone (its deadline).
    pub fn attributes(self) -> PubSubAttributes {
        let link = PubSubAttributes {
            subscriber_max_buffer_size: QUEUE_DEPTH,
            history_size: 0,
            enable_safe_overflow: true,
            max_publishers: 2,
            max_subscribers: 4,
            max_nodes: 6,
        };
        let monitored = PubSubAttributes { subscriber_max_buffer_size: MONITOR_QUEUE_DEPTH, max_subscribers: 8, max_nodes: 20, ..link };
        match self {
            Self::SensorFrames | Self::ActuatorCommands | Self::FirmwareAnnouncement => link,
            Self::FirmwareTelemetry => monitored,
            Self::GroundTruth => PubSubAttributes { enable_safe_overflow: false, ..monitored },
        }
    }

    /// What the rig needs of the service when another process created it.
    pub fn needs(self) -> Needs {
        match self {
            // The link's own queues: a smaller buffer would lose frames or commands
            // that the same run over `--in-process` keeps.
            Self::SensorFrames | Self::ActuatorCommands | Self::FirmwareAnnouncement => {
                Needs { min_buffer: QUEUE_DEPTH, safe_overflow: true, ..Needs::default() }
            }
            // The plant's telemetry queue; the firmware discards rather than waits
            // when the service has no safe overflow, so either kind works.
            Self::FirmwareTelemetry => Needs { min_buffer: QUEUE_DEPTH, ..Needs::default() },
            // The plant only publishes: whatever buffer a monitor chose is its own.
            Self::GroundTruth => Needs::default(),
        }
    }
}

/// What the rig needs of a publish-subscribe service another process created.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Needs {
    /// Smallest `subscriber_max_buffer_size` (0: any).
    pub min_buffer: usize,
    /// `enable_safe_overflow` must be true (the rig's subscribers rely on it).
    pub safe_overflow: bool,
    /// `enable_safe_overflow` must be false (the plant waits for full monitors:
    /// `sil-host run --monitors` in lockstep).
    pub no_safe_overflow: bool,
    /// Smallest `max_subscribers` (0: any).
    pub min_subscribers: usize,
    /// Smallest `max_nodes` (0: any).
    pub min_nodes: usize,
}

/// A service another process created without something the rig needs.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "service `{service}` has {attribute} = {found}, but {who} needs {attribute} {needed}: another process created it first \
     (a monitor with iceoryx2's defaults?); start monitors after the rig, or have them create it with {attribute} {needed} \
     (docs/rig.md, \"Monitors\")"
)]
pub struct Incompatible {
    /// The service's full name.
    pub service: String,
    /// The attribute, as iceoryx2's builders name it.
    pub attribute: &'static str,
    /// Its value in the service.
    pub found: String,
    /// What to use (`>= 64`, `= false`).
    pub needed: String,
    /// Who needs it (`the rig`, `--monitors in lockstep`).
    pub who: &'static str,
}

/// Opening a service failed.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// The service exists without what the rig needs.
    #[error(transparent)]
    Incompatible(#[from] Incompatible),
    /// iceoryx2 failed (with what was being done).
    #[error("{0}")]
    Other(String),
}

/// The full name of service `name` of rig `rig`.
pub fn service_name(rig: &str, name: &str) -> String {
    format!("painleve/{rig}/{name}")
}

fn iceoryx_name(full: &str) -> Result<ServiceName, ServiceError> {
    ServiceName::new(full).map_err(|e| ServiceError::Other(format!("service name {full}: {e:?}")))
}

/// Checks the attributes of an existing service against `needs`.
///
/// # Errors
/// [`Incompatible`] naming the first attribute that falls short.
pub fn check(service: &str, found: &PubSubAttributes, needs: &Needs, who: &'static str) -> Result<(), Incompatible> {
    let short = |attribute: &'static str, found: String, needed: String| {
        Err(Incompatible { service: service.to_string(), attribute, found, needed, who })
    };
    if found.subscriber_max_buffer_size < needs.min_buffer {
        return short("subscriber_max_buffer_size", found.subscriber_max_buffer_size.to_string(), format!(">= {}", needs.min_buffer));
    }
    if needs.safe_overflow && !found.enable_safe_overflow {
        return short("enable_safe_overflow", "false".into(), "= true".into());
    }
    if needs.no_safe_overflow && found.enable_safe_overflow {
        return short("enable_safe_overflow", "true".into(), "= false".into());
    }
    if found.max_subscribers < needs.min_subscribers {
        return short("max_subscribers", found.max_subscribers.to_string(), format!(">= {}", needs.min_subscribers));
    }
    if found.max_nodes < needs.min_nodes {
        return short("max_nodes", found.max_nodes.to_string(), format!(">= {}", needs.min_nodes));
    }
    Ok(())
}

/// The attributes of an open publish-subscribe service.
pub fn attributes_of<T: std::fmt::Debug + ZeroCopySend + 'static>(f: &PubSubFactory<ipc::Service, T, ()>) -> PubSubAttributes {
    let c = f.static_config();
    PubSubAttributes {
        subscriber_max_buffer_size: c.subscriber_max_buffer_size(),
        history_size: c.history_size(),
        enable_safe_overflow: c.has_safe_overflow(),
        max_publishers: c.max_publishers(),
        max_subscribers: c.max_subscribers(),
        max_nodes: c.max_nodes(),
    }
}

/// Opens service `topic` of rig `rig` as it is, or creates it with
/// [`Topic::attributes`], then checks it against `needs` (by default
/// [`Topic::needs`]); `who` names the need in an error.
///
/// # Errors
/// [`ServiceError::Incompatible`] when the service lacks something (the payload
/// type included); [`ServiceError::Other`] when iceoryx2 fails.
pub fn open_pubsub<T: std::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<ipc::Service>,
    rig: &str,
    topic: Topic,
    needs: &Needs,
    who: &'static str,
) -> Result<PubSubFactory<ipc::Service, T, ()>, ServiceError> {
    let full = service_name(rig, topic.name());
    let name = iceoryx_name(&full)?;
    let a = topic.attributes();
    let start = Instant::now();
    let other = |what: &str, e: &dyn std::fmt::Debug| ServiceError::Other(format!("{what} service {full}: {e:?}"));
    let factory = loop {
        // No attribute is set on opening: iceoryx2 then checks only the payload type.
        match node.service_builder(&name).publish_subscribe::<T>().open() {
            Ok(f) => break f,
            Err(PublishSubscribeOpenError::DoesNotExist) => {}
            Err(PublishSubscribeOpenError::IncompatibleTypes) => {
                return Err(Incompatible {
                    service: full,
                    attribute: "payload type",
                    found: "another type".into(),
                    needed: format!("= {} ({} B, no user header)", topic.type_name(), core::mem::size_of::<T>()),
                    who,
                }
                .into());
            }
            Err(e @ (PublishSubscribeOpenError::HangsInCreation | PublishSubscribeOpenError::IsMarkedForDestruction))
                if start.elapsed() < OPEN_TIMEOUT =>
            {
                let _ = e;
                std::thread::sleep(Duration::from_millis(1));
                continue;
            }
            Err(e) => return Err(other("open", &e)),
        }
        let created = node
            .service_builder(&name)
            .publish_subscribe::<T>()
            .subscriber_max_buffer_size(a.subscriber_max_buffer_size)
            .history_size(a.history_size)
            .enable_safe_overflow(a.enable_safe_overflow)
            .max_publishers(a.max_publishers)
            .max_subscribers(a.max_subscribers)
            .max_nodes(a.max_nodes)
            .create();
        match created {
            Ok(f) => break f,
            // Another process created it meanwhile: open that one.
            Err(PublishSubscribeCreateError::AlreadyExists | PublishSubscribeCreateError::IsBeingCreatedByAnotherInstance)
                if start.elapsed() < OPEN_TIMEOUT =>
            {
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) => return Err(other("create", &e)),
        }
    };
    check(&full, &attributes_of(&factory), needs, who)?;
    Ok(factory)
}

/// Opens event `name` of rig `rig` as it is, or creates it with `attributes`.
/// The rig needs nothing of an event another process created beyond room for its
/// own port (iceoryx2 checks that when the port is made).
///
/// # Errors
/// [`ServiceError::Other`] when iceoryx2 fails.
pub fn open_event(
    node: &Node<ipc::Service>,
    rig: &str,
    name: &str,
    attributes: &EventAttributes,
) -> Result<EventFactory<ipc::Service>, ServiceError> {
    let full = service_name(rig, name);
    let service = iceoryx_name(&full)?;
    let start = Instant::now();
    let other = |what: &str, e: &dyn std::fmt::Debug| ServiceError::Other(format!("{what} event {full}: {e:?}"));
    loop {
        match node.service_builder(&service).event().open() {
            Ok(f) => return Ok(f),
            Err(EventOpenError::DoesNotExist) => {}
            Err(EventOpenError::HangsInCreation | EventOpenError::IsMarkedForDestruction) if start.elapsed() < OPEN_TIMEOUT => {
                std::thread::sleep(Duration::from_millis(1));
                continue;
            }
            Err(e) => return Err(other("open", &e)),
        }
        let created = node
            .service_builder(&service)
            .event()
            .max_notifiers(attributes.max_notifiers)
            .max_listeners(attributes.max_listeners)
            .max_nodes(attributes.max_nodes)
            .create();
        match created {
            Ok(f) => return Ok(f),
            Err(EventCreateError::AlreadyExists | EventCreateError::IsBeingCreatedByAnotherInstance) if start.elapsed() < OPEN_TIMEOUT => {
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) => return Err(other("create", &e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_names_are_the_wire_types() {
        use shared::wire::{ActuatorCommand, FirmwareAnnouncement, FirmwareTelemetry, GroundTruth, SensorFrame};
        // SAFETY: `type_name` only returns the derive's constant string.
        let names = unsafe {
            [
                <SensorFrame as ZeroCopySend>::type_name(),
                <ActuatorCommand as ZeroCopySend>::type_name(),
                <FirmwareTelemetry as ZeroCopySend>::type_name(),
                <GroundTruth as ZeroCopySend>::type_name(),
                <FirmwareAnnouncement as ZeroCopySend>::type_name(),
            ]
        };
        let ours: Vec<&str> = Topic::ALL.iter().map(|t| t.type_name()).collect();
        assert_eq!(ours, names);
    }

    #[test]
    fn the_rig_accepts_what_it_creates_and_ground_truth_as_a_default_client_creates_it() {
        for t in Topic::ALL {
            assert_eq!(check("s", &t.attributes(), &t.needs(), "the rig"), Ok(()), "{t:?}");
        }
        // iceoryx2's defaults (no config file): what `open_or_create()` without settings makes.
        let d = &iceoryx2::config::Config::default().defaults.publish_subscribe;
        let defaults = PubSubAttributes {
            subscriber_max_buffer_size: d.subscriber_max_buffer_size,
            history_size: d.publisher_history_size,
            enable_safe_overflow: d.enable_safe_overflow,
            max_publishers: d.max_publishers,
            max_subscribers: d.max_subscribers,
            max_nodes: d.max_nodes,
        };
        assert_eq!((defaults.subscriber_max_buffer_size, defaults.enable_safe_overflow), (2, true));
        assert_eq!(check("s", &defaults, &Topic::GroundTruth.needs(), "the rig"), Ok(()));
        let e = check("painleve/r/firmware_telemetry", &defaults, &Topic::FirmwareTelemetry.needs(), "the rig").unwrap_err();
        assert_eq!((e.attribute, e.found.as_str(), e.needed.as_str()), ("subscriber_max_buffer_size", "2", ">= 64"));
        assert!(e.to_string().contains("subscriber_max_buffer_size = 2"), "{e}");
        let lossless = Needs { no_safe_overflow: true, ..Needs::default() };
        let e = check("g", &defaults, &lossless, "--monitors in lockstep").unwrap_err();
        assert_eq!((e.attribute, e.needed.as_str()), ("enable_safe_overflow", "= false"));
        assert_eq!(check("g", &Topic::GroundTruth.attributes(), &lossless, "x"), Ok(()));
    }
}
