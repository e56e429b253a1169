//! Decoding and checking a sensor frame (docs/hardware.md "Sensors").

use core::f32::consts::{PI, TAU};

use shared::wire::{self, SensorFrame, status};

/// A frame in SI units, after its checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// `theta1`, rad, in `(-pi, pi]`.
    pub theta1: f32,
    /// `theta2 - theta1` (elbow encoder), rad, in `(-pi, pi]`.
    pub elbow: f32,
    /// Tangential tip force `f_t`, N.
    pub f_t: f32,
    /// Normal tip force `f_n`, N.
    pub f_n: f32,
    /// Belt speed `v_belt`, m/s.
    pub v_belt: f32,
    /// Status bits raised by decoding (`LOAD_CLIPPED`).
    pub flags: u32,
}

/// Why a frame is not trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFault {
    /// An encoder count is outside `[0, 2^14)`.
    EncoderOutOfRange,
    /// A load-cell code is outside `[-2048, 2047]`.
    LoadOutOfRange,
    /// The belt speed is beyond +-5 m/s (no belt runs that fast: a corrupt frame).
    BeltOutOfRange,
    /// The sequence number repeats or goes back.
    Stale,
    /// A sensor flagged its reading invalid ([`wire::frame_flags`]).
    SensorInvalid,
}

impl FrameFault {
    /// The status bits that report it.
    pub fn status_bits(self) -> u32 {
        match self {
            Self::Stale => status::BAD_FRAME | status::STALE_FRAME,
            _ => status::BAD_FRAME,
        }
    }
}

/// Wraps an angle to `(-pi, pi]`.
#[inline(always)]
pub fn wrap(angle: f32) -> f32 {
    // `%` is a software `fmodf` on the MCU; within one turn it returns `angle`
    // itself (fmod is exact), so only larger angles pay for it.
    let a = if angle.abs() < TAU { angle } else { rem_turn(angle) };
    // `a > PI` and `a <= -PI` exclude each other: two selects, no branch (the
    // usual angle, within the turn, took one and its pipeline refill).
    let up = if a <= -PI { a + TAU } else { a };
    if a > PI { a - TAU } else { up }
}

/// [`wrap`] of the sum of two decoded angles (each in `(-pi, pi]` as
/// [`decode_with`] makes them, so the sum lies in `(-2 pi, 2 pi]`): the same bits
/// without the remainder's range check, which such a sum never needs (test
/// `the_sum_of_two_decoded_angles_wraps_as_wrap`; at `2 pi` itself both give
/// `+0`). Issue 56: the elbow's absolute angle, every step.
#[inline(always)]
pub fn wrap_sum(angle: f32) -> f32 {
    let up = if angle <= -PI { angle + TAU } else { angle };
    if angle > PI { angle - TAU } else { up }
}

/// `angle % TAU`, out of line: LLVM would otherwise compute the remainder on
/// both branches of [`wrap`] (a select), calling `fmodf` every time.
#[cold]
#[inline(never)]
fn rem_turn(angle: f32) -> f32 {
    angle % TAU
}

/// Decodes the counts of `frame` into SI units (docs/hardware.md resolutions: 14-bit
/// encoders, 12-bit load cell over +-25 N, belt speed in mm/s).
///
/// # Errors
/// [`FrameFault`] when a count is out of range. (The sequence check is the
/// caller's: it needs the previous frame.)
pub fn decode(frame: &SensorFrame) -> Result<Measurement, FrameFault> {
    decode_bits(frame, wire::ENCODER_BITS)
}

/// As [`decode`], for `encoder_bits`-bit encoders (counts in `[0, 2^bits)`;
/// `Config::encoder_bits`, clamped to `wire::ENCODER_BITS_RANGE`).
///
/// # Errors
/// As [`decode`].
pub fn decode_bits(frame: &SensorFrame, encoder_bits: u8) -> Result<Measurement, FrameFault> {
    decode_with(frame, &EncoderScale::of_bits(encoder_bits))
}

/// An encoder's resolution, derived once per configuration: the count range and
/// the angle of one count (the step's decoding then divides nothing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderScale {
    /// Counts per turn, `2^bits` with `bits` clamped to [`wire::ENCODER_BITS_RANGE`].
    pub counts: u32,
    /// One count, rad: `2 pi / counts` (exact: a power-of-two division).
    pub lsb: f32,
}

impl EncoderScale {
    /// The scale of a `bits`-bit encoder (clamped to [`wire::ENCODER_BITS_RANGE`]).
    pub fn of_bits(bits: u8) -> Self {
        let counts = 1u32 << bits.clamp(wire::ENCODER_BITS_RANGE.0, wire::ENCODER_BITS_RANGE.1);
        Self { counts, lsb: TAU / counts as f32 }
    }

    /// The angle of `count` (in `[0, counts)`), rad, wrapped to `(-pi, pi]`: the
    /// bits of [`wrap`] of `count * lsb`, which lies in `[0, 2 pi)`, so only the
    /// upper half turn moves.
    #[inline(always)]
    fn angle(&self, count: u16) -> f32 {
        let a = count as f32 * self.lsb;
        if a > PI { a - TAU } else { a }
    }
}

/// The load cell's codes modulo their range's size (`LOAD_CODE_MAX - LOAD_CODE_MIN + 1`, 4096).
const LOAD_RANGE_MASK: i32 = (wire::LOAD_CODE_MAX as i32 - wire::LOAD_CODE_MIN as i32 + 1) - 1;
const _: () = assert!((wire::LOAD_CODE_MAX as i32 - wire::LOAD_CODE_MIN as i32 + 1).count_ones() == 1, "a power of two");

/// [`decode_bits`] with the encoder's scale given (`scale` from
/// [`EncoderScale::of_bits`]): the firmware's step. The same measurement, bit for bit.
///
/// # Errors
/// As [`decode_bits`].
#[inline(always)]
pub fn decode_with(frame: &SensorFrame, scale: &EncoderScale) -> Result<Measurement, FrameFault> {
    if frame.flags & wire::frame_flags::ANY_INVALID != 0 {
        return Err(FrameFault::SensorInvalid);
    }
    if frame.theta1_count as u32 >= scale.counts || frame.elbow_count as u32 >= scale.counts {
        return Err(FrameFault::EncoderOutOfRange);
    }
    let load_ok = |c: i16| (wire::LOAD_CODE_MIN..=wire::LOAD_CODE_MAX).contains(&c);
    if !load_ok(frame.f_t_code) || !load_ok(frame.f_n_code) {
        return Err(FrameFault::LoadOutOfRange);
    }
    if frame.belt_count.unsigned_abs() > 5000 {
        return Err(FrameFault::BeltOutOfRange);
    }
    let lsb_force = wire::LOAD_FULL_SCALE_N / 2048.0;
    // At either end of the range (checked above): `c - MIN + 1` runs over
    // `[1, 4096]`, and modulo 4096 (the range's size, a power of two) it is 0 at
    // the top and 1 at the bottom, 2 or more elsewhere. One comparison a code and
    // no branch, where `c == MIN || c == MAX` took two and a branch out of line
    // and back (issue 56; the same flag at every code, test below).
    let clipped = |c: i16| ((i32::from(c) - i32::from(wire::LOAD_CODE_MIN) + 1) & LOAD_RANGE_MASK) < 2;
    Ok(Measurement {
        theta1: scale.angle(frame.theta1_count),
        elbow: scale.angle(frame.elbow_count),
        f_t: frame.f_t_code as f32 * lsb_force,
        f_n: frame.f_n_code as f32 * lsb_force,
        v_belt: frame.belt_count as f32 * wire::BELT_SPEED_RESOLUTION,
        flags: if clipped(frame.f_t_code) | clipped(frame.f_n_code) { status::LOAD_CLIPPED } else { 0 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clipped flag from one comparison a code is the two ends' comparisons
    /// for every pair of codes in the range (and every code with the other in the middle).
    #[test]
    fn the_clipped_flag_is_the_ends() {
        let frame = |f_t_code: i16, f_n_code: i16| SensorFrame { f_t_code, f_n_code, ..SensorFrame::default() };
        let scale = EncoderScale::of_bits(wire::ENCODER_BITS);
        let ends = |c: i16| c == wire::LOAD_CODE_MIN || c == wire::LOAD_CODE_MAX;
        for a in wire::LOAD_CODE_MIN..=wire::LOAD_CODE_MAX {
            for b in [wire::LOAD_CODE_MIN, wire::LOAD_CODE_MIN + 1, -1, 0, 1, wire::LOAD_CODE_MAX - 1, wire::LOAD_CODE_MAX, a] {
                for (t, n) in [(a, b), (b, a)] {
                    let m = decode_with(&frame(t, n), &scale).unwrap();
                    assert_eq!(m.flags == status::LOAD_CLIPPED, ends(t) || ends(n), "codes {t}, {n}");
                }
            }
        }
    }

    /// Every decoded angle of the first joint, at every encoder resolution the
    /// configuration takes, with a stride of the second's (all of them near the
    /// ends of the turn): [`wrap_sum`] of their sum has the bits of [`wrap`].
    #[test]
    fn the_sum_of_two_decoded_angles_wraps_as_wrap() {
        for bits in wire::ENCODER_BITS_RANGE.0..=wire::ENCODER_BITS_RANGE.1 {
            let scale = EncoderScale::of_bits(bits);
            let counts = scale.counts;
            let near = |c: u32| c < 64 || c + 64 >= counts || c.abs_diff(counts / 2) < 64;
            for a in 0..counts {
                let theta1 = scale.angle(a as u16);
                let mut b = 0;
                while b < counts {
                    let sum = theta1 + scale.angle(b as u16);
                    assert_eq!(wrap_sum(sum).to_bits(), wrap(sum).to_bits(), "{bits} bits: counts {a}, {b}");
                    b += if near(a) || near(b) { 1 } else { 61 };
                }
            }
        }
    }

    #[test]
    fn encode_decode_round_trips_within_one_count() {
        for i in -300..300 {
            let theta1 = i as f64 * 0.0101;
            let elbow = -0.4 + i as f64 * 0.002;
            let f_n = i as f64 * 0.07;
            let frame = SensorFrame {
                theta1_count: wire::encode_angle(theta1),
                elbow_count: wire::encode_angle(elbow),
                f_t_code: wire::encode_force(-f_n * 0.6),
                f_n_code: wire::encode_force(f_n),
                belt_count: -400,
                ..SensorFrame::default()
            };
            let m = decode(&frame).unwrap();
            let lsb = TAU as f64 / 16384.0;
            assert!((wrap((m.theta1 as f64 - theta1) as f32) as f64).abs() <= lsb, "theta1");
            assert!((wrap((m.elbow as f64 - elbow) as f32) as f64).abs() <= lsb, "elbow");
            let f_lsb = 25.0 / 2048.0;
            if f_n.abs() < 24.9 {
                assert!((m.f_n as f64 - f_n).abs() <= f_lsb, "f_n {f_n}");
                assert_eq!(m.flags & status::LOAD_CLIPPED, 0);
            } else {
                assert_ne!(m.flags & status::LOAD_CLIPPED, 0, "saturation is reported");
            }
            assert!((m.v_belt + 0.4).abs() < 1e-6);
        }
    }

    #[test]
    fn wrap_gives_the_bits_of_the_remainder_it_skips_within_a_turn() {
        let by_rem = |angle: f32| {
            let mut a = angle % TAU;
            if a > PI {
                a -= TAU;
            } else if a <= -PI {
                a += TAU;
            }
            a
        };
        let edges = [0.0, -0.0, PI, -PI, TAU, -TAU, f32::from_bits(TAU.to_bits() - 1), 3.0 * TAU, 1e6, f32::INFINITY, f32::NAN];
        let sweep = (-40_000..40_000).map(|i| i as f32 * 7.3e-4 + (i % 7) as f32 * 1e-9);
        for a in edges.into_iter().chain(edges.map(|e| -e)).chain(sweep) {
            let (w, r) = (wrap(a), by_rem(a));
            assert!(w.to_bits() == r.to_bits() || (w.is_nan() && r.is_nan()), "{a}: {w} vs {r}");
        }
    }

    #[test]
    fn the_scale_gives_the_bits_of_wrap_for_every_count_at_every_width() {
        for bits in 0..=20u8 {
            let scale = EncoderScale::of_bits(bits);
            let counts = 1u32 << bits.clamp(wire::ENCODER_BITS_RANGE.0, wire::ENCODER_BITS_RANGE.1);
            assert_eq!(scale.counts, counts);
            assert_eq!(scale.lsb.to_bits(), (TAU / counts as f32).to_bits());
            for c in 0..counts {
                let (a, w) = (scale.angle(c as u16), wrap(c as f32 * (TAU / counts as f32)));
                assert_eq!(a.to_bits(), w.to_bits(), "{bits} bits, count {c}");
                assert!(a > -PI && a <= PI);
            }
        }
    }

    #[test]
    fn out_of_range_counts_are_faults() {
        let ok = SensorFrame::default();
        assert!(decode(&ok).is_ok());
        assert_eq!(decode(&SensorFrame { theta1_count: 16384, ..ok }), Err(FrameFault::EncoderOutOfRange));
        assert_eq!(decode(&SensorFrame { elbow_count: u16::MAX, ..ok }), Err(FrameFault::EncoderOutOfRange));
        assert_eq!(decode(&SensorFrame { f_n_code: 2048, ..ok }), Err(FrameFault::LoadOutOfRange));
        assert_eq!(decode(&SensorFrame { f_t_code: i16::MIN, ..ok }), Err(FrameFault::LoadOutOfRange));
        assert_eq!(decode(&SensorFrame { belt_count: i16::MIN, ..ok }), Err(FrameFault::BeltOutOfRange));
        let nan_f_n = SensorFrame { flags: wire::frame_flags::F_N_INVALID, ..ok };
        assert_eq!(decode(&nan_f_n), Err(FrameFault::SensorInvalid));
    }
}
