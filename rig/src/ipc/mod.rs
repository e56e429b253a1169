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
//! Before any of that, each side takes its role's lock ([`rig_lock`]): one plant
//! and one firmware per rig, whatever the timing.

mod error;
mod mailbox;
mod monitors;
mod peers;
mod ports;
pub mod rig_lock;

pub use error::IpcError;
pub use mailbox::{Inbox, Outbox};
pub use monitors::{MonitorCounts, MonitorPolicy};
pub use peers::{PeerState, Role, check_rig_name, default_rig_name, live_owner, node, peer_state};
pub use ports::{FirmwarePorts, PlantPorts};
pub use rig_lock::RigLock;

pub use crate::services::QUEUE_DEPTH;
