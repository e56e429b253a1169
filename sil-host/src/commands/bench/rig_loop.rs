//! The rig's loop figures: the default scenario closed in-process, in lockstep over
//! iceoryx2 (the firmware in its own process, spawned before the clock starts) and,
//! when asked, in real time at 1 kHz. Runs keep no records ([`stream_loop`], as `run`).

use experiments::run_observer::{Gather, RunSink};
use std::time::Instant;

use crate::bench::figure::{Figure, Goal, median};
use crate::{cli::BenchArgs, error::CliError};
#[cfg(feature = "board")]
use board_link::TwinLink;
use rig::{
    FirmwareLink,
    in_process::InProcessLink,
    ipc::{MonitorPolicy, default_rig_name},
    ipc_link::{IpcLink, LinkTimings},
    scenario::Scenario,
    setup::RunSetup,
    stream_loop,
    summary::Percentiles,
};

/// Target of the in-process loop, periods per wall second (issue 16).
pub const IN_PROCESS_TARGET: f64 = 1_000_000.0;
/// Target of lockstep over iceoryx2, periods per wall second (issue 16).
pub const LOCKSTEP_TARGET: f64 = 350_000.0;
/// Target of the board twin's closed loop, periods per wall second (issue 23).
#[cfg(feature = "board")]
pub const TWIN_TARGET: f64 = 100_000.0;

/// Counts the plant's deadline misses as the run goes.
#[derive(Default)]
struct Misses(usize);

impl RunSink for Misses {
    fn record(&mut self, r: &rig::record::PeriodRecord) {
        self.0 += usize::from(r.deadline_miss);
    }
}

/// Runs `setup` over `link`: periods run, periods per wall second and deadline
/// misses, or the run's error.
fn timed(setup: &RunSetup, link: &mut dyn FirmwareLink) -> Result<(usize, f64, usize), CliError> {
    let mut misses = Gather::new(Misses::default(), None);
    let t = Instant::now();
    let (periods, e) = stream_loop(setup, link, &mut misses);
    let rate = periods as f64 / t.elapsed().as_secs_f64();
    match e {
        Some(e) => Err(CliError::from(e)),
        None => Ok((periods, rate, misses.sink.0)),
    }
}

/// The run of the default scenario, `duration_s` long, with a 1 s command timeout (the
/// default's 50 ms guards against a stalled firmware; a benchmark on a loaded
/// machine (issue 27) must measure a slow loop, not latch the firmware's safe state
/// after three descheduled waits in a row).
fn scenario(duration_s: f64) -> Result<RunSetup, CliError> {
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = duration_s;
    s.rig.command_timeout_s = 1.0;
    s.validate()?;
    RunSetup::new(s).map_err(CliError::from)
}

fn this_exe() -> Result<std::path::PathBuf, CliError> {
    std::env::current_exe().map_err(|e| CliError::bad_input(format!("cannot find this executable: {e}")))
}

fn fmt(p: &Percentiles) -> String {
    format!("p50 {:.2}, p99 {:.2}, p999 {:.1}, max {:.1} us", p.p50, p.p99, p.p999, p.max)
}

/// The in-process closed loop: median periods per wall second over `--repeat` runs.
///
/// # Errors
/// A run that fails (exit 1).
pub fn in_process(args: &BenchArgs) -> Result<Figure, CliError> {
    let setup = scenario(args.duration)?;
    let mut rates = Vec::new();
    let mut misses = 0;
    for _ in 0..args.repeat {
        let mut link = InProcessLink::new(&setup).map_err(CliError::from)?;
        let (_, rate, m) = timed(&setup, &mut link)?;
        rates.push(rate);
        misses += m;
    }
    let name = "in-process closed loop (default scenario)";
    Ok(Figure::measured("in_process", "in-process", name, median(&rates), "periods/s", IN_PROCESS_TARGET, Goal::AtLeast)
        .note(format!("{} runs of {} periods; deadline misses {misses}", rates.len(), setup.scenario().timing.periods()))
        .with_runs(rates))
}

/// The board twin's closed loop (`run --link twin`): median periods per wall
/// second over `--repeat` runs.
///
/// # Errors
/// A run that fails (exit 1).
#[cfg(feature = "board")]
pub fn twin(args: &BenchArgs) -> Result<Figure, CliError> {
    let setup = scenario(args.duration)?;
    let mut rates = Vec::new();
    let mut misses = 0;
    for _ in 0..args.repeat {
        let mut link = TwinLink::new(&setup).map_err(CliError::from)?;
        let (_, rate, m) = timed(&setup, &mut link)?;
        rates.push(rate);
        misses += m;
    }
    let name = "board twin closed loop (default scenario)";
    Ok(Figure::measured("twin", "twin", name, median(&rates), "periods/s", TWIN_TARGET, Goal::AtLeast)
        .note(format!("{} runs of {} periods; deadline misses {misses}", rates.len(), setup.scenario().timing.periods()))
        .with_runs(rates))
}

/// Lockstep over iceoryx2: median periods per wall second and the round trip.
///
/// # Errors
/// A run or the firmware process that fails (exit 1).
pub fn lockstep(args: &BenchArgs) -> Result<Figure, CliError> {
    let setup = scenario(args.duration)?;
    let exe = this_exe()?;
    let mut rates = Vec::new();
    let mut misses = 0;
    let mut timings = LinkTimings::default();
    for _ in 0..args.repeat {
        let mut link =
            IpcLink::connect(&setup, &default_rig_name(), Some(&exe), false, &MonitorPolicy::default()).map_err(CliError::from)?;
        let (_, rate, m) = timed(&setup, &mut link)?;
        rates.push(rate);
        misses += m;
        timings.rtt.merge(&link.timings.rtt);
    }
    let name = "lockstep over iceoryx2 (firmware in its own process)";
    Ok(Figure::measured("lockstep", "lockstep", name, median(&rates), "periods/s", LOCKSTEP_TARGET, Goal::AtLeast)
        .note(format!(
            "{} runs of {} periods; round trip {}; deadline misses {misses}",
            rates.len(),
            setup.scenario().timing.periods(),
            fmt(&timings.rtt.percentiles())
        ))
        .with_runs(rates))
}

/// Real time at 1 kHz over iceoryx2 for `--realtime-s`: deadline misses (target 0),
/// with the jitter, the step and the round trip.
///
/// # Errors
/// A run or the firmware process that fails (exit 1).
pub fn realtime(args: &BenchArgs) -> Result<Figure, CliError> {
    let setup = scenario(args.realtime_s)?;
    let exe = this_exe()?;
    let mut link = IpcLink::connect(&setup, &default_rig_name(), Some(&exe), true, &MonitorPolicy::default()).map_err(CliError::from)?;
    let (periods, _, misses) = timed(&setup, &mut link)?;
    let name = format!("real time at 1 kHz over iceoryx2, {} s: deadline misses", args.realtime_s);
    let mut f = Figure::measured("realtime_misses", "realtime", name, misses as f64, "misses", 0.0, Goal::AtMost)
        .note(format!("{periods} periods; period jitter {}", fmt(&link.timings.jitter.percentiles())))
        .note(format!("firmware step {}; round trip {}", fmt(&link.timings.step.percentiles()), fmt(&link.timings.rtt.percentiles())));
    if let Some(r) = &link.realtime_setup {
        f = f.note(format!("control loops on {}", r.describe()));
        for w in &r.warnings {
            f = f.note(format!("warning: {w}"));
        }
    }
    Ok(f)
}
