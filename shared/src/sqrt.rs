//! Square root in single precision on the Cortex-M4F's FPU.
//!
//! The `libm` crate's `sqrtf` is correctly rounded but computed in integer
//! arithmetic, bit by bit (about 150 instructions and a branch per bit on the
//! MCU), and nalgebra's `f32` `sqrt` in `no_std` is that `sqrtf`. The FPU's
//! `VSQRT.F32` (ARMv7-M Architecture Reference Manual, ARM DDI 0403E, A7.7.255;
//! 14 cycles, Cortex-M4 TRM ARM DDI 0439B, Table 7-1) is IEEE 754's square root,
//! also correctly rounded: the two give the same bits for every input (NaN for
//! a negative one), so the MCU's control step and its host copy in SIL agree to
//! the bit.

/// `sqrt x` (correctly rounded, IEEE 754 `squareRoot`; NaN for `x < 0` or NaN, `+inf`
/// for `+inf`): `VSQRT.F32` on a hard-float Arm target, `libm::sqrtf` elsewhere.
#[inline]
pub fn sqrt_f32(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        let r_bits: u32;
        let r: f32;
        // Through a general register and `s0`, which the block declares clobbered
        // (the compiler keeps nothing live in it across the block): Rust's `sreg`
        // operands need the `vfp2` feature (double precision), which the
        // Cortex-M4F's single-precision FPU does not have, but a clobber of an FPU
        // register does not. Before issue 56's fifth round `s0` was saved and
        // restored around it on the stack (`VPUSH`/`VPOP`, 4 cycles more).
        // SAFETY: the block reads `x` and writes `r` (general registers) and `s0`
        // (declared clobbered), and touches no memory; VSQRT.F32 sets only FPSCR's
        // cumulative exception bits, never the condition flags.
        #[allow(unsafe_code)]
        unsafe {
            core::arch::asm!(
                "vmov s0, {x}",
                "vsqrt.f32 s0, s0",
                "vmov {r}, s0",
                x = in(reg) x.to_bits(),
                r = lateout(reg) r_bits,
                out("s0") _,
                options(pure, nomem, nostack, preserves_flags),
            );
        }
        r = f32::from_bits(r_bits);
        r
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Correctly rounded: the f64 square root of an f32 rounded to f32 is the
    /// correctly rounded f32 square root (f64 has more than 2 x 24 + 2 bits), so the
    /// two agree to the bit; special values as IEEE 754.
    #[test]
    fn is_correctly_rounded_and_handles_special_values() {
        let mut bits: u32 = 0;
        while bits < 0x7f80_0000 {
            let x = f32::from_bits(bits);
            assert_eq!(sqrt_f32(x).to_bits(), ((x as f64).sqrt() as f32).to_bits(), "x = {x:e}");
            bits += 9973;
        }
        assert!(sqrt_f32(-1.0).is_nan() && sqrt_f32(f32::NAN).is_nan());
        assert_eq!(sqrt_f32(f32::INFINITY), f32::INFINITY);
        assert_eq!(sqrt_f32(-0.0).to_bits(), (-0.0f32).to_bits());
    }
}
