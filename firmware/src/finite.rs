//! Finiteness checks as float arithmetic (issue 56): one FPU comparison for one,
//! two or three values, where `f32::is_finite` is integer code on the MCU. The
//! step, the law and the checks use them on every value they compute from data.

/// `x.is_finite()` as float arithmetic: `x - x` is `+0` exactly for a finite `x`
/// and NaN for an infinity or a NaN, so the comparison with 0 is the same verdict
/// for every `x` (test `finite_is_is_finite`). On the MCU `f32::is_finite` is
/// integer code (a `VMOV` to a core register, `BIC`, `CMP`); this stays in the FPU
/// (issue 56).
#[inline(always)]
pub(crate) fn finite(x: f32) -> bool {
    #[allow(clippy::eq_op)] // deliberate: x - x is 0 exactly when x is finite
    let zero = x - x;
    zero == 0.0
}

/// `a.is_finite() && b.is_finite()` as one comparison: `(a - a) + (b - b)` is `+0`
/// exactly when both are finite (each difference `+0`) and NaN otherwise (a NaN
/// difference makes the sum NaN), so the verdict is the pair's for every `a`, `b`
/// (test `finite_all_is_each_finite`): one `VCMP`, `VMRS` and branch where two
/// checks take two (issue 56).
#[inline(always)]
pub(crate) fn finite_both(a: f32, b: f32) -> bool {
    #[allow(clippy::eq_op)] // deliberate: x - x is 0 exactly when x is finite
    let zero = (a - a) + (b - b);
    zero == 0.0
}

/// [`finite_both`] of three values: all of `a`, `b`, `c` finite, one comparison.
#[inline(always)]
pub(crate) fn finite_all3(a: f32, b: f32, c: f32) -> bool {
    #[allow(clippy::eq_op)] // deliberate: x - x is 0 exactly when x is finite
    let zero = ((a - a) + (b - b)) + (c - c);
    zero == 0.0
}

#[cfg(test)]
mod tests {
    /// [`super::finite_both`] and [`super::finite_all3`] give the verdict of each
    /// value's `is_finite` for every pair and triple of a set that holds every
    /// class of `f32` (zeros, subnormals, normals at both ends, the extremes, the
    /// infinities and NaNs of both signs and several payloads).
    #[test]
    fn finite_all_is_each_finite() {
        let mut xs = vec![
            0.0f32,
            -0.0,
            1e-45,
            -1e-45,
            f32::MIN_POSITIVE,
            1.0,
            -3.5,
            1e30,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7f80_0001),
            f32::from_bits(0xffc0_1234),
        ];
        let mut bits = 1u32;
        while bits < 0xff80_0000 {
            xs.push(f32::from_bits(bits));
            bits = bits.wrapping_mul(3).wrapping_add(0x0123_4567) % 0xff80_0000;
            if xs.len() > 200 {
                break;
            }
        }
        for &a in &xs {
            for &b in &xs {
                assert_eq!(super::finite_both(a, b), a.is_finite() && b.is_finite(), "{a:e}, {b:e}");
                for &c in &xs[..40] {
                    assert_eq!(super::finite_all3(a, b, c), a.is_finite() && b.is_finite() && c.is_finite(), "{a:e}, {b:e}, {c:e}");
                }
            }
        }
    }

    /// `finite` is `f32::is_finite` over a sweep of every bit pattern's
    /// neighbourhood and the special values (infinities, NaNs of both signs and
    /// any payload, the extremes, subnormals, zeros).
    #[test]
    fn finite_is_is_finite() {
        let mut bits = 0u32;
        loop {
            for b in [bits, bits.wrapping_add(1), bits.wrapping_sub(1)] {
                let x = f32::from_bits(b);
                assert_eq!(super::finite(x), x.is_finite(), "{x:e} ({b:#x})");
            }
            let (next, over) = bits.overflowing_add(4099);
            if over {
                break;
            }
            bits = next;
        }
        for x in [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7f80_0001),
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            1e-45,
            0.0,
            -0.0,
        ] {
            assert_eq!(super::finite(x), x.is_finite(), "{x:e}");
        }
    }
}
