//! The host side of the rig: the plant simulator of the arm on the moving belt
//! (event-driven, nonsmooth), the commands that run it, and their outputs.
#![warn(missing_docs)]

pub mod cli;
pub mod commands;
pub mod error;
pub mod initial;
pub mod output;
pub mod plant;
pub mod plot;
