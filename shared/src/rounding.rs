//! Rounding to whole numbers in `f64` with the values of `libm::floor` and
//! `libm::round` (half away from zero), bit for bit, signed zeros included.
//!
//! Below 2^52 in magnitude every `f64` converts to `i64` exactly, truncated
//! towards zero, and the fraction it drops, `x - trunc(x)`, is exact; the
//! conversion is one instruction on the host, where libm's portable code takes
//! about 25 (floor) and 50 (round) a call. At 2^52 and beyond every finite value is
//! whole already, and there, as for NaN and the infinities, libm answers. The
//! host's sensor models round every sample with these (the encoders' counts,
//! the load cell's codes, the belt's counter: [`crate::wire::encode_angle_bits`],
//! [`crate::wire::encode_force`], `drivers::belt::count_at`).

/// 2^52: from here on every finite `f64` is a whole number.
const WHOLE: f64 = 4_503_599_627_370_496.0;

/// `x` truncated towards zero when `|x| < 2^52` (`None` otherwise, NaN included;
/// the conversion saturates, so it is defined for every `x`).
#[inline(always)]
fn truncated(x: f64) -> Option<f64> {
    (x < WHOLE && x > -WHOLE).then_some(x as i64 as f64)
}

/// The largest whole number at most `x`: `libm::floor(x)`, the same bits.
#[inline]
pub fn floor(x: f64) -> f64 {
    match truncated(x) {
        Some(t) => {
            let f = if t > x { t - 1.0 } else { t };
            // A zero keeps the sign of `x` (floor(-0.0) = -0.0); x * 0.0 is that zero.
            if f == 0.0 { x * 0.0 } else { f }
        }
        None => libm::floor(x),
    }
}

/// `x` rounded to the nearest whole number, halfway cases away from zero:
/// `libm::round(x)`, the same bits.
#[inline]
pub fn round(x: f64) -> f64 {
    match truncated(x) {
        Some(t) => {
            // The fraction dropped, exact, of the sign of `x`.
            let d = x - t;
            let r = if d >= 0.5 {
                t + 1.0
            } else if d <= -0.5 {
                t - 1.0
            } else {
                t
            };
            // A zero keeps the sign of `x` (round(-0.3) = -0.0).
            if r == 0.0 { x * 0.0 } else { r }
        }
        None => libm::round(x),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values libm gives, bit for bit, over the edges (halves, the neighbours
    /// of whole numbers and halves, signed zeros, 2^52 and 2^53, the infinities,
    /// NaN) and a spread of magnitudes from 1e-300 to 1e300.
    #[test]
    fn the_same_bits_as_libm() {
        let mut xs: std::vec::Vec<f64> = std::vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            WHOLE,
            -WHOLE,
            2.0 * WHOLE,
            -2.0 * WHOLE,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for k in -40i32..=40 {
            for base in [f64::from(k), f64::from(k) + 0.5, f64::from(k) * 1e6 + 0.5, WHOLE + f64::from(k), -WHOLE + f64::from(k)] {
                xs.extend([base, base.next_up(), base.next_down()]);
            }
        }
        // A spread of magnitudes and fractions (a fixed sequence: no RNG needed).
        let mut v = 1e-300f64;
        while v < 1e300 {
            for frac in [0.0, 0.1, 0.25, 0.5, 0.75, 0.999] {
                let x = v * (1.0 + frac);
                xs.extend([x, -x]);
            }
            v *= 1.37;
        }
        for x in xs {
            assert_eq!(floor(x).to_bits(), libm::floor(x).to_bits(), "floor({x:e})");
            assert_eq!(round(x).to_bits(), libm::round(x).to_bits(), "round({x:e})");
        }
    }
}
