//! `trace.html`: a self-contained page per run that animates the arm on the belt
//! and plots the trace with a cursor at the animated time (issue 55).
//!
//! The page holds everything it needs (its script, its style and the data as
//! JSON; no network, no external file): the two links and the tip drawn from
//! `theta1`, `theta2` by the plant's forward kinematics ([`view::joints`]), the
//! belt's stripes moving at `v_belt`, the contact force `(f_t, f_n)` as an arrow
//! at the tip (its scale stated), a time slider, play and pause, the time and the
//! contact mode; beside them the plots of `z_t` (and `z_t*`), the tip's height
//! `z_n + H`, `f_n` and `f_t`, the torques and the contact mode, with a cursor line
//! at the current time; every event of the run (an impact, a lift-off, the safe
//! state) marked at its exact time in the plots, the animation, the readout and
//! a list ([`events`]). Long runs are thinned so the page stays small: the
//! animation to a frame every 10 ms of simulated time and at most 5 000 frames
//! ([`frames`]), the plots to the min and max of buckets finer than a pixel
//! ([`curves`]); the page says by how much.
//!
//! For tests and scripts the page reads `?t=SECONDS` from its URL (the frame
//! nearest that time is shown, paused) and exposes `window.painleve`
//! (`setTime(t)`, `time()`, `tipPixel()`); its arm canvas publishes the world to
//! pixel mapping as data attributes: `data-px-per-m` (CSS px per m) and
//! `data-base-x`, `data-base-y` (the base joint, CSS px from the page's top left),
//! so that a point `(z_t, z_n)` is at `(base_x + s z_t, base_y - s z_n)`.

pub mod curves;
pub mod events;
pub mod frames;
mod html;
pub mod info;
pub mod view;

pub use curves::{CurveSample, Curves};
pub use events::{Events, PageEvent};
pub use frames::{Frame, Frames};
pub use info::PageInfo;

use crate::plot::mode_code;

/// The page's file name in a command's output folder.
pub const FILE: &str = "trace.html";

/// One sample of a run as the page takes it (a row of `trace.csv`).
#[derive(Debug, Clone, Copy)]
pub struct PageSample {
    /// Time, s.
    pub t: f64,
    /// Joint angles `[theta1, theta2]`, rad.
    pub theta: [f64; 2],
    /// Tip position `[z_t, z_n]`, m.
    pub z: [f64; 2],
    /// Contact force `[f_t, f_n]`, N.
    pub force: [f64; 2],
    /// Contact mode (`flight`, `sliding`, `sticking`).
    pub mode: &'static str,
    /// Reference `z_t*`, m (NaN in open loop).
    pub z_t_ref: f64,
    /// Motor torques `[u1, u2]`, N m (NaN in open loop).
    pub u: [f64; 2],
    /// Whether the firmware is in its safe state (its status word's
    /// `SAFE_STATE`; false in open loop): its entry is an event of the page.
    pub safe_state: bool,
}

impl From<&rig::record::PeriodRecord> for PageSample {
    fn from(r: &rig::record::PeriodRecord) -> Self {
        Self {
            t: r.t,
            theta: [r.theta1, r.theta2],
            z: [r.z_t, r.z_n],
            force: [r.f_t, r.f_n],
            mode: r.mode,
            z_t_ref: r.z_t_ref,
            u: [r.u1_cmd, r.u2_cmd],
            safe_state: r.status & shared::wire::status::SAFE_STATE != 0,
        }
    }
}

/// A page being gathered while a run goes, in memory that does not grow with
/// the run (at most [`frames::MAX_FRAMES`] frames and [`curves::CURVE_BUCKETS`]
/// buckets per curve).
#[derive(Debug, Clone)]
pub struct TracePage {
    info: PageInfo,
    frames: Frames,
    curves: Curves,
    events: Events,
    safe_state: bool,
}

impl TracePage {
    /// An empty page for the run `info` describes.
    pub fn new(info: PageInfo) -> Self {
        let curves = Curves::new(info.h, info.closed_loop);
        Self { info, frames: Frames::default(), curves, events: Events::default(), safe_state: false }
    }

    /// Adds the next event (in time order, with the samples: an event at `t`
    /// before the sample at `t`).
    pub fn event(&mut self, e: PageEvent) {
        self.events.push(e);
    }

    /// Adds the next sample (in time order); the sample where the firmware
    /// enters its safe state adds that event.
    pub fn push(&mut self, s: &PageSample) {
        if s.safe_state && !self.safe_state {
            self.events.push(PageEvent { t: s.t, kind: events::SAFE_STATE, impulse: [0.0; 2] });
        }
        self.safe_state = s.safe_state;
        let mode = mode_code(s.mode) as u8;
        self.frames.push(Frame { t: s.t, theta: s.theta, force: s.force, mode, z_t_ref: s.z_t_ref, u: s.u });
        self.curves.push(&CurveSample { t: s.t, z: s.z, force: s.force, mode, z_t_ref: s.z_t_ref, u: s.u });
    }

    /// The page's HTML text (the caller writes it as [`FILE`] in its folder).
    pub fn html(self) -> String {
        html::page(self.info, self.frames, &self.curves, &self.events)
    }
}
