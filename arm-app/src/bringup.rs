//! The bring-up protocol (issue 23; docs/board.md "Bring-up"): what an engineer
//! asks of the `arm` image over USART1, in the PIL wire's framing (postcard with
//! CRC-32C, COBS-framed: `firmware::pil::encode` and `decode`), and what it
//! answers. ODrive's `odrivetool` is the model: read the state and raw readings,
//! calibrate with the drivers off or at low torque, send a configuration, save.
//!
//! One request, one reply. A request that would move the arm (a jog) is
//! refused unless the drivers are disabled and the arm is not running; every
//! refusal says why ([`Refusal`]).

use firmware::Config;
use serde::{Deserialize, Serialize};

pub use crate::record::{CalibrationRecord, Missing, SpanStep};
use crate::{
    joint::{EncoderFault, Joint},
    record::{RecordFault, Settings, Stored},
    telemetry::ArmTelemetry,
};

/// The protocol's version, told in [`Reply::Hello`] (9: [`Status::law_digest`];
/// 8: the configuration's
/// `law`, a law of one's own's parameters; 7: the control rate set
/// by `Configure` and `Restore` within `crate::rate`'s range, the tick's period
/// in [`Status::period_us`], a jog's length bounded in time; 6:
/// `Refusal::ProtectionOff` and `Refusal::NothingToSave`,
/// `RecordFault::ProtectionOff`; the configuration's runaway limits always on).
pub const BRINGUP_PROTOCOL: u16 = 9;

/// The torque limit after a calibration, until the operator lifts it
/// ([`Request::LiftTorqueLimit`]): 1 N m, a fifth of full scale (410 codes).
pub const REDUCED_TORQUE_CODES: i16 = 410;

/// The largest jog: 0.5 N m (205 codes) for at most [`MAX_JOG_US`].
pub const MAX_JOG_CODES: i16 = 205;
/// The longest jog, us (0.5 s: 500 periods at 1 kHz, 5 000 at 10 kHz, 125 at
/// 250 Hz): a jog's `periods` times the tick's period.
pub const MAX_JOG_US: u64 = 500_000;
/// The most periods a jog can ask for (0.5 s at 10 kHz, the fastest rate);
/// at a slower rate [`MAX_JOG_US`] bounds it first.
pub const MAX_JOG_PERIODS: u16 = 5_000;

/// What the image is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Activity {
    /// The drivers are disabled; the firmware steps (a press of the enable
    /// button, or [`Request::Enable`], starts the closed loop).
    Idle,
    /// The closed loop runs with the drivers enabled.
    Running,
    /// A jog is under way.
    Jogging,
}

/// What became of the last enable (`Request::Enable` or the button), so that
/// the host can say whether the drivers came on, and if not why.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum EnableOutcome {
    /// No enable since power-up.
    NotAsked,
    /// Asked: the firmware resets at the next tick and the drivers enable at its
    /// first command that is not the safe state.
    Pending,
    /// The drivers came on at period `seq`.
    Enabled {
        /// The period.
        seq: u32,
    },
    /// The drivers refused to enable at period `seq` (nFAULT asserted, or a pin failed).
    DriversRefused {
        /// The period.
        seq: u32,
    },
    /// The firmware's command after its reset was the safe state: the drivers
    /// stayed off.
    SafeState {
        /// The period.
        seq: u32,
        /// The command's status word (`shared::wire::status`, the reason in bits 24..31).
        status: u32,
    },
    /// A `Disable` came before the drivers enabled.
    Cancelled,
}

/// The image's state, for `sil-host board status`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// What it is doing.
    pub activity: Activity,
    /// Periods run since power-up.
    pub periods: u32,
    /// The drivers are enabled.
    pub drivers_enabled: bool,
    /// The last command's status word (`shared::wire::status`).
    pub status: u32,
    /// Deadline overruns since the last reset.
    pub overruns: u32,
    /// The torque limit in force, codes (2048 = full scale).
    pub torque_limit_codes: i16,
    /// The encoders' zeros have been set since power-up or loaded from flash.
    pub zeros_set: bool,
    /// Both joints' directions were checked by a jog since power-up, or the
    /// record in flash says they were.
    pub directions_checked: bool,
    /// The settings in force against the record in flash: the drivers enable
    /// only when `Saved` (else the lockout, and why).
    pub settings: Settings,
    /// The bring-up steps the calibration in force lacks (`save` refuses it
    /// until none).
    pub missing: Missing,
    /// What became of the last enable.
    pub last_enable: EnableOutcome,
    /// The control period the board's tick runs, us (TIM2's reload on the
    /// image, from the configuration in force: `crate::rate`).
    pub period_us: u32,
    /// The digest of the image's control law's declaration
    /// (`firmware::LawSpec::digest`, a compile-time constant): the host
    /// binds a scenario's `[law]` table to the declaration it reads from the
    /// ELF that was flashed, and refuses one whose digest is not this
    /// (`sil-host board configure --elf`).
    pub law_digest: u32,
}

/// Raw readings, the drivers disabled or not (`sil-host board watch`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RawReadings {
    /// The period they were sampled in.
    pub seq: u32,
    /// Each encoder's raw ANGLECOM count, or why it gave none.
    pub encoder_counts: [Result<u16, EncoderFault>; 2],
    /// Each encoder's AGC (field strength: 0 strong, 255 weak), if readable.
    pub encoder_agc: [Option<u8>; 2],
    /// The ADC's raw counts `[f_t, f_n]`, if this period's conversion is there.
    pub adc_counts: Option<[u16; 2]>,
    /// The belt's counter.
    pub belt_count: u16,
    /// The drivers assert nFAULT.
    pub driver_fault: bool,
}

/// A request from the host.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Request {
    /// Which protocol the image speaks.
    Hello,
    /// The image's state.
    Status,
    /// The last period's raw readings.
    Raw,
    /// The calibration in force.
    GetCalibration,
    /// Sets the encoders' zeros so that the arm's current pose reads
    /// `pose_counts` (`[theta1, theta2 - theta1]` in counts of 2^14 per turn,
    /// in `[0, 2^14)`): the arm must stand at that pose (docs/board.md
    /// "Bring-up": the calibration pose, held by its jig). Drivers disabled only.
    SetZeros {
        /// The pose's joint counts.
        pose_counts: [u16; 2],
    },
    /// Jogs `joint` with torque `code` (at most [`MAX_JOG_CODES`]) for
    /// `periods` of the tick (at most [`MAX_JOG_US`] long: the host converts a
    /// time with [`Status::period_us`]), the other joint at zero torque,
    /// then disables the drivers. Drivers disabled and zeros set only. The
    /// reply comes with [`Request::JogResult`].
    Jog {
        /// The joint.
        joint: Joint,
        /// The torque code (sign: the direction to move).
        code: i16,
        /// How long.
        periods: u16,
    },
    /// The last jog's result.
    JogResult,
    /// Sets the load cell's zero counts to the current counts (nothing on the
    /// load cell). Drivers disabled only.
    Tare,
    /// Sets the gain of `axis` (0: f_t, 1: f_n) from a known force `newtons` on
    /// it now: `gain = newtons / (count - zero)`. Drivers disabled and the load
    /// cell tared only.
    Span {
        /// 0: tangential, 1: normal.
        axis: u8,
        /// The force applied, N (a weight: `m g`).
        newtons: f32,
    },
    /// Keeps the nominal gain of `axis` (0: f_t, 1: f_n) instead of measuring
    /// its span (no known weight at hand); the record says so. Drivers disabled only.
    SkipSpan {
        /// 0: tangential, 1: normal.
        axis: u8,
    },
    /// Takes a whole calibration (a saved one, restored), its bring-up steps as
    /// it says, except that new encoder zeros or directions clear its direction
    /// checks. Drivers disabled only.
    SetCalibration(CalibrationRecord),
    /// Takes a firmware configuration (controller, gains, rate, limits), which
    /// the firmware validates. Drivers disabled only; the control period must be
    /// one the image runs (`crate::rate`: 100 to 4000 us, else
    /// [`Refusal::Rate`]), and the board's tick follows it at once (TIM2's
    /// reload; [`Status::period_us`] then reports it); the runaway limits must
    /// be on ([`Refusal::ProtectionOff`]). A belt scale in force that the new
    /// period puts out of range is [`Refusal::OutOfRange`].
    Configure(Config),
    /// Lifts the reduced torque limit a calibration set.
    LiftTorqueLimit,
    /// The enable button: resets the firmware and enables the drivers at the next
    /// command that is not the safe state.
    Enable,
    /// Disables the drivers now (the firmware goes on stepping).
    Disable,
    /// The last window's telemetry (`step_stats::WINDOW` periods: the step's
    /// ticks, the tick's interval, overruns).
    Telemetry,
    /// Saves the calibration and configuration in force to the flash record
    /// (`crate::record`), then reads it back. Drivers disabled, a complete
    /// calibration (`CalibrationRecord::missing` empty) and something unsaved
    /// ([`Refusal::NothingToSave`]: the settings in force are the record) only. The
    /// control loop pauses while the sector erases (about 1 s on the STM32F405).
    Save,
    /// The firmware configuration in force.
    GetConfig,
    /// Restores a backup (`sil-host board restore FILE`): the calibration and the
    /// configuration together, both or neither. The firmware validates them as it
    /// validates the flash record at reset (the same checks: the configuration by
    /// `Firmware::new` with the runaway limits on, the encoders' zeros below 2^14,
    /// the load cell's calibration, the belt's scale at the control period), and
    /// the rate must be one the image runs (`crate::rate`; the tick follows it
    /// as for `Configure`). The calibration's bring-up steps are taken as recorded (a
    /// backup of this board: the steps were done with these very values); a
    /// calibration that differs from the one in force runs at the reduced torque
    /// limit until lifted, and any change is unsaved (the drivers locked out until
    /// `Save`). Drivers disabled only. Refused: `DriversEnabled`, `Busy`, `Rate`,
    /// `InvalidConfig`, `OutOfRange` (the calibration), with nothing changed.
    Restore(Stored),
}

/// A jog's result: how far each joint moved, in counts of the calibrated joint
/// angle (signed: the joint's positive direction), and the verdict.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JogOutcome {
    /// The joint jogged.
    pub joint: Joint,
    /// The torque code applied.
    pub code: i16,
    /// Change of `[theta1, theta2 - theta1]` over the jog, counts (2^14 per turn).
    pub moved_counts: [i32; 2],
    /// `Ok` when the jogged joint moved the way its torque pushed, by at least
    /// [`MIN_JOG_COUNTS`] and at most [`MAX_JOG_COUNTS`]; else why not.
    pub verdict: Result<(), JogFault>,
}

/// The least movement a jog must show, counts (0.7 degrees).
pub const MIN_JOG_COUNTS: i32 = 32;
/// The most a jog may move a joint, counts (30 degrees): the jog stops there.
pub const MAX_JOG_COUNTS: i32 = 1365;

/// The least count difference a span takes: below it the ADC's noise and
/// quantisation (about 2 counts rms on the reference board) would make the gain
/// wrong by more than 5 %.
pub const MIN_SPAN_COUNTS: u16 = 40;

/// Why a jog failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum JogFault {
    /// The joint moved against its torque: the motor is wired the other way or
    /// the encoder counts the other way (swap one, or set `reversed`).
    WrongDirection,
    /// The joint did not move (less than [`MIN_JOG_COUNTS`]): motor, driver or
    /// encoder not connected, or the arm is blocked.
    NoMotion,
    /// The joint moved more than [`MAX_JOG_COUNTS`]: the jog was stopped there.
    TooFar,
    /// An encoder gave no reading during the jog.
    EncoderFault,
    /// The drivers refused to enable (nFAULT asserted).
    DriversRefused,
}

/// Why a request was refused.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Refusal {
    /// The drivers are enabled, or the closed loop runs: disable first.
    DriversEnabled,
    /// A jog needs the encoders' zeros set first.
    ZerosNotSet,
    /// A value is out of its range (the jog's torque or length, the span's axis
    /// or force, a zero count).
    OutOfRange,
    /// The encoders gave no reading.
    EncoderFault(EncoderFault),
    /// The ADC gave no conversion this period.
    NoConversion,
    /// The span's force gives less than `MIN_SPAN_COUNTS` (40) counts of
    /// difference from the tare (nothing on the load cell? too light a weight?).
    NoSpan,
    /// The configuration is invalid (`firmware::Config::validate` says why: the
    /// host checks it before sending).
    InvalidConfig,
    /// The configuration's control period is not one the image runs
    /// (`crate::rate`: 100 to 4000 us, 10 kHz to 250 Hz); or, to an enable, the
    /// board's tick does not run the configuration's period.
    Rate,
    /// No jog has run since power-up.
    NoJog,
    /// A jog is under way: ask again.
    Busy,
    /// Lifting the reduced torque limit needs both joints' directions checked
    /// by a jog first.
    DirectionsNotChecked,
    /// The drivers are locked out: the settings in force are not the record in
    /// flash (missing, corrupt, or changed and not saved).
    LockedOut(Settings),
    /// The save failed, and why.
    Flash(RecordFault),
    /// The calibration lacks these bring-up steps: `Save` refuses it (and
    /// `Span` refuses before the tare).
    Incomplete(Missing),
    /// The configuration turns the runaway limits off (`Config::runaway_limits`
    /// false): a board never runs without them (`Configure`, `Restore`; a flash
    /// record holding it is refused at reset, `RecordFault::ProtectionOff`). The
    /// studies that need them off run without a board (docs/board.md "Runaway
    /// limits").
    ProtectionOff,
    /// `Save` with nothing to save: the settings in force are already the record
    /// in flash (loaded at the last reset, or saved since). A change sent before a
    /// reset was discarded by it (a reset reloads the record): send it again.
    NothingToSave,
}

/// A reply to a [`Request`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Reply {
    /// [`BRINGUP_PROTOCOL`].
    Hello {
        /// The protocol version.
        protocol: u16,
    },
    /// The state.
    Status(Status),
    /// Raw readings.
    Raw(RawReadings),
    /// The calibration in force (after a change: the new one).
    Calibration(CalibrationRecord),
    /// A jog's result.
    Jogged(JogOutcome),
    /// The last window's telemetry (`None` before the first window closes).
    Telemetry(Option<ArmTelemetry>),
    /// The firmware configuration in force.
    Config(Config),
    /// Done.
    Done,
    /// Refused, and why.
    Refused(Refusal),
}
