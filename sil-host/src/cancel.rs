//! One cancellation per process: Ctrl-C (SIGINT) and SIGTERM set a single flag,
//! installed once, that every long step of every command checks (a sweep between
//! and inside its runs, a sensitivity study, a closed-loop run every period, the
//! report between and during its experiments). The flag is never cleared, so a
//! command made of several steps (`report`) stops them all, not only the one
//! running when the signal came.
//!
//! A command stopped this way keeps what it finished and exits with the shell's
//! code for the signal, 128 + its number: 130 for SIGINT, 143 for SIGTERM
//! ([`exit_code`]). A second signal while the command winds down ends the
//! process at once, with the same code.

use std::sync::{
    Arc, OnceLock,
    atomic::{AtomicBool, AtomicUsize, Ordering},
};

use signal_hook::consts::{SIGINT, SIGTERM};

struct Cancel {
    /// Set by the first signal.
    stop: Arc<AtomicBool>,
    /// The number of the last signal received (0: none).
    signal: Arc<AtomicUsize>,
}

static CANCEL: OnceLock<Cancel> = OnceLock::new();

fn installed() -> &'static Cancel {
    CANCEL.get_or_init(|| {
        let cancel = Cancel { stop: Arc::new(AtomicBool::new(false)), signal: Arc::new(AtomicUsize::new(0)) };
        for sig in [SIGINT, SIGTERM] {
            // Order matters: the second signal finds the flag set and exits; the first
            // finds it clear, then records its number and sets it. Registration can only
            // fail for a forbidden signal, which these are not.
            let _ = signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&cancel.stop));
            let _ = signal_hook::flag::register_usize(sig, Arc::clone(&cancel.signal), sig as usize);
            let _ = signal_hook::flag::register(sig, Arc::clone(&cancel.stop));
        }
        cancel
    })
}

/// The process's stop flag (the same one on every call; the handlers are
/// installed by the first call). Set by SIGINT or SIGTERM, never cleared.
pub fn stop_flag() -> Arc<AtomicBool> {
    Arc::clone(&installed().stop)
}

/// The exit code for a command stopped by a signal: 128 + the signal's number
/// (130 SIGINT, 143 SIGTERM); `None` when no signal came (or no handler was
/// ever installed).
pub fn exit_code() -> Option<i32> {
    match CANCEL.get()?.signal.load(Ordering::Relaxed) {
        0 => None,
        sig => Some(128 + sig as i32),
    }
}
