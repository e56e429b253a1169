//! The measurements of `sil-host bench` (the command, its groups and targets:
//! [`crate::commands::bench`]): a figure against its target ([`figure`]), the
//! flash and static RAM of an MCU image ([`elf`]), and PIL runs of the image in
//! QEMU with their step counts and rate ([`pil`]).

pub mod elf;
pub mod figure;
pub mod pil;
