//! What the arm application tells its operator, as values: the image logs each
//! with defmt, the board twin collects them, tests assert them. No formatting
//! here (the image has no `core::fmt`; docs/board.md "Budgets").

use crate::telemetry::ArmTelemetry;

/// One of the two joint encoders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Joint {
    /// The base joint's encoder (`theta1`).
    Theta1,
    /// The elbow's encoder (`theta2 - theta1`).
    Elbow,
}

impl Joint {
    /// `theta1` or `elbow`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Theta1 => "theta1",
            Self::Elbow => "elbow",
        }
    }
}

/// Why an encoder is not ready at start-up ([`drivers::as5047p::Error`] without
/// its bus error's type).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncoderFault {
    /// The SPI transfer failed.
    Bus,
    /// An answer had odd parity.
    Parity,
    /// The error flag was set (ERRFL bits).
    ErrorFlag(u16),
    /// Offset compensation not finished, or no chip on the bus.
    NotReady,
    /// The magnetic field is out of range.
    Magnet,
    /// CORDIC overflow.
    CordicOverflow,
}

impl EncoderFault {
    /// The fault of a driver error.
    pub fn of<E>(e: &drivers::as5047p::Error<E>) -> Self {
        use drivers::as5047p::Error;
        match e {
            Error::Bus(_) => Self::Bus,
            Error::Parity { .. } => Self::Parity,
            Error::ErrorFlag { errfl } => Self::ErrorFlag(*errfl),
            Error::NotReady => Self::NotReady,
            Error::Magnet { .. } => Self::Magnet,
            Error::CordicOverflow => Self::CordicOverflow,
        }
    }

    /// A short description for a log line.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Bus => "SPI bus error",
            Self::Parity => "parity error",
            Self::ErrorFlag(_) => "error flag",
            Self::NotReady => "offset compensation not finished, or no chip on the bus",
            Self::Magnet => "magnetic field out of range",
            Self::CordicOverflow => "CORDIC overflow",
        }
    }
}

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
    /// A window of `step_stats::WINDOW` periods closed: its report (the image sends
    /// it on USART1 and logs it).
    Window(ArmTelemetry),
}
