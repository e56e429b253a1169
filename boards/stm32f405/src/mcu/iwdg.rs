//! The independent watchdog (RM0090 21): started once, fed by every completed
//! control step; a hung step resets the MCU, which comes up with the drivers
//! disabled (the safe state). Once started it cannot be stopped.

use core::sync::atomic::{AtomicU32, Ordering};

use stm32f4::stm32f405 as pac;

fn iwdg() -> &'static pac::iwdg::RegisterBlock {
    // SAFETY: the watchdog is started at start-up and fed by the control interrupt only.
    unsafe { &*pac::IWDG::ptr() }
}

/// The timeout [`start`] set, us (restored after [`stretched`]).
static TIMEOUT_US: AtomicU32 = AtomicU32::new(0);

/// Starts the watchdog with a timeout of at least `timeout_us` ([`crate::timing::watchdog`]).
pub fn start(timeout_us: u32) {
    TIMEOUT_US.store(timeout_us, Ordering::Relaxed);
    iwdg().kr().write(|w| unsafe { w.key().bits(0xCCCC) }); // start (and LSI on)
    set_timeout(timeout_us);
}

/// Sets a new timeout of at least `timeout_us` on the running watchdog (a new
/// control rate: five of its periods, `super::timers::retime`); [`stretched`]
/// restores this one from now on.
pub fn retime(timeout_us: u32) {
    TIMEOUT_US.store(timeout_us, Ordering::Relaxed);
    set_timeout(timeout_us);
}

/// Runs `f` with the watchdog's timeout lengthened to at least `timeout_us`
/// (a flash sector erase stalls the core for up to 1.1 s: DS8626 "Flash
/// memory programming"), then restores [`start`]'s timeout. PR and RLR can be
/// rewritten while the watchdog runs (RM0090 21.3.5).
pub fn stretched<T>(timeout_us: u32, f: impl FnOnce() -> T) -> T {
    set_timeout(timeout_us);
    let out = f();
    let normal = TIMEOUT_US.load(Ordering::Relaxed);
    if normal != 0 {
        set_timeout(normal);
    }
    out
}

// Out of line: start-up, the save's stretch and a change of rate share one copy.
#[inline(never)]
fn set_timeout(timeout_us: u32) {
    let (pr, rl) = crate::timing::watchdog(timeout_us);
    let w = iwdg();
    feed();
    w.kr().write(|w| unsafe { w.key().bits(0x5555) }); // unlock PR and RLR
    w.pr().write(|w| unsafe { w.pr().bits(pr) });
    w.rlr().write(|w| unsafe { w.rl().bits(rl) });
    // The new values take a few LSI periods to reach the watchdog's domain:
    // bounded, the watchdog itself covers a hang here.
    for _ in 0..100_000 {
        if w.sr().read().bits() & 0b11 == 0 {
            break;
        }
    }
    feed();
}

/// Reloads the counter.
pub fn feed() {
    iwdg().kr().write(|w| unsafe { w.key().bits(0xAAAA) });
}

/// The watchdog as the arm application's [`arm_app::Watchdog`] (started with [`start`]).
#[derive(Debug, Clone, Copy)]
pub struct Iwdg;

impl arm_app::Watchdog for Iwdg {
    fn feed(&mut self) {
        feed();
    }
}
