//! The two joint encoders by name, and why one gives no reading (the driver's
//! error without its bus error's type): what notices, raw readings and jogs
//! speak of.

/// One of the two joint encoders.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// The period's acquisition of both encoders failed ([`AcquisitionFault`]).
    Acquisition(AcquisitionFault),
}

/// Why a period's acquisition of the two encoders failed on a board that reads
/// them without the core (the `arm` image: SPI1 through DMA2, RM0090 10;
/// docs/board.md "The encoders by DMA"). Both encoders' readings of that period
/// are invalid (the frame's `THETA1_INVALID` and `ELBOW_INVALID`); the
/// firmware holds its last command, and `bad_frame_limit` (3) such periods in a
/// row latch the safe state with its own reason, 13 `Acquisition`
/// (`firmware::SafeReason`, latched before that period's step, so neither the
/// bad-frame rule nor the consistency check names it first), the drivers
/// disabled. Each fault is logged by name ([`crate::Notice::AcquisitionFault`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum AcquisitionFault {
    /// A stream's transfer error (DMA_LISR TEIF: a bus error at SxPAR or
    /// SxM0AR; the hardware disables the stream, RM0090 10.3.16).
    TransferError,
    /// A stream's FIFO error (DMA_LISR FEIF: in direct mode, RM0090 10.3.16).
    FifoError,
    /// A stream's direct-mode error (DMA_LISR DMEIF, RM0090 10.3.16).
    DirectModeError,
    /// The frames had not completed by the acquisition's deadline (a stream or
    /// SPI1 stalled: no request, a mode fault, a stream disabled).
    Timeout,
    /// An encoder's chip select read low after it was released (a short, a
    /// pin held by something else): both chips could drive MISO at once.
    StuckChipSelect,
}

impl AcquisitionFault {
    /// A short description for a log line.
    pub fn describe(self) -> &'static str {
        match self {
            Self::TransferError => "DMA transfer error (TEIF)",
            Self::FifoError => "DMA FIFO error (FEIF)",
            Self::DirectModeError => "DMA direct-mode error (DMEIF)",
            Self::Timeout => "the encoders' frames did not complete in time",
            Self::StuckChipSelect => "an encoder's chip select is stuck low",
        }
    }
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
            Self::Acquisition(f) => f.describe(),
        }
    }
}
