//! Sine and cosine in single precision only, for the Cortex-M4F: its FPU has no
//! double precision, and the `libm` crate's `sinf`/`cosf` evaluate their
//! polynomials in `f64` (software there: about 2300 instructions per `sincosf`,
//! most of a control step). This one stays in `f32` (about 50 instructions).
//!
//! Method (Cephes `sinf.c`, S. L. Moshier, "Methods and Programs for Mathematical
//! Functions", 1989): `k = round(x 2/pi)`, `r = x - k pi/2` with `pi/2` split in
//! three parts (Cody and Waite) so that `k * part` is exact for `|k| < 2^16`, then
//! the Cephes minimax polynomials for `sin r` and `cos r` on `[-pi/4, pi/4]` and
//! the quadrant `k mod 4`. Error: within 2.5e-7 of the true value for
//! `|x| <= 2^13` rad (test below). Beyond that (never an arm angle) `x` is first
//! reduced modulo `2 pi` in `f32` (`x % TAU`, exact for the `f32` value of
//! `TAU`, which is 1.75e-7 above `2 pi`): the result is then the sine and cosine,
//! within 2.5e-7, of an angle within half an ulp of `x` (the error of that
//! reduction, `|x| 2.8e-8`, is below `|x| 2^-25`), that is of a value `x` could
//! have been rounded from. Not `libm`'s `sinf`/`cosf` there: they would bring
//! their `f64` software arithmetic and large-argument reduction, about 6 KiB of
//! the MCU image's flash (docs/measurements.md "Speed and scale").

// The constants are written as published (Cephes); f32 rounds them.
#![allow(clippy::excessive_precision)]

/// `pi/2` in three parts: `PIO2_1` has 8 significant bits, `PIO2_2` 20.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_512_969_970_703_125e-4;
const PIO2_3: f32 = 7.549_789_954_891_882e-8;
/// Largest `|x|` reduced in single precision.
const REDUCE_MAX: f32 = 8192.0;

/// `(sin x, cos x)` for `x` in radians, in `f32` arithmetic only; NaN for NaN or
/// infinite `x`.
#[inline]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    sin_cos_reduced(in_range(x))
}

/// `(sin x, cos x)` of two angles `x = [x0, x1]` (rad): exactly
/// `[sin_cos_f32(x0), sin_cos_f32(x1)]` (test below; NaN for NaN alike), written as
/// one straight run so that the two evaluations share their constants' loads and
/// interleave on the MCU's FPU (the arm's two joints, every control step).
#[inline(always)]
pub fn sin_cos2_f32(x0: f32, x1: f32) -> [(f32, f32); 2] {
    let (x0, x1) = (in_range(x0), in_range(x1));
    let (k0, r0) = reduce(x0);
    let (k1, r1) = reduce(x1);
    let (s0, c0) = polynomials(r0);
    let (s1, c1) = polynomials(r1);
    [quadrant(k0, s0, c0), quadrant(k1, s1, c1)]
}

/// `x` when `|x| <= 2^13` (one comparison, false for NaN and infinities too), else
/// [`outside`]`(x)`.
#[inline(always)]
fn in_range(x: f32) -> f32 {
    if x.abs() <= REDUCE_MAX { x } else { outside(x) }
}

/// Beyond `2^13` rad: `x % TAU` (exact: fmodf; `|x % TAU| < TAU`); NaN for NaN or
/// infinite `x` (the evaluation then gives NaN). Out of line and cold: never an arm
/// angle, and kept out of the control step's code (its cycles are a CI gate).
#[cold]
#[inline(never)]
fn outside(x: f32) -> f32 {
    if x.is_finite() { x % core::f32::consts::TAU } else { f32::NAN }
}

/// `(sin x, cos x)` for `|x| <= 2^13`: the reduction, the polynomials and the quadrant.
#[inline(always)]
fn sin_cos_reduced(x: f32) -> (f32, f32) {
    let (k, r) = reduce(x);
    let (s, c) = polynomials(r);
    quadrant(k, s, c)
}

/// `k = round(x 2/pi)` (halves away from zero) and `r = x - k pi/2` in three parts
/// (Cody and Waite), for `|x| <= 2^13`.
#[inline(always)]
fn reduce(x: f32) -> (i32, f32) {
    let t = x * core::f32::consts::FRAC_2_PI;
    // `t + 0.5` for `t >= 0` (-0 included), `t - 0.5` below: `0.5` with the sign of `t`
    // (the same `k`: `-0 - 0.5` and `-0 + 0.5` both truncate to 0), no select.
    let half = f32::from_bits(0.5f32.to_bits() | (t.to_bits() & 0x8000_0000));
    let k = (t + half) as i32;
    let kf = k as f32;
    (k, ((x - kf * PIO2_1) - kf * PIO2_2) - kf * PIO2_3)
}

/// Cephes' minimax polynomials for `(sin r, cos r)` on `[-pi/4, pi/4]`.
#[inline(always)]
fn polynomials(r: f32) -> (f32, f32) {
    let z = r * r;
    let s = ((-1.951_529_589_1e-4 * z + 8.332_160_873_6e-3) * z - 1.666_665_461_1e-1) * z * r + r;
    let c = ((2.443_315_711_809_948e-5 * z - 1.388_731_625_493_765e-3) * z + 4.166_664_568_298_827e-2) * z * z - 0.5 * z + 1.0;
    (s, c)
}

/// `(sin x, cos x)` from `(sin r, cos r)` in quadrant `k mod 4` (`x = r + k pi/2`):
/// `(s, c)`, `(c, -s)`, `(-s, -c)`, `(-c, s)`. Without a branch (a table branch and
/// its pipeline refill on the MCU): the pair swapped for an odd `k`, the sine's sign
/// flipped by bit 1 of `k`, the cosine's by bit 1 of `k + 1` (a sign bit's flip is
/// the negation, bit for bit).
#[inline(always)]
fn quadrant(k: i32, s: f32, c: f32) -> (f32, f32) {
    let (a, b) = if k & 1 != 0 { (c, s) } else { (s, c) };
    let sin_sign = ((k as u32) & 2) << 30;
    let cos_sign = ((k.wrapping_add(1) as u32) & 2) << 30;
    (f32::from_bits(a.to_bits() ^ sin_sign), f32::from_bits(b.to_bits() ^ cos_sign))
}

/// Largest angle step (rad) [`rotate_f32`] takes.
pub const ROTATE_MAX: f32 = 0.0625;

/// `(sin(b + d), cos(b + d))` from `(s, c) = (sin b, cos b)` and a step `d`
/// (rad, `|d| <= ROTATE_MAX = 1/16`), in `f32`: the angle-addition identities
/// `sin(b + d) = s + (s (cos d - 1) + c sin d)` and
/// `cos(b + d) = c + (c (cos d - 1) - s sin d)`, with the Taylor series of `sin d`
/// to `d^5` and of `cos d - 1` to `d^6` (the first omitted terms, `d^7/5040` and
/// `d^8/40320`, are below `1e-12`). About a dozen instructions against
/// [`sin_cos_f32`]'s fifty; within a few `f32` rounding errors of the true values
/// when `s` and `c` are (test below). `None` beyond `1/16` rad or for a NaN `d`.
#[inline]
pub fn rotate_f32(s: f32, c: f32, d: f32) -> Option<(f32, f32)> {
    if d.is_nan() || d.abs() > ROTATE_MAX {
        return None;
    }
    let d2 = d * d;
    let sd = d + d * d2 * (-1.0 / 6.0 + d2 * (1.0 / 120.0));
    let cm1 = d2 * (-0.5 + d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)));
    Some((s + (s * cm1 + c * sd), c + (c * cm1 - s * sd)))
}

/// `cos(b + d)` alone from `(s, c) = (sin b, cos b)` and a step `d` (rad,
/// `|d| <= ROTATE_MAX = 1/16`), in `f32`: `c - (c (1 - cos d) + s sin d)` with
/// `1 - cos d` to `d^2 / 2` and `sin d` to `d^3 / 6`. Half of [`rotate_f32`]'s
/// work for one output and its series' two leading terms each: within `d^4 / 24`
/// (6.4e-7 at `1/16`, below 1e-13 at the encoders' few milliradians) plus a few
/// `f32` roundings of the true value when `s` and `c` are exact (test below).
/// `None` beyond `1/16` rad or for a NaN `d`. For a check that needs the value to
/// far less than that (the firmware's tip height against the load cell, tolerance
/// millimetres), not for a computation carried on.
#[inline]
pub fn cos_rotated_f32(s: f32, c: f32, d: f32) -> Option<f32> {
    // One comparison, false for NaN too.
    let within = d.abs() <= ROTATE_MAX;
    if !within {
        return None;
    }
    let d2 = d * d;
    let sd = d - d * d2 * (1.0 / 6.0);
    Some(c - (c * (0.5 * d2) + s * sd))
}

/// `tan(pi/8)`: below it `atan` takes its argument directly.
const TAN_PI_8: f32 = 0.414_213_562_373_095;
/// `tan(3 pi/8)`: above it `atan` takes the reciprocal's.
const TAN_3PI_8: f32 = 2.414_213_562_373_095;

/// `atan2(y, x)` in radians, in `[-pi, pi]` (the signs of zeros as IEEE's
/// `atan2`: `atan2(-0, 1) = -0`, `atan2(0, -1) = pi`), in `f32` arithmetic only,
/// with one division; NaN when either argument is NaN or infinite.
///
/// Method (Cephes `atanf.c`, S. L. Moshier 1989): `t = |y| / |x|` reduced to
/// `|r| <= tan(pi/8)` by `atan t = pi/4 + atan((t - 1) / (t + 1))` or
/// `pi/2 - atan(1 / t)`, each written as one quotient of `|x|` and `|y|` (so one
/// division where `libm::atan2f` takes two and a call to `atanf`); Cephes' minimax
/// polynomial `r + r z (c0 + c1 z + c2 z^2 + c3 z^3)`, `z = r^2`, relative error
/// 1.9e-7 on the reduced range; then the quadrant from the signs. Error: within
/// 3 ulp of the true value over the plane (test below), about 40 cycles on the
/// Cortex-M4F against about 85 for `libm::atan2f`.
#[inline]
pub fn atan2_f32(y: f32, x: f32) -> f32 {
    if !(y.is_finite() && x.is_finite()) {
        return f32::NAN;
    }
    atan2_finite_f32(y, x)
}

/// [`atan2_f32`] for finite `y` and `x`, without its finiteness checks: the same
/// bits there (it is that function's own arithmetic), an unspecified value (never
/// a panic) for a NaN or infinite argument. For a caller whose arguments are
/// finite by a check already made (issue 56: the PID's reference angle, whose
/// target the reach's comparison refuses when not finite).
#[inline]
pub fn atan2_finite_f32(y: f32, x: f32) -> f32 {
    let a = atan_first_quadrant(y.abs(), x.abs());
    let a = if x.is_sign_negative() { core::f32::consts::PI - a } else { a };
    if y.is_sign_negative() { -a } else { a }
}

/// [`atan2_f32`] in the first quadrant, `y` and `x` finite and at least `+0`
/// (not `-0`): there that function takes neither of its sign corrections, so
/// this is the same arithmetic with the same bits (test below), without the
/// finiteness checks and the sign handling (issue 56: the PID's half elbow
/// angle, whose sine and cosine are bounded so by construction). Outside that
/// domain the value is unspecified (never a panic).
#[inline]
pub fn atan2_first_quadrant_f32(y: f32, x: f32) -> f32 {
    atan_first_quadrant(y, x)
}

/// `atan2(ay, ax)` for `ay, ax >= 0` (radians, `[0, pi/2]`): the octant's
/// reduction, one division and Cephes' polynomial ([`atan2_f32`]'s method).
#[inline(always)]
fn atan_first_quadrant(ay: f32, ax: f32) -> f32 {
    let (r, base) = if ay <= TAN_PI_8 * ax {
        // Also (0, 0): 0 / 0 is NaN, so the quotient is taken from 0 itself.
        (if ay == 0.0 { 0.0 } else { ay / ax }, 0.0)
    } else if ay >= TAN_3PI_8 * ax {
        (-ax / ay, core::f32::consts::FRAC_PI_2)
    } else {
        ((ay - ax) / (ay + ax), core::f32::consts::FRAC_PI_4)
    };
    let z = r * r;
    base + ((((8.053_744_495_38e-2 * z - 1.387_768_560_32e-1) * z + 1.997_771_064_78e-1) * z - 3.333_294_915_39e-1) * z * r + r)
}

#[cfg(test)]
mod tests {

    /// Within 1/16 rad, the rotated values are within 4e-7 of the true sine and
    /// cosine of `b + d` (f64), as close as `sin_cos_f32` of the sum; beyond it, none.
    #[test]
    fn small_rotations_agree_with_the_true_values() {
        let mut worst = 0.0f64;
        for i in -300..=300 {
            let b = 0.0213 * i as f32;
            let (s, c) = sin_cos_f32(b);
            for j in -64..=64 {
                let d = ROTATE_MAX * j as f32 / 64.0;
                let (sr, cr) = rotate_f32(s, c, d).expect("within 1/16 rad");
                let x = b as f64 + d as f64;
                worst = worst.max((sr as f64 - x.sin()).abs()).max((cr as f64 - x.cos()).abs());
            }
        }
        assert!(worst <= 4e-7, "worst error {worst:e}");
        assert_eq!(rotate_f32(0.3, 0.9, 0.0), Some((0.3, 0.9)), "no step, the same values");
        assert!(rotate_f32(0.0, 1.0, 0.0626).is_none() && rotate_f32(0.0, 1.0, f32::NAN).is_none());
    }
    use super::*;

    /// The form before issue 56's third round: the rounding by a select, the
    /// quadrant by a `match` (a table branch on the MCU).
    fn sin_cos_matched(x: f32) -> (f32, f32) {
        if !x.is_finite() {
            return (f32::NAN, f32::NAN);
        }
        let x = if x.abs() > REDUCE_MAX { x % core::f32::consts::TAU } else { x };
        let t = x * core::f32::consts::FRAC_2_PI;
        let k = if t >= 0.0 { (t + 0.5) as i32 } else { (t - 0.5) as i32 };
        let kf = k as f32;
        let r = ((x - kf * PIO2_1) - kf * PIO2_2) - kf * PIO2_3;
        let (s, c) = polynomials(r);
        match k & 3 {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }

    /// The branchless rounding and quadrant, and the two-angle form, give the
    /// matched form's bits: every quadrant's boundaries (`k pi/4` and the floats
    /// next to them), a sweep over `|x| <= 2^13`, zeros, large values, NaN and
    /// infinities.
    #[test]
    fn the_branchless_quadrant_and_the_pair_are_the_matched_form_bit_for_bit() {
        let same = |x: f32, y: f32| {
            let want = sin_cos_matched(x);
            let bits = |p: (f32, f32)| (p.0.to_bits(), p.1.to_bits());
            let got = sin_cos_f32(x);
            assert!(bits(got) == bits(want) || (got.0.is_nan() && want.0.is_nan()), "x = {x:e}: {got:?} against {want:?}");
            let pair = sin_cos2_f32(x, y);
            let want_y = sin_cos_matched(y);
            assert!(bits(pair[0]) == bits(want) || (pair[0].0.is_nan() && want.0.is_nan()), "x = {x:e} in a pair");
            assert!(bits(pair[1]) == bits(want_y) || (pair[1].0.is_nan() && want_y.0.is_nan()), "y = {y:e} in a pair");
        };
        for k in -40..=40 {
            let b = k as f32 * core::f32::consts::FRAC_PI_4;
            for d in -3i32..=3 {
                let x = f32::from_bits((b.to_bits() as i32 + d) as u32);
                same(x, -x);
                same(-x, 0.37 * x);
            }
        }
        for i in -200_000..=200_000 {
            let x = i as f32 * 0.040_96;
            same(x, 1.0 - x * 0.5);
        }
        for x in [0.0f32, -0.0, 8192.0, -8192.0, 8192.5, 1.0e9, f32::MAX, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            same(x, 0.25);
            same(0.25, x);
        }
    }

    /// Within 1/16 rad, the cosine of `b + d` from `(sin b, cos b)` is within
    /// `d^4 / 24 + 1.5e-7` of the true value (f64 of the `f32` inputs); beyond
    /// 1/16 or for NaN, none. A series' term dropped (the `d^3` of the sine) fails it.
    #[test]
    fn the_rotated_cosine_agrees_with_the_true_value() {
        let mut worst = 0.0f64;
        for i in -300..=300 {
            let b = 0.0213 * i as f32;
            let (s, c) = sin_cos_f32(b);
            for j in -256i32..=256 {
                let d = ROTATE_MAX * j as f32 / 256.0;
                let got = cos_rotated_f32(s, c, d).expect("within 1/16 rad") as f64;
                let want = (b as f64 + d as f64).cos();
                let bound = (d as f64).powi(4) / 24.0 + 1.5e-7;
                assert!((got - want).abs() <= bound, "b = {b}, d = {d}: {got} against {want}");
                worst = worst.max((got - want).abs());
                let dropped = (c - (c * (0.5 * d * d) + s * d)) as f64;
                if j.abs() == 256 && (b as f64).sin().abs() > 0.5 {
                    assert!((dropped - want).abs() > bound, "the sine's cube matters at 1/16 (b = {b})");
                }
            }
        }
        assert!(worst > 1e-8, "the bound is exercised ({worst:e})");
        assert!(cos_rotated_f32(0.0, 1.0, 0.0626).is_none() && cos_rotated_f32(0.0, 1.0, f32::NAN).is_none());
        assert_eq!(cos_rotated_f32(0.3, 0.9, 0.0), Some(0.9), "no step, the same value");
    }

    #[test]
    fn agrees_with_f64_over_the_reduced_range() {
        let mut worst = 0.0f64;
        let n = 400_000;
        for i in 0..=n {
            let x = -60.0 + 120.0 * i as f32 / n as f32;
            let (s, c) = sin_cos_f32(x);
            let xd = x as f64;
            worst = worst.max((s as f64 - xd.sin()).abs()).max((c as f64 - xd.cos()).abs());
        }
        assert!(worst <= 2.5e-7, "worst error {worst:e}");
        for x in [1000.5f32, -8191.0, 4321.25] {
            let (s, c) = sin_cos_f32(x);
            assert!((s as f64 - (x as f64).sin()).abs() < 1e-6 && (c as f64 - (x as f64).cos()).abs() < 1e-6, "x = {x}");
        }
    }

    #[test]
    fn identities_and_edge_values() {
        assert_eq!(sin_cos_f32(0.0), (0.0, 1.0));
        for i in 0..1000 {
            let x = i as f32 * 0.0123 - 6.0;
            let (s, c) = sin_cos_f32(x);
            let (sn, cn) = sin_cos_f32(-x);
            assert_eq!((s, c), (-sn, cn), "odd sine, even cosine at {x}");
            assert!((s * s + c * c - 1.0).abs() < 5e-7);
        }
        let (s, c) = sin_cos_f32(f32::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos_f32(f32::INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }

    /// Beyond `2^13` rad: the sine and cosine of an angle within half an ulp of
    /// `x` (the reduction's error `|x| 2.8e-8` is below it), within 2.5e-7 plus
    /// the slope times that distance.
    #[test]
    fn large_arguments_are_the_values_of_an_angle_within_half_an_ulp() {
        let tau_excess = core::f32::consts::TAU as f64 - 2.0 * core::f64::consts::PI;
        for x in [8192.5f32, -8193.0, 1.0e4, -3.3e5, 1.234_567e6, 7.0e7, -1.0e9, 3.0e38, f32::MAX, f32::MIN] {
            let (s, c) = sin_cos_f32(x);
            let xd = x as f64;
            let half_ulp = (x.abs() as f64) * f64::powi(2.0, -24) / 2.0;
            let shift = (xd / (core::f32::consts::TAU as f64)).trunc() * tau_excess;
            assert!(shift.abs() <= half_ulp, "x = {x}: reduction error {shift:e} > half an ulp {half_ulp:e}");
            // `x % TAU`, exact in f64 as in f32: the angle whose values these are.
            let r = xd % (core::f32::consts::TAU as f64);
            assert!((s as f64 - r.sin()).abs() < 3e-7 && (c as f64 - r.cos()).abs() < 3e-7, "x = {x}: ({s}, {c}) against r = {r}");
            assert!((s * s + c * c - 1.0).abs() < 5e-7, "x = {x}");
        }
        let (s, c) = sin_cos_f32(f32::NEG_INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }

    /// The first quadrant's form keeps [`atan2_f32`]'s bits wherever its domain
    /// holds (both arguments finite and at least `+0`): every direction of the
    /// quadrant on a fine grid, magnitudes from 1e-30 to 1e30, the axes and the
    /// origin, and the PID's half angles (`x` in `(0, 1]`, `y = sqrt(1 - x^2)`).
    /// So does the form without the finiteness checks for every finite pair
    /// (every direction of the plane, the signed zeros).
    #[test]
    fn the_unchecked_forms_keep_the_bits() {
        let mut n = 0;
        for k in 0..=20_000 {
            let a = core::f64::consts::FRAC_PI_2 * k as f64 / 20_000.0;
            for m in [1e-30f64, 1e-3, 0.21, 1.0, 7.5, 1e30] {
                let (y, x) = ((m * a.sin()) as f32, (m * a.cos()) as f32);
                let (y, x) = (y.max(0.0), x.max(0.0));
                assert_eq!(atan2_first_quadrant_f32(y, x).to_bits(), atan2_f32(y, x).to_bits(), "({y:e}, {x:e})");
                n += 1;
            }
        }
        let mut bits = 1u32;
        while bits <= 0x3f80_0000 {
            let x = f32::from_bits(bits);
            let y = crate::sqrt::sqrt_f32((1.0 - x) * (1.0 + x));
            assert_eq!(atan2_first_quadrant_f32(y, x).to_bits(), atan2_f32(y, x).to_bits(), "({y:e}, {x:e})");
            bits += 997;
            n += 1;
        }
        for (y, x) in [(0.0f32, 0.0f32), (0.0, 1.0), (1.0, 0.0), (3.0, 3.0), (f32::MAX, f32::MIN_POSITIVE), (f32::MIN_POSITIVE, f32::MAX)] {
            assert_eq!(atan2_first_quadrant_f32(y, x).to_bits(), atan2_f32(y, x).to_bits(), "({y:e}, {x:e})");
        }
        assert!(n > 100_000);
        for k in -20_000..=20_000 {
            let a = core::f64::consts::PI * k as f64 / 20_000.0;
            for m in [1e-30f64, 0.21, 1e30] {
                let (y, x) = ((m * a.sin()) as f32, (m * a.cos()) as f32);
                assert_eq!(atan2_finite_f32(y, x).to_bits(), atan2_f32(y, x).to_bits(), "({y:e}, {x:e})");
            }
        }
        for (y, x) in [(0.0f32, -0.0f32), (-0.0, -0.0), (-0.0, 1.0), (0.0, -1.0), (-1.0, 0.0)] {
            assert_eq!(atan2_finite_f32(y, x).to_bits(), atan2_f32(y, x).to_bits(), "({y:e}, {x:e})");
        }
    }

    /// Within 3 ulp of the true `atan2` (f64) over the plane (2.74 measured): every direction on
    /// a fine grid (both sides of each reduction's threshold among them) at radii
    /// from 1e-30 to 1e30, and the axes and zeros exactly as IEEE's `atan2`.
    #[test]
    fn atan2_agrees_with_f64_over_the_plane() {
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let phi = -core::f64::consts::PI + 2.0 * core::f64::consts::PI * i as f64 / 200_000.0;
            for radius in [1e-30f64, 3e-3, 0.21, 1.0, 7.5, 1e30] {
                let (y, x) = ((radius * phi.sin()) as f32, (radius * phi.cos()) as f32);
                let got = atan2_f32(y, x);
                let exact = (y as f64).atan2(x as f64);
                let ulp = f32::from_bits((exact.abs() as f32).to_bits() + 1) as f64 - (exact.abs() as f32) as f64;
                let err = (got as f64 - exact).abs() / ulp.max(f32::MIN_POSITIVE as f64);
                worst = worst.max(err);
                assert!(err <= 3.0, "atan2({y:e}, {x:e}) = {got:e}, exact {exact:e}: {err} ulp");
            }
        }
        assert!(worst > 0.5, "the f32 result is not exact everywhere (worst {worst} ulp)");
        use core::f32::consts::{FRAC_PI_2, PI};
        for (y, x, want) in [
            (0.0f32, 1.0f32, 0.0f32),
            (-0.0, 1.0, -0.0),
            (0.0, -1.0, PI),
            (-0.0, -1.0, -PI),
            (1.0, 0.0, FRAC_PI_2),
            (-1.0, 0.0, -FRAC_PI_2),
            (0.0, 0.0, 0.0),
            (0.0, -0.0, PI),
        ] {
            assert_eq!(atan2_f32(y, x).to_bits(), want.to_bits(), "atan2({y}, {x})");
        }
        for (y, x) in [(f32::NAN, 1.0), (1.0, f32::NAN), (f32::INFINITY, 1.0), (1.0, f32::NEG_INFINITY)] {
            assert!(atan2_f32(y, x).is_nan());
        }
    }
}
