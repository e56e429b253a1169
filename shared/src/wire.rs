//! Wire messages between the plant side and the firmware (docs/hardware.md): raw
//! counts as the hardware gives them, `#[repr(C)]` with fixed layouts so that
//! shared memory, a USART frame or a C client see the same bytes.
//!
//! With the `iceoryx2` feature (host only) the messages derive iceoryx2's
//! `ZeroCopySend` with stable type names, so a C, C++ or Python iceoryx2 client
//! can attach to the rig's services (docs/wire.md, the layouts below):
//!
//! | type | iceoryx2 type name | size |
//! |---|---|---|
//! | [`SensorFrame`] | `painleve::SensorFrame` | 24 B |
//! | [`ActuatorCommand`] | `painleve::ActuatorCommand` | 32 B |
//! | [`GroundTruth`] | `painleve::GroundTruth` | 96 B |
//! | [`FirmwareTelemetry`] | `painleve::FirmwareTelemetry` | 48 B |
//! | [`FirmwareAnnouncement`] | `painleve::FirmwareAnnouncement` | 920 B |
//!
//! [`WIRE_VERSION`] names these layouts: a plant and a firmware built from
//! different layouts refuse each other at the handshake (docs/rig.md).

#[cfg(feature = "iceoryx2")]
use iceoryx2::prelude::ZeroCopySend;

/// Version of the shared-memory layouts above (the iceoryx2 rig's wire). It goes
/// up whenever one of them changes; the plant sends its version in the handshake
/// frame ([`frame_flags::HELLO`]) and the firmware its own in its
/// [`FirmwareAnnouncement`], and each side refuses a different one. The PIL
/// serial protocol has its own version (`firmware::pil::PROTOCOL_VERSION`).
///
/// Version 2 (issue 70): the announcement carries the law's declared
/// configuration ([`FirmwareAnnouncement::law`]).
pub const WIRE_VERSION: u32 = 2;

/// Bytes a [`FirmwareAnnouncement`] holds for the firmware's encoded configuration.
pub const ANNOUNCEMENT_CONFIG_BYTES: usize = 384;

/// Bytes a [`FirmwareAnnouncement`] holds for the law's encoded declaration
/// (`firmware::law_spec::LawSpec`: its name, source and parameters).
pub const ANNOUNCEMENT_LAW_BYTES: usize = 512;

/// Encoder resolution of the reference board: 14 bit per revolution (docs/hardware.md).
pub const ENCODER_BITS: u8 = 14;
/// Encoder counts per revolution at [`ENCODER_BITS`].
pub const ENCODER_COUNTS: u32 = 1 << ENCODER_BITS;
/// Encoder resolutions a configuration may give (bits per revolution): the wire's
/// `u16` counts hold up to 16 bits. Both sides of the wire must use the same one
/// (the scenario's `sensors.encoder_bits`, the firmware's `Config::encoder_bits`).
pub const ENCODER_BITS_RANGE: (u8, u8) = (10, 16);
/// Load-cell ADC: 12-bit signed codes in `[-2048, 2047]` (docs/hardware.md).
pub const LOAD_CODE_MIN: i16 = -2048;
/// Largest load-cell code.
pub const LOAD_CODE_MAX: i16 = 2047;
/// Load-cell full scale, N (docs/hardware.md: +-25 N).
pub const LOAD_FULL_SCALE_N: f32 = 25.0;
/// Torque command: 12-bit signed codes in `[-2048, 2047]` (docs/hardware.md).
pub const TORQUE_CODE_MIN: i16 = -2048;
/// Largest torque code.
pub const TORQUE_CODE_MAX: i16 = 2047;
/// Torque full scale per joint, N m (docs/hardware.md: +-5 N m).
pub const TORQUE_FULL_SCALE_NM: f32 = 5.0;
/// Belt encoder resolution, m/s per count (docs/hardware.md: 1 mm/s).
pub const BELT_SPEED_RESOLUTION: f32 = 1e-3;

/// One sample of the sensors, period `seq` (docs/hardware.md "Sensors").
///
/// Layout (24 bytes, little-endian on every target we build): `t_us: u64`,
/// `seq: u32`, `theta1_count: u16`, `elbow_count: u16`, `f_t_code: i16`,
/// `f_n_code: i16`, `belt_count: i16`, `flags: u16`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend), type_name("painleve::SensorFrame"))]
#[repr(C)]
pub struct SensorFrame {
    /// Sample time `t_k = k Ts`, microseconds since the start of the run.
    pub t_us: u64,
    /// Period index `k` (increments by one per period).
    pub seq: u32,
    /// Base-joint absolute encoder, `theta1` in counts of `2 pi / 2^14`, in `[0, 2^14)`.
    pub theta1_count: u16,
    /// Elbow absolute encoder, `theta2 - theta1` in counts of `2 pi / 2^14`, in `[0, 2^14)`.
    pub elbow_count: u16,
    /// Tip load cell, tangential force `f_t` in codes of `25/2048 N`, in `[-2048, 2047]`.
    pub f_t_code: i16,
    /// Tip load cell, normal force `f_n` in codes of `25/2048 N`, in `[-2048, 2047]`.
    pub f_n_code: i16,
    /// Belt speed `v_belt` in mm/s.
    pub belt_count: i16,
    /// Sensor-side bits ([`frame_flags`]): a sensor that could not produce a
    /// reading (NaN) says so here and sends count 0; the end of a run.
    pub flags: u16,
}

/// Bits of [`SensorFrame::flags`].
pub mod frame_flags {
    /// The base-joint encoder gave no valid reading.
    pub const THETA1_INVALID: u16 = 1 << 0;
    /// The elbow encoder gave no valid reading.
    pub const ELBOW_INVALID: u16 = 1 << 1;
    /// The load cell's tangential channel gave no valid reading.
    pub const F_T_INVALID: u16 = 1 << 2;
    /// The load cell's normal channel gave no valid reading.
    pub const F_N_INVALID: u16 = 1 << 3;
    /// The belt encoder gave no valid reading.
    pub const BELT_INVALID: u16 = 1 << 4;
    /// A motor driver asserts its fault line (reference board): the reading
    /// "drivers healthy" is invalid, so the frame is not trusted either.
    pub const DRIVER_FAULT: u16 = 1 << 5;
    /// Any sensor invalid (the driver fault line included).
    pub const ANY_INVALID: u16 = THETA1_INVALID | ELBOW_INVALID | F_T_INVALID | F_N_INVALID | BELT_INVALID | DRIVER_FAULT;
    /// The plant ends the run: no command is expected for this frame (SIL rig only).
    pub const END_OF_RUN: u16 = 1 << 15;
    /// The handshake before period 0 (SIL rig only): the plant asks the firmware
    /// to announce its configuration ([`super::FirmwareAnnouncement`]); `t_us`
    /// carries the plant's [`super::WIRE_VERSION`]. No command answers it.
    pub const HELLO: u16 = 1 << 14;
}

/// Status word bits of an [`ActuatorCommand`].
pub mod status {
    /// The firmware is in its safe state (zero torque); the reason is in bits 24..31.
    pub const SAFE_STATE: u32 = 1 << 0;
    /// This frame was rejected (out-of-range counts or bad sequence); not trusted.
    pub const BAD_FRAME: u32 = 1 << 1;
    /// This frame repeated or went back in sequence (stale).
    pub const STALE_FRAME: u32 = 1 << 2;
    /// One or more periods were skipped before this frame (lost frames).
    pub const SEQUENCE_GAP: u32 = 1 << 3;
    /// Lift-off detected (the firmware believes the tip is off the belt).
    pub const LIFT_OFF: u32 = 1 << 4;
    /// The base-joint torque `u1` saturated.
    pub const SATURATED_U1: u32 = 1 << 5;
    /// The elbow torque `u2` saturated.
    pub const SATURATED_U2: u32 = 1 << 6;
    /// The previous step overran its deadline.
    pub const DEADLINE_MISS: u32 = 1 << 7;
    /// The load-cell reading is at the end of its range (clipped).
    pub const LOAD_CLIPPED: u32 = 1 << 8;
    /// The reference is still moving (before the hold).
    pub const REFERENCE_MOVING: u32 = 1 << 9;
    /// Shift of the safe-state reason code (see `SafeReason` in the firmware).
    pub const REASON_SHIFT: u32 = 24;
}

impl SensorFrame {
    /// The sample time [`SensorFrame::t_us`] as an [`Instant`](crate::time::Instant).
    pub const fn sampled_at(&self) -> crate::time::Instant {
        crate::time::Instant::from_us(self.t_us)
    }
}

/// The firmware's answer to frame `seq` (docs/hardware.md "Actuators").
///
/// Layout (32 bytes): `t_sent_us: u64`, `seq: u32`, `u1_code: i16`, `u2_code: i16`,
/// `status: u32`, `step_ticks: u32`, `overruns: u32`, `reserved: u32`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend), type_name("painleve::ActuatorCommand"))]
#[repr(C)]
pub struct ActuatorCommand {
    /// When the command left the firmware, microseconds on the clock of
    /// [`SensorFrame::t_us`] (the step's start plus its own execution time). The
    /// plant applies it at `max(t_k + delta, t_sent_us)`; later than `t_k + Ts` is a
    /// deadline miss (docs/hardware.md "Timing").
    pub t_sent_us: u64,
    /// Echo of the [`SensorFrame::seq`] this command answers.
    pub seq: u32,
    /// Base-joint motor torque `u1` in codes of `5/2048 N m`, in `[-2048, 2047]`.
    pub u1_code: i16,
    /// Elbow motor torque `u2` in codes of `5/2048 N m`, in `[-2048, 2047]`.
    pub u2_code: i16,
    /// Status bits ([`status`]).
    pub status: u32,
    /// The step's own execution time, in ticks of the firmware's clock.
    pub step_ticks: u32,
    /// Deadline overruns counted since the last reset.
    pub overruns: u32,
    /// Reserved (explicit padding), 0.
    pub reserved: u32,
}

/// The plant's ground truth of period `seq`, for monitors (SIL rig): what no
/// sensor measures. Sizes: 96 bytes; `f64` SI units, radians.
///
/// Layout: `t: f64`, `seq: u32`, `mode: u8`, `lift_off: u8`, `reserved: u16`,
/// `x: [f64; 4]`, `z: [f64; 2]`, `f: [f64; 2]`, `u_applied: [f64; 2]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend), type_name("painleve::GroundTruth"))]
#[repr(C)]
pub struct GroundTruth {
    /// Sample time `t_k`, s.
    pub t: f64,
    /// Period index `k`.
    pub seq: u32,
    /// Contact mode: 0 flight, 1 sliding, 2 sticking.
    pub mode: u8,
    /// 1 when the tip is off the belt (true lift-off), else 0.
    pub lift_off: u8,
    /// Reserved (explicit padding), 0.
    pub reserved: u16,
    /// State `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s).
    pub x: [f64; 4],
    /// Tip position `[z_t, z_n]`, m.
    pub z: [f64; 2],
    /// Contact force `[f_t, f_n]`, N.
    pub f: [f64; 2],
    /// Motor torques `[u1, u2]` applied at `t_k`, N m.
    pub u_applied: [f64; 2],
}

/// What the firmware computed for frame `seq` (its telemetry: the SIL trace
/// records the reference from it). Sizes: 48 bytes; `f32` SI units, radians.
///
/// Layout: `seq: u32`, `status: u32`, `z_t_ref: f32`, `f_n_ref: f32`,
/// `q: [f32; 2]`, `qd: [f32; 2]`, `f: [f32; 2]`, `u_raw: [f32; 2]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend), type_name("painleve::FirmwareTelemetry"))]
#[repr(C)]
pub struct FirmwareTelemetry {
    /// The frame this answers.
    pub seq: u32,
    /// The command's status word.
    pub status: u32,
    /// Tangential reference `z_t*`, m.
    pub z_t_ref: f32,
    /// Normal-force reference `f_n*` (after the ramp), N.
    pub f_n_ref: f32,
    /// Estimated `[theta1, theta2]`, rad.
    pub q: [f32; 2],
    /// Estimated `[theta1_dot, theta2_dot]`, rad/s.
    pub qd: [f32; 2],
    /// Measured `[f_t, f_n]`, N.
    pub f: [f32; 2],
    /// Motor torques before saturation and quantisation, N m.
    pub u_raw: [f32; 2],
}

/// The firmware's answer to the handshake frame ([`frame_flags::HELLO`]): its wire
/// version, its whole configuration as it will run, and what its control law
/// declares about its own settings, so the plant can map a scenario's `[law]`
/// table onto the law's parameters, check their ranges and refuse a firmware
/// configured differently from its scenario before period 0 (SIL rig,
/// docs/rig.md "Handshake"). Size: 920 bytes.
///
/// Layout: `wire_version: u32`, `config_len: u32`, `config_hash: u64`,
/// `config: [u8; 384]`, `law_len: u32`, `reserved: u32`, `law: [u8; 512]`.
/// `config[..config_len]` is the firmware's `Config` in postcard's encoding
/// (`firmware::announce`); `config_hash` is the CRC-64/XZ of those bytes, the
/// short name of a configuration in logs and `summary.json`;
/// `law[..law_len]` is the law's `firmware::law_spec::LawSpec` in postcard's
/// encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend), type_name("painleve::FirmwareAnnouncement"))]
#[repr(C)]
pub struct FirmwareAnnouncement {
    /// The firmware's [`WIRE_VERSION`].
    pub wire_version: u32,
    /// Bytes of `config` used.
    pub config_len: u32,
    /// CRC-64/XZ of `config[..config_len]`.
    pub config_hash: u64,
    /// The encoded configuration, zero-padded.
    pub config: [u8; ANNOUNCEMENT_CONFIG_BYTES],
    /// Bytes of `law` used.
    pub law_len: u32,
    /// Zero (keeps `law` 8-byte aligned for C clients).
    pub reserved: u32,
    /// The law's encoded declaration, zero-padded.
    pub law: [u8; ANNOUNCEMENT_LAW_BYTES],
}

impl Default for FirmwareAnnouncement {
    /// This wire version, an empty configuration.
    fn default() -> Self {
        Self {
            wire_version: WIRE_VERSION,
            config_len: 0,
            config_hash: 0,
            config: [0; ANNOUNCEMENT_CONFIG_BYTES],
            law_len: 0,
            reserved: 0,
            law: [0; ANNOUNCEMENT_LAW_BYTES],
        }
    }
}

/// Encodes an angle (rad) as a 14-bit absolute encoder count (rounded, wrapped to `[0, 2^14)`).
pub fn encode_angle(angle: f64) -> u16 {
    encode_angle_bits(angle, ENCODER_BITS)
}

/// Encodes an angle (rad) as the count of a `bits`-bit absolute encoder (rounded,
/// wrapped to `[0, 2^bits)`; `bits` is clamped to [`ENCODER_BITS_RANGE`]).
pub fn encode_angle_bits(angle: f64, bits: u8) -> u16 {
    let counts = 1u32 << bits.clamp(ENCODER_BITS_RANGE.0, ENCODER_BITS_RANGE.1);
    let turns = angle / core::f64::consts::TAU;
    let frac = turns - crate::rounding::floor(turns);
    let count = crate::rounding::round(frac * counts as f64) as u32 % counts;
    count as u16
}

/// Encodes a force (N) as a 12-bit load-cell code; saturates at the ends of the range.
pub fn encode_force(force: f64) -> i16 {
    let code = crate::rounding::round(force / (LOAD_FULL_SCALE_N as f64) * 2048.0);
    if !code.is_finite() {
        return 0;
    }
    code.clamp(LOAD_CODE_MIN as f64, LOAD_CODE_MAX as f64) as i16
}

/// Decodes a torque code to N m.
pub fn decode_torque(code: i16) -> f32 {
    code as f32 * (TORQUE_FULL_SCALE_NM / 2048.0)
}

/// Codes per N m of the torque codes: `2048 / TORQUE_FULL_SCALE_NM`, rounded to `f32`.
const TORQUE_CODES_PER_NM: f32 = 2048.0 / TORQUE_FULL_SCALE_NM;

/// Encodes a torque (N m) as a 12-bit code, saturating; returns the code and whether
/// it saturated (a non-finite torque: code 0, saturated).
///
/// The code is `round(torque * 2048 / TORQUE_FULL_SCALE_NM)` (halfway away from
/// zero) within `[TORQUE_CODE_MIN, TORQUE_CODE_MAX]`: the scale is one product by
/// [`TORQUE_CODES_PER_NM`] (a division is 14 cycles on the M4F, and the firmware
/// encodes two torques a step), within one rounding of the quotient
/// `torque / TORQUE_FULL_SCALE_NM * 2048` (test below), so a code can differ from
/// the quotient's only for a torque within 2^-23 of a code's half.
/// It saturates when the rounded code leaves the range, that is from `x >= 2047.5`
/// or `x <= -2048.5` (compared on `x`, before rounding).
// Inlined: the firmware's step encodes two torques, and a call each cost about 12
// cycles of the step (issue 56).
#[inline(always)]
pub fn encode_torque(torque: f32) -> (i16, bool) {
    let x = torque * TORQUE_CODES_PER_NM;
    // The range's comparisons first (false for a NaN), the infinities among the
    // out-of-range values, a NaN by `x != x`: the verdicts of a finiteness check
    // first, with float comparisons (issue 56: the check was integer code).
    if x >= TORQUE_CODE_MAX as f32 + 0.5 {
        if x == f32::INFINITY { (0, true) } else { (TORQUE_CODE_MAX, true) }
    } else if x <= TORQUE_CODE_MIN as f32 - 0.5 {
        if x == f32::NEG_INFINITY { (0, true) } else { (TORQUE_CODE_MIN, true) }
    } else if x.is_nan() {
        (0, true)
    } else {
        // Within the range: through i32 (one VCVT) rather than `as i16`'s saturating compares.
        (round_half_away(x) as i32 as i16, false)
    }
}

/// `x` rounded to the nearest integer, halfway cases away from zero (`roundf`),
/// for `|x| <= 2^22`: the truncation (one `VCVT`) and the exact remainder `x - trunc x`,
/// about 8 instructions on the MCU against `libm::roundf`'s bit manipulation.
/// The same value as `libm::roundf` (test below) but for the sign of a zero.
#[inline]
fn round_half_away(x: f32) -> f32 {
    let t = x as i32 as f32;
    let f = x - t;
    if f >= 0.5 {
        t + 1.0
    } else if f <= -0.5 {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `round_half_away` equals `libm::roundf` on every f32 in [-2^22, 2^22] (a
    /// stride through their bits, and every halfway case near the code range), so
    /// the torque codes did not change; torques beyond the range saturate as before.
    #[test]
    fn rounding_equals_roundf_and_codes_saturate() {
        let mut bits: u32 = 0;
        while bits <= 0x4a80_0000 {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                assert!(round_half_away(x) == libm::roundf(x), "x = {x:e}");
            }
            bits += 997;
        }
        for k in -4200..4200 {
            let x = k as f32 + 0.5;
            for y in [x, f32::from_bits(x.to_bits() + 1), f32::from_bits(x.to_bits() - 1)] {
                assert!(round_half_away(y) == libm::roundf(y), "x = {y:e}");
            }
        }
        assert_eq!(encode_torque(1e30), (TORQUE_CODE_MAX, true));
        assert_eq!(encode_torque(-1e30), (TORQUE_CODE_MIN, true));
        assert_eq!(encode_torque(f32::NAN), (0, true));
        assert_eq!(encode_torque(5.0 * 2047.0 / 2048.0), (2047, false));
        assert_eq!(encode_torque(5.0 * 2047.6 / 2048.0), (2047, true));
    }

    #[test]
    fn layouts_are_fixed() {
        assert_eq!(core::mem::size_of::<SensorFrame>(), 24);
        assert_eq!(core::mem::size_of::<ActuatorCommand>(), 32);
        assert_eq!(core::mem::size_of::<GroundTruth>(), 96);
        assert_eq!(core::mem::size_of::<FirmwareTelemetry>(), 48);
        assert_eq!(core::mem::size_of::<FirmwareAnnouncement>(), 920);
    }

    #[test]
    fn angle_encoding_round_trips_within_one_count() {
        let lsb = core::f64::consts::TAU / ENCODER_COUNTS as f64;
        for i in -2000..2000 {
            let a = i as f64 * 0.00317;
            let c = encode_angle(a);
            let back = c as f64 * lsb;
            let d = (back - a).rem_euclid(core::f64::consts::TAU);
            let d = d.min(core::f64::consts::TAU - d);
            assert!(d <= 0.5 * lsb + 1e-12);
        }
    }

    /// The encoding as it was (the quotient `torque / 5 * 2048`, clamped, rounded,
    /// clamped again): the reference of the product form.
    fn encode_torque_by_quotient(torque: f32) -> (i16, bool) {
        let x = torque / TORQUE_FULL_SCALE_NM * 2048.0;
        if !x.is_finite() {
            return (0, true);
        }
        let code = libm::roundf(x.clamp(-4096.0, 4096.0));
        let clamped = code.clamp(TORQUE_CODE_MIN as f32, TORQUE_CODE_MAX as f32);
        (clamped as i32 as i16, clamped != code)
    }

    /// The product by `2048 / 5` is within one rounding of the quotient: each is
    /// the exact `2048 t / 5` rounded once, but for the constant's own rounding
    /// (relative 2^-24 at most), so the two differ by at most one ulp of `x`. The
    /// codes are then the quotient's, saturation included, except for an `x` within
    /// an ulp of a code's half; and every torque of the range (a dense sweep through
    /// the f32 bits from 1e-30 to 2.5 times the full scale, both signs) agrees so.
    #[test]
    fn torque_codes_from_the_product_are_the_quotients() {
        // From 1e-30 N m: below, the quotient's `t / 5` is subnormal (fewer bits); every code there is 0.
        let mut bits: u32 = 1e-30f32.to_bits();
        let mut differ = 0usize;
        let end = (2.5 * TORQUE_FULL_SCALE_NM).to_bits();
        while bits <= end {
            for t in [f32::from_bits(bits), -f32::from_bits(bits)] {
                let (xp, xq) = (t * TORQUE_CODES_PER_NM, t / TORQUE_FULL_SCALE_NM * 2048.0);
                let ulp = f32::from_bits(xq.abs().to_bits() + 1) - xq.abs();
                assert!((xp - xq).abs() <= ulp, "t = {t:e}: {xp:e} against {xq:e}");
                let (new, old) = (encode_torque(t), encode_torque_by_quotient(t));
                if new != old {
                    // Only across a code's half: the quotient within one ulp of k + 1/2.
                    let half = xq.abs() - xq.abs().floor();
                    assert!((half - 0.5).abs() <= ulp, "t = {t:e}: {new:?} against {old:?}");
                    differ += 1;
                }
            }
            bits += 101;
        }
        assert!(differ < 20, "{differ} codes differ");
        // The saturation's edges exactly: the largest torques whose `x` is below the
        // code range's halves keep their codes, the next ones saturate.
        let next = |t: f32| f32::from_bits(t.to_bits() + 1);
        for (half, code) in [(2047.5f32, TORQUE_CODE_MAX), (-2048.5, TORQUE_CODE_MIN)] {
            let mut t = half / TORQUE_CODES_PER_NM;
            while (t * TORQUE_CODES_PER_NM).abs() >= half.abs() {
                t = f32::from_bits(t.to_bits() - 1);
            }
            assert_eq!(encode_torque(t), (code, false), "below {half}");
            assert_eq!(encode_torque(next(t)), (code, true), "at {half}");
        }
        for t in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 0.0, -0.0, 1e30, -1e30] {
            assert_eq!(encode_torque(t), encode_torque_by_quotient(t), "t = {t}");
        }
    }

    /// The comparisons-first form has the verdicts of the finiteness check first
    /// (the form before issue 56's fourth round) over a sweep of every bit pattern's
    /// neighbourhood: the infinities and the NaNs (both signs, any payload) give
    /// `(0, true)`, and every other value the same code.
    #[test]
    fn torque_encoding_matches_the_finiteness_check_first() {
        let before = |torque: f32| {
            let x = torque * TORQUE_CODES_PER_NM;
            if !x.is_finite() {
                (0, true)
            } else if x >= TORQUE_CODE_MAX as f32 + 0.5 {
                (TORQUE_CODE_MAX, true)
            } else if x <= TORQUE_CODE_MIN as f32 - 0.5 {
                (TORQUE_CODE_MIN, true)
            } else {
                (round_half_away(x) as i32 as i16, false)
            }
        };
        let mut bits = 0u32;
        loop {
            for b in [bits, bits.wrapping_add(1), bits.wrapping_sub(1)] {
                let t = f32::from_bits(b);
                assert_eq!(encode_torque(t), before(t), "t = {t:e} ({b:#x})");
            }
            let (next, over) = bits.overflowing_add(4099);
            if over {
                break;
            }
            bits = next;
        }
        for t in [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7f80_0001),
            f32::from_bits(0xffc0_1234),
            f32::MAX,
            f32::MIN,
        ] {
            assert_eq!(encode_torque(t), before(t), "t = {t:e}");
        }
    }

    #[test]
    fn torque_encoding_saturates_and_reports_it() {
        assert_eq!(encode_torque(10.0), (2047, true));
        assert_eq!(encode_torque(-10.0), (-2048, true));
        assert_eq!(encode_torque(f32::NAN), (0, true));
        assert_eq!(encode_torque(-f32::NAN), (0, true));
        assert_eq!(encode_torque(f32::INFINITY), (0, true));
        assert_eq!(encode_torque(f32::NEG_INFINITY), (0, true));
        let (c, sat) = encode_torque(1.0);
        assert!(!sat);
        assert!((decode_torque(c) - 1.0).abs() <= 5.0 / 2048.0 / 2.0 + 1e-6);
    }
}
