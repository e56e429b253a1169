//! Long calls: the work runs on a thread of its own without the GIL, while the
//! calling (Python) thread waits for it, polls `Python::check_signals` every
//! 100 ms and reports progress.
//!
//! Ctrl-C: Python's SIGINT handler marks the signal; the waiting thread sees it
//! through `check_signals` (which raises `KeyboardInterrupt`), sets the work's
//! stop flag, the flag the experiments' loops read (the CLI's signal handler sets it;
//! here one per call, never a process-wide signal handler: Python keeps its
//! own), waits for the work to wind down (a sweep stops within its current
//! run, a closed-loop run within its period, a `Z_t,sliding` search before its
//! next trial, `poincare` before its next belt speed, a simulation within its
//! chunk of 0.25 s of samples) and raises the `KeyboardInterrupt`.

use std::{
    panic::{AssertUnwindSafe, catch_unwind},
    sync::{
        Condvar, Mutex,
        atomic::{AtomicBool, AtomicU64, Ordering},
    },
    time::{Duration, Instant},
};

use pyo3::{exceptions::PyRuntimeError, prelude::*};

/// What the work and the waiting thread share: the stop flag and the progress.
#[derive(Debug, Default)]
pub struct Control {
    /// Set on Ctrl-C (or when a progress callback raises): the work stops early.
    pub stop: AtomicBool,
    /// Units of work done.
    pub done: AtomicU64,
    /// Units of work in all (0: not known yet).
    pub total: AtomicU64,
}

impl Control {
    /// One more unit done.
    pub fn tick(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }

    /// Sets the progress to `done` of `total`.
    pub fn set(&self, done: u64, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.done.store(done, Ordering::Relaxed);
    }

    /// Whether the work should stop.
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// How progress is shown: `progress=False`/`None` nothing, `True` a line on
/// `sys.stderr` rewritten in place (`\r`), a callable `f(done, total)` called
/// instead, or an object with a method `show(text, last)` given the same line
/// (`painleve._progress.NotebookLine`, which `painleve` passes for `True` under
/// Jupyter: one display output updated in place, not a stream of rewrites).
enum Reporter {
    Silent,
    Text { label: &'static str, unit: &'static str, shown: bool, line: Option<Py<PyAny>> },
    Callback(Py<PyAny>),
}

impl Reporter {
    fn new(progress: Option<&Bound<'_, PyAny>>, label: &'static str, unit: &'static str) -> PyResult<Self> {
        Ok(match progress {
            None => Self::Silent,
            Some(p) if p.is_callable() => Self::Callback(p.clone().unbind()),
            Some(p) if p.hasattr("show")? => Self::Text { label, unit, shown: false, line: Some(p.clone().unbind()) },
            Some(p) if p.is_truthy()? => Self::Text { label, unit, shown: false, line: None },
            Some(_) => Self::Silent,
        })
    }

    fn report(&mut self, py: Python<'_>, c: &Control, started: Instant, last: bool) -> PyResult<()> {
        let (done, total) = (c.done.load(Ordering::Relaxed), c.total.load(Ordering::Relaxed));
        match self {
            Self::Silent => Ok(()),
            Self::Callback(f) => f.call1(py, (done, total)).map(|_| ()),
            Self::Text { label, unit, shown, line } => {
                let elapsed = started.elapsed().as_secs_f64();
                // Quick calls print nothing; a long one shows its line from 0.5 s on.
                if !*shown && (last || elapsed < 0.5) {
                    return Ok(());
                }
                *shown = true;
                let of = if total > 0 {
                    format!("{done}/{total} {unit} ({:.0} %)", 100.0 * done as f64 / total as f64)
                } else {
                    format!("{done} {unit}")
                };
                let eta = if total > 0 && done > 0 && done < total && !last {
                    format!(", about {:.0} s left", elapsed * (total - done) as f64 / done as f64)
                } else {
                    String::new()
                };
                let text = format!("{label}: {of}, {elapsed:.1} s{eta}");
                match line {
                    Some(sink) => sink.call_method1(py, "show", (text, last)).map(|_| ()),
                    None => write_stderr(py, &format!("\r{text}   {}", if last { "\n" } else { "" })),
                }
            }
        }
    }

    /// Ends a progress line left open by an interrupted call (so that the traceback
    /// starts on a line of its own).
    fn interrupted(&self, py: Python<'_>) {
        if let Self::Text { shown: true, line: None, .. } = self {
            let _ = write_stderr(py, "\n");
        }
    }
}

/// Writes to Python's `sys.stderr` (where Jupyter shows it under the cell);
/// nothing when there is none (`pythonw`).
fn write_stderr(py: Python<'_>, text: &str) -> PyResult<()> {
    let stderr = py.import("sys")?.getattr("stderr")?;
    if stderr.is_none() {
        return Ok(());
    }
    stderr.call_method1("write", (text,))?;
    stderr.call_method0("flush")?;
    Ok(())
}

/// Runs `work` on a thread of its own, without the GIL, while this thread waits,
/// polls for signals and reports progress (`progress`: see [`Reporter`]; `label`
/// and `unit` name the work and its units in the text line).
///
/// # Errors
/// `KeyboardInterrupt` (or whatever `check_signals` raises) after the work
/// stopped; the progress callback's exception, likewise; `RuntimeError` when the
/// work panicked (a bug: the message says where).
pub fn run<T, F>(py: Python<'_>, progress: Option<&Bound<'_, PyAny>>, label: &'static str, unit: &'static str, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Control) -> T + Send,
{
    let mut reporter = Reporter::new(progress, label, unit)?;
    let control = Control::default();
    let finished = (Mutex::new(false), Condvar::new());
    let started = Instant::now();
    std::thread::scope(|scope| {
        let (control, finished) = (&control, &finished);
        let worker = std::thread::Builder::new()
            .name(format!("painleve-{label}"))
            .spawn_scoped(scope, move || {
                let out = catch_unwind(AssertUnwindSafe(|| work(control)));
                let (lock, cv) = finished;
                *lock.lock().unwrap_or_else(|p| p.into_inner()) = true;
                cv.notify_all();
                out
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?;
        let mut raised: Option<PyErr> = None;
        let mut last_report = Instant::now();
        loop {
            let done = py.detach(|| {
                let (lock, cv) = finished;
                let guard = lock.lock().unwrap_or_else(|p| p.into_inner());
                let (guard, _) = cv.wait_timeout_while(guard, Duration::from_millis(100), |f| !*f).unwrap_or_else(|p| p.into_inner());
                *guard
            });
            if done {
                break;
            }
            if raised.is_some() {
                continue;
            }
            if let Err(e) = py.check_signals() {
                control.stop.store(true, Ordering::Relaxed);
                raised = Some(e);
                continue;
            }
            if last_report.elapsed() >= Duration::from_millis(250) {
                last_report = Instant::now();
                if let Err(e) = reporter.report(py, control, started, false) {
                    control.stop.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
        }
        let out = py.detach(|| worker.join()).unwrap_or_else(Err);
        if let Some(e) = raised {
            reporter.interrupted(py);
            return Err(e);
        }
        reporter.report(py, control, started, true)?;
        out.map_err(|panic| {
            let what = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("(no message)");
            PyRuntimeError::new_err(format!("painleve: internal error in {label} (a panic; please report it): {what}"))
        })
    })
}
