//! The rig's figures, drawn from a run's rows and an analysis's values: plots fit
//! for a paper (SVG, and PDF with the embedded font: [`plot`]), the animated,
//! self-contained trace page of a run (`trace.html`: [`trace_page`]) and the GIF
//! animations of the report ([`animation`]).
//!
//! Architecture invariant: this crate knows no command. It takes values (rows,
//! panels, series, a scenario) and returns or writes a figure; which figure a
//! command draws, and where its folder is, is the command's business
//! (`sil-host`, and the Python package). Its errors are its own ([`Error`]),
//! which the fronts' error takes as its own with the same message.
#![warn(missing_docs)]

pub mod animation;
mod error;
pub mod plot;
pub mod trace_page;

pub use error::Error;
