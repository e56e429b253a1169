//! The kinds of link to the firmware and the faults each can inject, checked in
//! one place ([`LinkKind::check`]) by the links' constructors and the commands.

use super::{Fault, FaultKind};
use crate::record::RunError;

/// The kinds of link to the firmware, for the faults each can inject (checked
/// in one place, [`LinkKind::check`], by the links' constructors and by the
/// commands before they write anything).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkKind {
    /// The firmware step linked into the plant's process.
    InProcess,
    /// The firmware in its own process over iceoryx2.
    Ipc,
    /// The MCU image in QEMU over a socket.
    PilQemu,
    /// The MCU image on a board behind a serial port (HIL).
    PilSerial,
    /// The arm application on the board twin (bus-level device models).
    Twin,
    /// The `arm` ELF on the emulated board (register-level models).
    Emulator,
}

impl LinkKind {
    /// Every fault this link can inject. Sensor, late and dropped commands act on
    /// the plant's side or the firmware's start time and work everywhere;
    /// `stall` needs a host process to stop, `kill_firmware` a process to kill
    /// (the firmware's, or QEMU).
    pub fn injectable(self) -> &'static [FaultKind] {
        use FaultKind::*;
        const EVERYWHERE: [FaultKind; 5] = [LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange];
        match self {
            Self::Ipc => &[LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, Stall, KillFirmware],
            Self::PilQemu => &[LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, KillFirmware],
            Self::InProcess => &[LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, EncoderSpike, LoadCellDrift, BeltGain],
            Self::PilSerial => &EVERYWHERE,
            // The twin makes its readings on the bus: the plant side's frame
            // faults (nan_sensor, out_of_range) do not reach it; a late step needs
            // a clock, which the twin's steps do not take.
            Self::Twin | Self::Emulator => &[
                DropCommand,
                StuckSensor,
                SpiError,
                ParityError,
                MagnetLost,
                MissingConversion,
                DriverFault,
                DmaTransferError,
                DmaFifoError,
                DmaDirectModeError,
                DmaLateTransfer,
                StuckChipSelect,
                EncoderSpike,
                LoadCellDrift,
                BeltGain,
                Board,
            ],
        }
    }

    /// Refuses a scenario fault this link cannot inject.
    ///
    /// # Errors
    /// [`RunError::Unsupported`] naming the first such fault, why, and what to use instead.
    pub fn check(self, faults: &[Fault]) -> Result<(), RunError> {
        let Some(f) = faults.iter().find(|f| !self.injectable().contains(&f.kind)) else { return Ok(()) };
        Err(RunError::Unsupported(match (f.kind, self) {
            (FaultKind::Stall | FaultKind::KillFirmware, Self::Twin | Self::Emulator) => format!(
                "fault {:?} acts on a firmware process, and the board {} runs in this one: run over iceoryx2 (without --link)",
                f.kind,
                if self == Self::Twin { "twin" } else { "emulator" }
            ),
            (FaultKind::Stall | FaultKind::KillFirmware, Self::InProcess) => {
                format!("fault {:?} acts on the firmware process: run over iceoryx2 (without --in-process)", f.kind)
            }
            (FaultKind::Stall, Self::PilQemu) => "fault stall stalls a host process: not available in PIL (kill_firmware is)".into(),
            (FaultKind::Stall, _) => "fault stall stalls a host process: not available over a serial port".into(),
            (FaultKind::KillFirmware, _) => {
                "fault kill_firmware kills the emulator that runs the image: not available over a serial port; \
                 to test a lost board, cut its power or unplug it during a run"
                    .into()
            }
            (FaultKind::Board, link) => format!(
                "fault board changes the board's physical truth, which only a board has: run on the board twin (`run --link twin`) \
                 or the emulated board (`run --link emulator`), not the {link:?} link"
            ),
            (kind @ (FaultKind::EncoderSpike | FaultKind::LoadCellDrift | FaultKind::BeltGain), link) => format!(
                "fault {kind:?} is made by the rig's sensor model or the board's devices: run in process (`run --in-process`), \
                 on the board twin (`run --link twin`) or the emulated board (`run --link emulator`), not the {link:?} link"
            ),
            (kind, link) if kind.is_bus_fault() => {
                format!(
                    "fault {kind:?} acts on the board's bus and devices: run on the board twin (`run --link twin`) or the emulated board \
                     (`run --link emulator`), not the {link:?} link"
                )
            }
            (kind @ (FaultKind::NanSensor | FaultKind::OutOfRange | FaultKind::LateCommand), Self::Twin | Self::Emulator) => format!(
                "fault {kind:?} acts on the wire-level frame or the step's clock, which the board twin does not have: \
                 use its bus faults (spi_error, parity_error, magnet_lost, missing_conversion, driver_fault), its acquisition faults \
                 (dma_transfer_error, dma_fifo_error, dma_direct_mode_error, dma_late_transfer, stuck_chip_select) or stuck_sensor"
            ),
            (kind, link) => format!("fault {kind:?} cannot be injected over the {link:?} link"),
        }))
    }
}
