//! The software-in-the-loop rig: scenarios, sensor models and faults, the
//! plant-side loop, and the transports that reach the firmware (in-process, or
//! iceoryx2 shared memory to the firmware in its own process, or the MCU image
//! over its USART, in QEMU or on a board behind a serial port: processor and
//! hardware in the loop). The board twin and the emulated `arm` image as links,
//! and the board tools (bring-up, backup), are the `board-link` crate, above this one.
//!
//! Features: `ipc` (iceoryx2: [`ipc`], [`services`], [`ipc_link`], [`firmware_process`]) and
//! `pil` ([`pil_link`]), both on by default; without them the rig runs the
//! firmware in-process only (what the analyses need).
#![warn(missing_docs)]

pub mod arm;
pub mod board_protection;
pub mod calibration;
pub mod envelope;
pub mod faults;
#[cfg(feature = "ipc")]
pub mod firmware_process;
pub mod firmware_side;
pub mod frames;
pub mod handshake;
pub mod image_path;
pub mod in_process;
#[cfg(feature = "ipc")]
pub mod ipc;
#[cfg(feature = "ipc")]
pub mod ipc_link;
pub mod law;
pub mod link;
pub mod overrides;
pub mod period_loop;
#[cfg(feature = "pil")]
pub mod pil_link;
pub mod private_files;
pub mod realtime;
pub mod record;
pub mod scenario;
pub mod sensors;
#[cfg(feature = "ipc")]
pub mod services;
pub mod setup;
pub mod stats;
pub mod status_words;
pub mod summary;

// The API callers use most, at the crate root (`rig::Scenario`, `rig::run_loop`);
// every item keeps its module path too (`rig::scenario::Scenario`).
pub use envelope::Envelope;
pub use faults::{Fault, FaultKind, FaultPlan, LinkKind};
pub use in_process::InProcessLink;
#[cfg(feature = "ipc")]
pub use ipc::MonitorPolicy;
#[cfg(feature = "ipc")]
pub use ipc_link::IpcLink;
pub use link::{Exchange, FirmwareLink};
pub use overrides::Override;
pub use period_loop::{PeriodFailure, PeriodLoop, RunObserver, run_loop, stream_loop};
#[cfg(feature = "pil")]
pub use pil_link::{PilLink, PilOptions, PilTarget, QemuLink};
pub use record::{PeriodRecord, RunError};
pub use scenario::{DEFAULT_TOML, Scenario, ScenarioError};
pub use setup::{RunSetup, firmware_config, plant_for};
pub use stats::RunStats;
pub use summary::{PilFigures, RunSummary};
