//! The model both sides of the rig share: the two-link arm whose tip slides on a
//! moving belt, after D. Marchese, M. Coraggio, S. J. Hogan, M. di Bernardo,
//! "Control of Painlevé Paradox in a Robotic System", ECC 2019 ("the paper"),
//! with the parameters of Zhao et al. (2008).
//!
//! `no_std`, heap-free, and generic over the scalar ([`Real`]): the firmware
//! evaluates the model in `f32` on the Cortex-M4F, the plant simulator in `f64`,
//! from the one implementation here.
//!
//! Conventions (docs/model.md): angles are absolute, from the downward vertical, in
//! radians; `q = [theta1, theta2]`; the tip is `z = [z_t, z_n]` (tangential along
//! the belt, normal upward); the belt surface is `z_n = -H`; SI units throughout.
#![no_std]
// No unsafe code but one instruction of inline assembly, the FPU's square root
// ([`sqrt::sqrt_f32`]: no stable Rust exposes it in `no_std`).
#![deny(unsafe_code)]
#![warn(missing_docs)]

// clap's derives name `::std` (host-only feature); the tests use its strings.
#[cfg(any(test, feature = "clap"))]
extern crate std;

pub mod contact;
pub mod kinematics;
pub mod model;
pub mod params;
pub mod rounding;
pub mod slip;
pub mod sqrt;
pub mod time;
pub mod trig;
pub mod wire;

pub use contact::{ContactMode, SlipDirection};
pub use kinematics::{ElbowBranch, IkError};
pub use model::Arm;
pub use params::{ParamError, Params};
pub use time::{Instant, Period};

/// The scalar the model is generic over: `f32` (firmware) or `f64` (plant).
///
/// nalgebra's `RealField` (with `libm` for `no_std` maths) plus `Copy`, and the
/// sine and cosine the model uses: `RealField`'s for `f64`, single precision only
/// for `f32` ([`trig::sin_cos_f32`]: the MCU has no double-precision FPU).
pub trait Real: nalgebra::RealField + Copy {
    /// `(sin x, cos x)`, `x` in radians.
    fn sin_cos_rad(self) -> (Self, Self);
    /// `sin x`, `x` in radians.
    fn sin_rad(self) -> Self;
    /// `cos x`, `x` in radians.
    fn cos_rad(self) -> Self;
    /// `sqrt x`, correctly rounded (NaN for `x < 0`): `RealField`'s for `f64`,
    /// [`sqrt::sqrt_f32`] for `f32` (the FPU's `VSQRT.F32` on the MCU, the same bits).
    fn square_root(self) -> Self;
    /// `acos x`, radians: `RealField`'s for `f64`; `libm::acosf` for `f32` on
    /// every target, so that the firmware's f32 computes the same bits on the
    /// host (where `RealField` would take the C library's `acosf` once a crate
    /// of the workspace enables nalgebra's `std`) as on the MCU (issue 38).
    fn arc_cos(self) -> Self;
    /// `atan2(self, x)`, radians, in `(-pi, pi]`: as [`Real::arc_cos`], `libm::atan2f` for `f32`.
    fn arc_tan2(self, x: Self) -> Self;
}

impl Real for f64 {
    #[inline]
    fn sin_cos_rad(self) -> (Self, Self) {
        nalgebra::ComplexField::sin_cos(self)
    }
    #[inline]
    fn sin_rad(self) -> Self {
        nalgebra::ComplexField::sin(self)
    }
    #[inline]
    fn cos_rad(self) -> Self {
        nalgebra::ComplexField::cos(self)
    }
    #[inline]
    fn square_root(self) -> Self {
        nalgebra::ComplexField::sqrt(self)
    }
    #[inline]
    fn arc_cos(self) -> Self {
        nalgebra::ComplexField::acos(self)
    }
    #[inline]
    fn arc_tan2(self, x: Self) -> Self {
        nalgebra::RealField::atan2(self, x)
    }
}

impl Real for f32 {
    #[inline]
    fn sin_cos_rad(self) -> (Self, Self) {
        trig::sin_cos_f32(self)
    }
    #[inline]
    fn sin_rad(self) -> Self {
        trig::sin_cos_f32(self).0
    }
    #[inline]
    fn cos_rad(self) -> Self {
        trig::sin_cos_f32(self).1
    }
    #[inline]
    fn square_root(self) -> Self {
        sqrt::sqrt_f32(self)
    }
    #[inline]
    fn arc_cos(self) -> Self {
        libm::acosf(self)
    }
    #[inline]
    fn arc_tan2(self, x: Self) -> Self {
        libm::atan2f(self, x)
    }
}

/// Converts an `f64` literal to the scalar `T` (exact for `f64`, rounded for `f32`).
#[inline(always)]
pub fn lit<T: Real>(x: f64) -> T {
    nalgebra::convert(x)
}
