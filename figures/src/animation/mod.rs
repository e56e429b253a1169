//! Animations of a run as GIF images, for the report (issue 55: "nobody can see
//! the arm move"): the two-link arm from its joint angles by the plant's forward
//! kinematics, the belt with stripes moving at its speed, the contact force (or an
//! impact's impulse) as an arrow at the tip with its scale, the tip's recent path,
//! the time and contact mode, and a strip plot with a cursor ([`frame`]); drawn
//! with plotters' bitmap backend and encoded by the `gif` crate ([`encode`]).
//!
//! Frame `k` (from 0) shows the run at `t0 + k / (fps * slow_down)` s, drawn from
//! the trace's sample nearest to that time; there are
//! `round((t1 - t0) * slow_down * fps)` frames, each shown `round(100 / fps)`
//! hundredths of a second, looping.

pub mod encode;
pub mod frame;
pub mod scene;
pub mod trace;

use std::path::Path;

use rayon::prelude::*;

pub use frame::{Look, Strip};
pub use scene::{Arm, Scene};
pub use trace::ArmTrace;

use crate::error::Error;

/// An animation of a stretch of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    /// First time shown, s of the run.
    pub t0: f64,
    /// End of the stretch shown, s of the run.
    pub t1: f64,
    /// Frames per second of animation (1 to 100).
    pub fps: u32,
    /// Its title, strip plot and slow-down ([`Look::slow_down`]: seconds of
    /// animation per second of the run).
    pub look: Look,
}

impl Animation {
    /// The number of frames: `round((t1 - t0) * slow_down * fps)`.
    pub fn frames(&self) -> usize {
        ((self.t1 - self.t0) * self.look.slow_down * f64::from(self.fps)).round() as usize
    }

    /// The time of the run frame `k` shows, s: `t0 + k / (fps * slow_down)`.
    pub fn time(&self, k: usize) -> f64 {
        self.t0 + k as f64 / (f64::from(self.fps) * self.look.slow_down)
    }

    /// How long each frame is shown, hundredths of a second: `round(100 / fps)`.
    pub fn delay_cs(&self) -> u16 {
        (100.0 / f64::from(self.fps)).round() as u16
    }
}

/// What [`write_gif`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Written {
    /// Frames.
    pub frames: usize,
    /// Each frame's delay, hundredths of a second.
    pub delay_cs: u16,
    /// The file's size, bytes.
    pub bytes: u64,
    /// The mapping from the arm's plane to the frame's pixels.
    pub scene: Scene,
}

/// Frames rendered at once (in parallel) before they are encoded in order.
const BATCH: usize = 16;

/// Writes `animation` of `trace` (an arm `arm`) to `path` as an animated GIF of
/// [`frame::WIDTH`] x [`frame::HEIGHT`] px.
///
/// # Errors
/// [`Error::bad_input`] for a frame rate outside 1 to 100, a slow-down that is
/// not a positive number, an empty stretch or one the trace does not cover;
/// [`Error::Io`] when the file cannot be written; [`Error::Plot`] when a
/// frame cannot be drawn or encoded.
pub fn write_gif(path: &Path, trace: &ArmTrace, arm: Arm, animation: &Animation) -> Result<Written, Error> {
    let a = animation;
    if !(1..=100).contains(&a.fps) {
        return Err(Error::bad_input(format!("animation: {} frames per second: give 1 to 100", a.fps)));
    }
    if !(a.look.slow_down.is_finite() && a.look.slow_down > 0.0) {
        return Err(Error::bad_input(format!("animation: slow-down {}: give a positive number", a.look.slow_down)));
    }
    let (first, last) = (trace.t.first().copied().unwrap_or(f64::NAN), trace.t.last().copied().unwrap_or(f64::NAN));
    if !(a.t0 < a.t1 && a.t0 >= first && a.t1 <= last + 1e-9) || a.frames() == 0 {
        return Err(Error::bad_input(format!(
            "animation: the stretch {} s to {} s is empty or outside the trace ({first} s to {last} s)",
            a.t0, a.t1
        )));
    }
    let plot_err = |m: String| Error::Plot { path: path.to_path_buf(), message: m };
    let painter = frame::Painter::new(arm, trace, a.look.clone(), a.t0, a.t1).map_err(plot_err)?;
    let palette = encode::Palette::new(&frame::INKS);
    let size = (frame::WIDTH as u16, frame::HEIGHT as u16);
    let mut gif = encode::GifWriter::create(path, size, a.delay_cs(), palette)?;
    let ks: Vec<usize> = (0..a.frames()).collect();
    for batch in ks.chunks(BATCH) {
        let frames: Vec<Result<Vec<u8>, String>> = batch.par_iter().map(|&k| painter.frame(a.time(k))).collect();
        for f in frames {
            gif.add(&f.map_err(plot_err)?)?;
        }
    }
    gif.finish()?;
    let bytes = std::fs::metadata(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?.len();
    Ok(Written { frames: a.frames(), delay_cs: a.delay_cs(), bytes, scene: painter.scene })
}
