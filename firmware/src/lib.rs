//! The arm's control firmware: `no_std`, heap-free, control maths in `f32`.
//!
//! One function per control period, time passed in and hardware behind traits:
//! [`Firmware::step`] takes a [`SensorFrame`] of raw counts and returns an
//! [`ActuatorCommand`] of torque codes and a status word. The same code runs on
//! the host (SIL rig, tests) and on the Cortex-M4F (`boards/stm32f405`: the
//! `arm` and `pil` images), every board through [`board::handle`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

// clap's derives name `::std` (host-only feature).
#[cfg(all(feature = "clap", not(test)))]
extern crate std;

pub mod announce;
pub mod board;
pub mod config;
pub mod consistency;
pub mod controller;
pub mod decode;
pub mod estimator;
pub mod law;
pub mod liftoff;
pub mod mu_estimate;
pub mod pil;
pub mod reference;
pub mod runaway;
pub mod tracking;
pub mod wiring;

#[cfg(test)]
mod tests;

pub use board::{Board, Event, Outcome, TickClock};
pub use config::{Config, ControllerKind};
pub use controller::{Firmware, SafeReason, Telemetry};
pub use shared;
pub use shared::wire::{ActuatorCommand, SensorFrame};

/// The model in the firmware's scalar type: the paper's parameters in `f32`.
pub fn paper_arm() -> shared::Arm<f32> {
    shared::Arm::new(shared::Params::paper())
}

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

#[cfg(test)]
mod finite_tests {
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
