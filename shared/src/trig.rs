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

/// `x % TAU` (exact: fmodf), out of line and cold: never an arm angle, and kept
/// out of the control step's code (its instruction count is a CI gate).
#[cold]
#[inline(never)]
fn reduce_large(x: f32) -> f32 {
    x % core::f32::consts::TAU
}

/// `(sin x, cos x)` for `x` in radians, in `f32` arithmetic only; NaN for NaN or
/// infinite `x`.
#[inline]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    // `%` is exact (fmodf); `|x % TAU| < TAU` is then in the range below.
    let x = if x.abs() > REDUCE_MAX { reduce_large(x) } else { x };
    let t = x * core::f32::consts::FRAC_2_PI;
    let k = if t >= 0.0 { (t + 0.5) as i32 } else { (t - 0.5) as i32 };
    let kf = k as f32;
    let r = ((x - kf * PIO2_1) - kf * PIO2_2) - kf * PIO2_3;
    let z = r * r;
    let s = ((-1.951_529_589_1e-4 * z + 8.332_160_873_6e-3) * z - 1.666_665_461_1e-1) * z * r + r;
    let c = ((2.443_315_711_809_948e-5 * z - 1.388_731_625_493_765e-3) * z + 4.166_664_568_298_827e-2) * z * z - 0.5 * z + 1.0;
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
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
    let (ax, ay) = (x.abs(), y.abs());
    let (r, base) = if ay <= TAN_PI_8 * ax {
        // Also (0, 0): 0 / 0 is NaN, so the quotient is taken from 0 itself.
        (if ay == 0.0 { 0.0 } else { ay / ax }, 0.0)
    } else if ay >= TAN_3PI_8 * ax {
        (-ax / ay, core::f32::consts::FRAC_PI_2)
    } else {
        ((ay - ax) / (ay + ax), core::f32::consts::FRAC_PI_4)
    };
    let z = r * r;
    let a = base + ((((8.053_744_495_38e-2 * z - 1.387_768_560_32e-1) * z + 1.997_771_064_78e-1) * z - 3.333_294_915_39e-1) * z * r + r);
    let a = if x.is_sign_negative() { core::f32::consts::PI - a } else { a };
    if y.is_sign_negative() { -a } else { a }
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
