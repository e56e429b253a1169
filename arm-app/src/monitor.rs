//! The monitor block: what the image publishes in RAM after every tick, for a
//! debugger to read without stopping the core (probe-rs's live watch of the
//! symbol `PAINLEVE_MONITOR` on a board, the emulator's lockstep link on the
//! emulated image: docs/board.md "The emulated image"). It holds the tick's
//! command and the firmware's telemetry in the wire's own layouts
//! (docs/wire.md), so that the host decodes them as it decodes the wire.
//!
//! Layout (`repr(C)`, little-endian, 96 bytes):
//!
//! | offset | field | type |
//! |---|---|---|
//! | 0 | `magic` | `u32`, [`MONITOR_MAGIC`] once the first tick wrote it (0 before) |
//! | 4 | `version` | `u32`, [`MONITOR_VERSION`] |
//! | 8 | `ticks` | `u32`, ticks run since power-up (wraps) |
//! | 12 | `drivers_enabled` | `u32`, 1 when the drivers are enabled |
//! | 16 | `command` | `shared::wire::ActuatorCommand` (32 bytes) |
//! | 48 | `telemetry` | `shared::wire::FirmwareTelemetry` (48 bytes) |

use firmware::ControlLaw;
use shared::wire::{ActuatorCommand, FirmwareTelemetry};

use crate::{app::ArmApp, io::ArmIo};

/// `b"PLVM"` as a little-endian word.
pub const MONITOR_MAGIC: u32 = u32::from_le_bytes(*b"PLVM");
/// The block's layout version.
pub const MONITOR_VERSION: u32 = 1;
/// The block's size, bytes.
pub const MONITOR_BYTES: usize = core::mem::size_of::<Monitor>();

/// The monitor block (see the module's table).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct Monitor {
    /// [`MONITOR_MAGIC`] once written.
    pub magic: u32,
    /// [`MONITOR_VERSION`].
    pub version: u32,
    /// Ticks since power-up.
    pub ticks: u32,
    /// 1 when the drivers are enabled, else 0.
    pub drivers_enabled: u32,
    /// The last tick's command.
    pub command: ActuatorCommand,
    /// The firmware's telemetry answering it (zero before the firmware's first step).
    pub telemetry: FirmwareTelemetry,
}

const _: () = assert!(MONITOR_BYTES == 96);

impl<H: ArmIo, L: ControlLaw> ArmApp<H, L> {
    /// The monitor block after the last tick (`None` before the first command).
    pub fn monitor(&self) -> Option<Monitor> {
        let command = *self.last_command()?;
        Some(Monitor {
            magic: MONITOR_MAGIC,
            version: MONITOR_VERSION,
            ticks: self.periods(),
            drivers_enabled: u32::from(self.drivers_enabled()),
            command,
            telemetry: self.firmware().map(|fw| fw.telemetry_message(&command)).unwrap_or_default(),
        })
    }
}
