//! Why the firmware is in its safe state ([`SafeReason`]): the reasons, their
//! codes in the status word and their descriptions.

use shared::wire::status;

use crate::law::LawError;

/// Why the firmware is in its safe state (zero torque). The code is reported in
/// bits 24..31 of the status word.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum SafeReason {
    /// `deadline_miss_limit` consecutive deadline misses.
    DeadlineMisses = 1,
    /// `bad_frame_limit` consecutive bad (out-of-range or stale) frames.
    BadFrames = 2,
    /// The control law produced a NaN or infinite value.
    NonFinite = 3,
    /// The arm reached a singular (straight) configuration.
    Singular = 4,
    /// The reference is out of the arm's reach.
    Unreachable = 5,
    /// The peer (the plant, or the link to it) is gone: no frames arrive and the
    /// board reports it dead ([`Firmware::enter_safe_state`](super::Firmware::enter_safe_state) from the board's loop).
    PeerLost = 6,
    /// The encoders and the load cell disagree about where the tip is (a stuck or
    /// failed sensor; [`crate::consistency`]) for `sensor_fault_confirm` periods.
    SensorFault = 7,
    /// A joint's speed past [`crate::runaway::SPEED_LIMIT`] ([`crate::runaway`]).
    Runaway = 8,
    /// The load cell at full scale for [`crate::runaway::OVERLOAD_S`]: the force
    /// loop is blind ([`crate::runaway`]).
    Overload = 9,
    /// A joint accelerated against the torque its motor applied, beyond the
    /// model's uncertainty, for 5 ms ([`crate::wiring`]): a motor wired the other
    /// way, an encoder mounted reversed, the encoders swapped.
    Miswired = 10,
    /// Under the hybrid law the tip strayed more than 5 mm from `z_t*` for 3 ms
    /// ([`crate::tracking`]).
    Tracking = 11,
    /// Under the hybrid law lift-off stayed declared for 2 ms ([`crate::tracking::LIFT_OFF_S`]).
    LiftOff = 12,
    /// The board's acquisition of the encoders failed (issue 56: a DMA2
    /// transfer, FIFO or direct-mode error, frames not done by their deadline, a
    /// stuck chip select; RM0090 10.3.16) in `bad_frame_limit` consecutive
    /// periods. Latched by the board through
    /// [`Firmware::enter_safe_state`](super::Firmware::enter_safe_state) before
    /// that period's step (the `arm` image's application, `arm_app`), never by
    /// the step itself.
    Acquisition = 13,
    /// Under the hybrid law the tip strayed past its derived bound
    /// ([`crate::tracking`]) while the law had saturated a motor within the last
    /// 50 ms: the law could not act at its torque limit (friction or a force the
    /// motors cannot hold), not a fault of the wiring.
    Saturated = 14,
    /// The law's own failure, not a fault of the wiring: under the hybrid law
    /// with gains outside the envelope at this rate (`K'_D Ts` past 1, `K'_P
    /// Ts^2` past 0.25, `K'_I Ts` past 1, or a gain not positive:
    /// [`crate::config::KD_TS_MAX`]) the tracking or the lift-off check tripped;
    /// or, under either law, a motor's command chattered ([`crate::chatter`]:
    /// reversed by half the torque limit four periods in a row, the paper's PID
    /// from `x0u` at 250 Hz).
    Unstable = 15,
}

impl SafeReason {
    /// The reason of a status word, if the safe-state bit is set.
    pub fn from_status(status_word: u32) -> Option<Self> {
        if status_word & status::SAFE_STATE == 0 {
            return None;
        }
        match (status_word >> status::REASON_SHIFT) as u8 {
            1 => Some(Self::DeadlineMisses),
            2 => Some(Self::BadFrames),
            3 => Some(Self::NonFinite),
            4 => Some(Self::Singular),
            5 => Some(Self::Unreachable),
            6 => Some(Self::PeerLost),
            7 => Some(Self::SensorFault),
            8 => Some(Self::Runaway),
            9 => Some(Self::Overload),
            10 => Some(Self::Miswired),
            11 => Some(Self::Tracking),
            12 => Some(Self::LiftOff),
            13 => Some(Self::Acquisition),
            14 => Some(Self::Saturated),
            15 => Some(Self::Unstable),
            _ => None,
        }
    }

    /// Whether the check that latched it judges what the motors do (their
    /// torque against the joints' motion, the tip's tracking or contact, the
    /// command's chatter): with the drivers off it trips on a healthy arm, and
    /// a board logs it only once the drivers were on (`arm_app`, issue 80).
    pub fn needs_the_motors(self) -> bool {
        matches!(self, Self::Miswired | Self::Tracking | Self::LiftOff | Self::Saturated | Self::Unstable)
    }

    /// The reason in a few words, for the operator (no `core::fmt` on the image).
    pub fn describe(self) -> &'static str {
        match self {
            Self::DeadlineMisses => "too many consecutive deadline misses",
            Self::BadFrames => "too many consecutive bad or stale sensor frames",
            Self::NonFinite => "the control law produced a NaN or infinite value",
            Self::Singular => "the arm reached a singular (straight) configuration",
            Self::Unreachable => "the reference is out of the arm's reach",
            Self::PeerLost => "the plant or the link to it is gone",
            Self::SensorFault => {
                "the encoders and the load cell disagree about the tip (a stuck or failed sensor, a load cell of the wrong sign, or a driver fault)"
            }
            Self::Runaway => "a joint ran away: its speed passed 20 rad/s (a reversed motor, or motors that cannot hold the arm)",
            Self::Overload => {
                "the load cell stayed at full scale for 10 ms: the force ran away (a reversed motor, or the tip driven into the belt)"
            }
            Self::Tracking => {
                "the tip strayed past its derived bound (the error a quarter's error in mu_hat leaves, plus 5 mm), or away from it faster than that error can grow, under the force law for 3 ms (a motor or sensor wired wrong)"
            }
            Self::Unstable => {
                "the control law is unstable at this rate: its command chattered, or the force law's tip left its reference or the belt with its gains outside their envelope (raise the rate or lower the gains; with gains inside it, check the motors' wiring: a reversed motor can chatter first)"
            }
            Self::Saturated => {
                "the tip strayed past its derived bound under the force law while the law had saturated a motor: the motors cannot hold the arm on its reference (the law's limit, not a wiring fault)"
            }
            Self::LiftOff => {
                "the tip was off the belt, or the load cell read no force, for 10 ms under the force law (a motor or the load cell wired wrong, or the paradox's bounce)"
            }
            Self::Acquisition => {
                "the encoders' acquisition (SPI1 by DMA) failed in consecutive periods: a DMA transfer, FIFO or direct-mode error, frames not done in time, or a chip select stuck low"
            }
            Self::Miswired => {
                "a joint accelerated against its motor's torque for 5 ms (a motor wired the other way, an encoder reversed, or the encoders swapped)"
            }
        }
    }
}

impl From<LawError> for SafeReason {
    fn from(e: LawError) -> Self {
        match e {
            LawError::Unreachable => Self::Unreachable,
            LawError::Singular => Self::Singular,
            LawError::NonFinite => Self::NonFinite,
        }
    }
}
