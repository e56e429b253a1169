//! What the arm application tells its operator, as values: the image logs each
//! with defmt, the board twin collects them, tests assert them. No formatting
//! here (the image has no `core::fmt`; docs/board.md "Budgets").

use crate::{
    joint::{EncoderFault, Joint},
    telemetry::ArmTelemetry,
};

/// Something the operator should know, with the period (`seq`) it happened in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Notice {
    /// At start-up: an encoder answered and is ready (its AGC value).
    EncoderReady {
        /// Which encoder.
        joint: Joint,
        /// DIAAGC's AGC, 0 (strong field) to 255 (weak).
        agc: u8,
    },
    /// At start-up: an encoder is not ready; its readings will be invalid.
    EncoderNotReady {
        /// Which encoder.
        joint: Joint,
        /// Why.
        fault: EncoderFault,
    },
    /// The frame's invalid-reading flags changed to a non-zero set
    /// (`shared::wire::frame_flags`).
    InvalidReadings {
        /// The period.
        seq: u32,
        /// The frame's flags masked with `frame_flags::ANY_INVALID`.
        flags: u16,
    },
    /// The period's acquisition of the encoders failed (logged when the fault
    /// first appears or changes; the frame flags them invalid).
    AcquisitionFault {
        /// The period.
        seq: u32,
        /// Which fault.
        fault: crate::joint::AcquisitionFault,
    },
    /// Every sensor reads again.
    ReadingsBack {
        /// The period.
        seq: u32,
    },
    /// The firmware entered its safe state; the drivers are disabled (logged once
    /// per entry).
    SafeState {
        /// The period.
        seq: u32,
        /// `firmware::SafeReason` as its number (0 if unknown).
        reason: u8,
    },
    /// The drivers were asked to disable and a pin failed.
    DriversDidNotDisable,
    /// The drivers enabled after a reset.
    DriversEnabled {
        /// The period.
        seq: u32,
    },
    /// The drivers refused to enable (the fault line is asserted, or a pin failed).
    DriversRefused {
        /// The period.
        seq: u32,
    },
    /// The enable button reset the firmware; the drivers enable at the next command.
    FirmwareReset,
    /// A jog (bring-up) ended: its outcome; the drivers are disabled.
    Jogged(crate::bringup::JogOutcome),
    /// At start-up: the settings found in flash (`Saved`: the record was loaded;
    /// otherwise the drivers are locked out, and why).
    Settings(crate::record::Settings),
    /// The enable button was pressed while the drivers are locked out (the
    /// settings, and why).
    LockedOut(crate::record::Settings),
    /// A window of `step_stats::WINDOW` periods closed: its report (the image sends
    /// it on USART1 and logs it).
    Window(ArmTelemetry),
}
