//! The defmt log's timestamp (the knurling app-template's `defmt::timestamp!`):
//! the control tick's time, microseconds, as `period number x control period`.
//!
//! - `arm`: TIM2's update interrupt counts its ticks ([`tick`], the first is period
//!   0, as the application's `seq`); the period is the configured control period
//!   ([`set_period_us`] at start-up; at a change of rate [`retime`] rebases the
//!   count, so the stamps go on). A line's stamp is the time of the last tick
//!   since the first: a line logged in period `k`'s tick (`period k: ...`), or in
//!   the idle loop after it, reads `k` periods.
//! - `pil`: the plant owns time; each frame sets the period number it carries
//!   ([`set_tick`], the frame's `seq`) and the configuration the period. A line's
//!   stamp is the plant's time of the frame being handled: the same under QEMU and
//!   on a board, run after run (the PIL golden `defmt.log` holds them).
//!
//! Before the first tick (and, in `pil`, before the configuration) the stamp is 0.
//! The decoders print it in seconds with six decimals (`0.001000`): probe-rs,
//! `defmt-print`, and `sil-host pil`'s `defmt.log` (`rig::pil_link::LogLine`).
//! Cost: two relaxed atomic loads and a 32x32 multiply per line, 8 bytes of RAM.

use core::sync::atomic::{AtomicU32, Ordering};

/// The current period's number: the last control tick's (`arm`, from 0) or the
/// frame's (`pil`); [`NONE`] before the first.
static TICKS: AtomicU32 = AtomicU32::new(NONE);
/// No tick yet (the first [`tick`] wraps it to period 0).
const NONE: u32 = u32::MAX;
/// The control period, microseconds (0 until known).
static PERIOD_US: AtomicU32 = AtomicU32::new(0);

/// Sets the control period the stamp counts in, microseconds.
pub fn set_period_us(us: u32) {
    PERIOD_US.store(us, Ordering::Relaxed);
}

/// A new control period, microseconds, from the current period on (`arm`'s
/// change of rate: `super::timers::retime`): the period number is rebased so
/// that the stamp goes on from where it is, rounded up to a whole new period
/// (never back; ahead by less than one new period). Called between two ticks
/// with the interrupts masked.
pub fn retime(us: u32) {
    let k = TICKS.load(Ordering::Relaxed);
    if k != NONE && us != 0 {
        TICKS.store(now_us().div_ceil(u64::from(us)) as u32, Ordering::Relaxed);
    }
    set_period_us(us);
}

/// Counts one control tick (TIM2's update interrupt, `arm`): the first is period 0.
pub fn tick() {
    TICKS.fetch_add(1, Ordering::Relaxed);
}

/// Sets the period number (`pil`: the frame's `seq`).
pub fn set_tick(n: u32) {
    TICKS.store(n, Ordering::Relaxed);
}

/// The stamp, microseconds: the current period's number times the period (0
/// before the first tick; the number rebased at a change of rate, [`retime`]).
pub fn now_us() -> u64 {
    match TICKS.load(Ordering::Relaxed) {
        NONE => 0,
        k => u64::from(k) * u64::from(PERIOD_US.load(Ordering::Relaxed)),
    }
}

defmt::timestamp!("{=u64:us}", now_us());
