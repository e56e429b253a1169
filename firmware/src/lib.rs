//! The arm's control firmware: `no_std`, heap-free, control maths in `f32`.
//!
//! This crate builds for the host and for `thumbv7em-none-eabihf`; it already
//! evaluates the shared model in `f32` (the same code the plant runs in `f64`).
//! The controllers, estimation and deadline monitoring arrive with issue 3.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub use shared;

/// The model in the firmware's scalar type: the paper's parameters in `f32`.
pub fn paper_arm() -> shared::Arm<f32> {
    shared::Arm::new(shared::Params::paper())
}
