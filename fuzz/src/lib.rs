//! Fuzzing harnesses that run on the pinned stable toolchain (issue 15, "Fuzzing in the
//! repository"): the firmware step under arbitrary frames and times
//! ([`firmware_step`]), the PIL wire decoder ([`pil_decode`]) and the scenario parser
//! with `--set` overrides ([`scenario`]). The binary `fuzz` runs them for millions of
//! cases (docs/fuzzing.md); the crate's tests run a few thousand cases of each.
//!
//! # Why proptest, not cargo-fuzz or `arbitrary`
//!
//! cargo-fuzz (libFuzzer) needs a nightly compiler and sanitizers; the toolchain is
//! pinned to stable 1.95.0. `arbitrary` with a seeded RNG runs on stable but gives
//! unstructured inputs and no shrinking. proptest is already in the workspace (the
//! firmware's and drivers' property tests), generates structured inputs (valid
//! configurations, frame sequences with sequence and time jumps, TOML documents
//! built from the scenario's key set), and **shrinks** a failing input to a minimal
//! one before reporting it. Its runner takes a seeded RNG ([`proptest::test_runner::TestRng::from_seed`],
//! ChaCha) and a [`proptest::test_runner::Config`] without failure persistence, so a
//! run is reproducible from its seed alone.
//!
//! # Reproducibility
//!
//! Case `k` of a run with seed `S` draws its input from a ChaCha RNG keyed by
//! `(S, k)` alone ([`case_seed`]), never from the cases before it: a failure is
//! replayed with `fuzz TARGET --seed S --case k`, without running the cases before
//! it, and a run's outcome does not depend on how it is split or on the profile
//! (debug or release).
//!
//! # Stack
//!
//! A stack overflow aborts the process (it is not a panic and cannot be caught), so
//! the harnesses run on a thread with the 8 MiB stack of a Linux main thread
//! ([`HARNESS_STACK_BYTES`], [`on_harness_thread`]): what the harness survives,
//! `sil-host`'s main thread survives too.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod firmware_step;
pub mod pil_decode;
pub mod scenario;

use std::{cell::RefCell, fmt::Debug, time::Instant};

use proptest::{
    strategy::{Strategy, ValueTree},
    test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner},
};

/// The stack of the thread the harnesses run on, bytes: 8 MiB, a Linux main
/// thread's default (`ulimit -s`), the stack `sil-host` parses scenarios on.
pub const HARNESS_STACK_BYTES: usize = 8 << 20;

/// Shrinking steps at most per failure (each re-runs the property on a smaller input).
pub const MAX_SHRINK_ITERS: u32 = 20_000;

/// A harness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Target {
    /// [`firmware_step`]: `firmware::Firmware::step` under hostile frames and times.
    FirmwareStep,
    /// [`pil_decode`]: `firmware::pil::decode` under mutated and random frames.
    PilDecode,
    /// [`scenario`]: `rig::scenario::Scenario::from_toml_with` under hostile documents.
    Scenario,
}

impl Target {
    /// Every target, in the order `all` runs them.
    pub const ALL: [Target; 3] = [Target::FirmwareStep, Target::PilDecode, Target::Scenario];

    /// The name on the command line (`firmware-step`, `pil-decode`, `scenario`).
    pub fn name(self) -> &'static str {
        match self {
            Self::FirmwareStep => "firmware-step",
            Self::PilDecode => "pil-decode",
            Self::Scenario => "scenario",
        }
    }

    /// Runs cases `first..first + count` of seed `seed`; `progress` is called with
    /// the number of cases done so far (every [`PROGRESS_EVERY`] cases and at the end).
    /// Stops at the first failing case.
    pub fn run(self, seed: u64, first: u64, count: u64, progress: &mut dyn FnMut(u64)) -> Report {
        match self {
            Self::FirmwareStep => {
                run_strategy(self.name(), &firmware_step::strategy(), &firmware_step::check, seed, first, count, progress)
            }
            Self::PilDecode => run_strategy(self.name(), &pil_decode::strategy(), &pil_decode::check, seed, first, count, progress),
            Self::Scenario => run_strategy(self.name(), &scenario::strategy(), &scenario::check, seed, first, count, progress),
        }
    }
}

impl Target {
    /// The input of case `case` of seed `seed`, `{:#?}`, without running it (to see
    /// a case that aborts the process, such as a stack overflow).
    pub fn show(self, seed: u64, case: u64) -> String {
        match self {
            Self::FirmwareStep => show_case(&firmware_step::strategy(), seed, case),
            Self::PilDecode => show_case(&pil_decode::strategy(), seed, case),
            Self::Scenario => show_case(&scenario::strategy(), seed, case),
        }
    }
}

fn show_case<S: Strategy>(strategy: &S, seed: u64, case: u64) -> String
where
    S::Value: Debug,
{
    let mut runner = TestRunner::new_with_rng(runner_config(), TestRng::from_seed(RngAlgorithm::ChaCha, &case_seed(seed, case)));
    match strategy.new_tree(&mut runner) {
        Ok(tree) => format!("{:#?}", tree.current()),
        Err(why) => format!("generation aborted: {why}"),
    }
}

/// How often [`Target::run`] reports progress, cases.
pub const PROGRESS_EVERY: u64 = 256;

/// A failing case, shrunk.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// Index of the case in its run (replay: `--seed S --case K`).
    pub case: u64,
    /// What the property says is wrong (a panic's message and place included).
    pub message: String,
    /// The minimal failing input, `{:#?}`.
    pub input: String,
    /// Shrinking steps that still failed.
    pub shrink_steps: u32,
}

/// The outcome of [`Target::run`].
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The target's name ([`Target::name`]).
    pub target: &'static str,
    /// The run's seed.
    pub seed: u64,
    /// Cases run (the failing one included).
    pub cases: u64,
    /// Wall time, s.
    pub seconds: f64,
    /// The first failure, if any.
    pub failure: Option<Failure>,
}

impl Report {
    /// Cases per second of wall time.
    pub fn cases_per_second(&self) -> f64 {
        if self.seconds > 0.0 { self.cases as f64 / self.seconds } else { 0.0 }
    }
}

/// The 32-byte ChaCha key of case `case` of seed `seed`: both little-endian, then a
/// fixed tag (a run is the same on every machine and every proptest 1.x).
pub fn case_seed(seed: u64, case: u64) -> [u8; 32] {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&case.to_le_bytes());
    key[16..].copy_from_slice(b"painleve-fuzz/1\0");
    key
}

/// The proptest configuration of every case: one case per runner (the RNG is
/// re-keyed per case), no failure files, no fork or timeout, bounded shrinking.
fn runner_config() -> Config {
    Config {
        cases: 1,
        failure_persistence: None,
        max_shrink_iters: MAX_SHRINK_ITERS,
        max_shrink_time: 0,
        fork: false,
        timeout: 0,
        verbose: 0,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    }
}

thread_local! {
    /// The last panic's message and place on this thread (set by [`quiet_panics`]'s hook).
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Replaces the panic hook by one that prints nothing and records the panic's
/// message and place for the failure report (the binary: a shrinking run panics
/// thousands of times). Tests keep the default hook.
pub fn quiet_panics() {
    std::panic::set_hook(Box::new(|info| {
        let place = info.location().map(|l| format!(" at {}:{}:{}", l.file(), l.line(), l.column())).unwrap_or_default();
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "<non-string panic>".into());
        LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("panic: {msg}{place}")));
    }));
}

/// Runs cases `first..first + count` of seed `seed` of `check` on inputs from
/// `strategy` (what [`Target::run`] does for each target; `name` labels the
/// report): each case's input from its own RNG ([`case_seed`]), a failure shrunk
/// and reported with its case index. Stops at the first failure.
pub fn run_strategy<S: Strategy>(
    target: &'static str,
    strategy: &S,
    check: &dyn Fn(&S::Value) -> Result<(), String>,
    seed: u64,
    first: u64,
    count: u64,
    progress: &mut dyn FnMut(u64),
) -> Report
where
    S::Value: Debug,
{
    let start = Instant::now();
    let mut runner = TestRunner::new_with_rng(runner_config(), TestRng::from_seed(RngAlgorithm::ChaCha, &case_seed(seed, first)));
    let test = |v: S::Value| check(&v).map_err(TestCaseError::fail);
    let mut failure = None;
    let mut done = 0;
    while done < count {
        let case = first + done;
        *runner.rng() = TestRng::from_seed(RngAlgorithm::ChaCha, &case_seed(seed, case));
        done += 1;
        let outcome = match strategy.new_tree(&mut runner) {
            Ok(tree) => {
                let shrunk = std::cell::Cell::new(0u32);
                let counted = |v: S::Value| {
                    let r = test(v);
                    if r.is_err() {
                        shrunk.set(shrunk.get() + 1);
                    }
                    r
                };
                runner.run_one(tree, counted).map(|_| ()).map_err(|e| (e, shrunk.get().saturating_sub(1)))
            }
            Err(why) => Err((TestError::Abort(why), 0)),
        };
        if let Err((e, shrink_steps)) = outcome {
            failure = Some(match e {
                TestError::Fail(why, value) => {
                    // Once more on the minimal input, to report the panic's place.
                    LAST_PANIC.with(|p| p.borrow_mut().take());
                    let again = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| check(&value)));
                    let message = match (again, LAST_PANIC.with(|p| p.borrow_mut().take())) {
                        (Err(_), Some(panic)) => panic,
                        (Ok(Err(msg)), _) => msg,
                        _ => why.to_string(),
                    };
                    Failure { case, message, input: format!("{value:#?}"), shrink_steps }
                }
                TestError::Abort(why) => {
                    Failure { case, message: format!("generation aborted: {why}"), input: String::new(), shrink_steps: 0 }
                }
            });
            break;
        }
        if done % PROGRESS_EVERY == 0 {
            progress(done);
        }
    }
    progress(done);
    Report { target, seed, cases: done, seconds: start.elapsed().as_secs_f64(), failure }
}

/// Runs `f` on a thread with a [`HARNESS_STACK_BYTES`] stack and returns its result.
///
/// # Panics
/// When the thread cannot be spawned, or `f` panics outside a case (a harness defect).
pub fn on_harness_thread<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .name("fuzz-harness".into())
        .stack_size(HARNESS_STACK_BYTES)
        .spawn(f)
        .expect("spawn the harness thread")
        .join()
        .unwrap_or_else(|e| std::panic::resume_unwind(e))
}

/// `Ok` when `ok`, else `Err(msg())`: the properties' `ensure`.
///
/// # Errors
/// `msg()` when `ok` is false.
pub fn ensure(ok: bool, msg: impl FnOnce() -> String) -> Result<(), String> {
    if ok { Ok(()) } else { Err(msg()) }
}
