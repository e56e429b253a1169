//! Standard output, with one behaviour for every command when it cannot be
//! written (issue 52, 7: `println!` panicked, exit 101, on a closed pipe or a
//! full disk).
//!
//! Everything a command prints goes through [`outln!`] or [`out`]. The first
//! write that fails is kept, and every later one is dropped: the command still
//! does its work (its files are written whole and committed; what it prints is a
//! report of them), and [`crate::run`] then ends it with
//!
//! - exit [`BROKEN_PIPE_EXIT`] (141, what a shell reports for a command ended by
//!   `SIGPIPE`) and no message when the reader went away (`sil-host run --json |
//!   head -c 10`, `| true`): as `cat` ends, quietly;
//! - exit 1 and `error: cannot write to standard output: <why>` on standard
//!   error for any other failure (`> /dev/full`: "No space left on device").
//!
//! A command that would print for ever (`board watch`) asks [`failed`] and stops.
//! The command's own error, if it has one, wins over standard output's.

use std::{
    io::{self, Write},
    sync::Mutex,
};

/// The exit code of a command whose standard output's reader went away (128 +
/// `SIGPIPE`).
pub const BROKEN_PIPE_EXIT: i32 = 141;

/// The first error writing standard output, if any.
static FAILURE: Mutex<Option<io::Error>> = Mutex::new(None);

fn failure() -> std::sync::MutexGuard<'static, Option<io::Error>> {
    FAILURE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Whether a write to standard output has failed (later writes are dropped).
pub fn failed() -> bool {
    failure().is_some()
}

/// Takes the first error writing standard output (for [`crate::run`]'s exit).
pub fn take_failure() -> Option<io::Error> {
    failure().take()
}

fn keep(e: io::Error) {
    let mut f = failure();
    if f.is_none() {
        *f = Some(e);
    }
}

/// Writes `args` to standard output and flushes it; a failure is kept, not raised.
pub fn write_fmt(args: std::fmt::Arguments<'_>) {
    if failed() {
        return;
    }
    let mut o = io::stdout().lock();
    if let Err(e) = o.write_fmt(args).and_then(|()| o.flush()) {
        keep(e);
    }
}

/// Standard output as a writer whose writes never fail: the first error is kept
/// (see the module) and the rest dropped. Flushed when dropped.
pub fn out() -> Out {
    Out { lock: io::stdout().lock() }
}

/// See [`out`].
pub struct Out {
    lock: io::StdoutLock<'static>,
}

impl Write for Out {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if !failed()
            && let Err(e) = self.lock.write_all(buf)
        {
            keep(e);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        if !failed()
            && let Err(e) = self.lock.flush()
        {
            keep(e);
        }
        Ok(())
    }
}

impl Drop for Out {
    fn drop(&mut self) {
        let _ = self.flush();
    }
}

/// `println!` for commands: a line on standard output through
/// [`stdout::write_fmt`](crate::stdout::write_fmt) (never panics).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::stdout::write_fmt(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::stdout::write_fmt(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for commands (no newline), as [`outln!`].
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::stdout::write_fmt(format_args!($($arg)*))
    };
}
