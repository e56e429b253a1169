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
