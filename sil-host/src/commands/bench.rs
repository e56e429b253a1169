//! `sil-host bench`: the rig's speed figures (issue targets: in-process at least
//! 300 000 control periods per wall second, lockstep over iceoryx2 at least
//! 100 000; real time at 1 kHz with zero deadline misses), measured on the
//! default scenario in one invocation so that the ratios compare like with like.

use std::{io::Write, time::Instant};

use serde::Serialize;

use crate::{cli::BenchArgs, error::CliError};
use rig::{
    in_process::InProcessLink,
    ipc::{MonitorPolicy, default_rig_name},
    ipc_link::IpcLink,
    realtime::RealtimeSetup,
    rig::{RunObserver, stream_loop},
    scenario::Scenario,
    summary::Percentiles,
};

/// One transport's figures.
#[derive(Debug, Clone, Serialize)]
pub struct TransportFigures {
    /// `in-process`, `iceoryx2 lockstep` or `iceoryx2 realtime`.
    pub transport: String,
    /// Runs measured.
    pub runs: usize,
    /// Periods per run.
    pub periods: usize,
    /// Median over the runs of periods per wall second.
    pub median_periods_per_s: f64,
    /// Every run's periods per wall second.
    pub periods_per_s: Vec<f64>,
    /// iceoryx2: round trip over all runs, us.
    pub rtt_us: Option<Percentiles>,
    /// Real time: period jitter, us.
    pub jitter_us: Option<Percentiles>,
    /// Real time: the firmware's step time, us.
    pub step_us: Option<Percentiles>,
    /// Real time: the control loops' CPU and scheduling, and what the kernel refused.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub realtime_setup: Option<RealtimeSetup>,
    /// Deadline misses over all runs (plant side).
    pub deadline_misses: usize,
    /// The target, periods per wall second (or misses for real time).
    pub target: f64,
    /// Whether the median meets it.
    pub meets_target: bool,
}

/// Counts the plant's deadline misses as the run goes (the bench keeps no records, as `run`).
#[derive(Default)]
struct Misses(usize);

impl RunObserver for Misses {
    fn on_record(&mut self, r: &rig::record::PeriodRecord) {
        self.0 += usize::from(r.deadline_miss);
    }
}

/// Runs `s` over `link` ([`stream_loop`]): periods run, periods per wall second
/// and deadline misses, or the run's error.
fn timed(s: &Scenario, link: &mut dyn rig::rig::FirmwareLink) -> Result<(usize, f64, usize), CliError> {
    let mut misses = Misses::default();
    let t = Instant::now();
    let (periods, e) = stream_loop(s, link, &mut misses);
    let rate = periods as f64 / t.elapsed().as_secs_f64();
    match e {
        Some(e) => Err(CliError::Run(e)),
        None => Ok((periods, rate, misses.0)),
    }
}

/// Measures the rig's speed (in-process and iceoryx2 lockstep, and a real-time
/// run when asked); prints nothing.
///
/// # Errors
/// A failing run or the firmware process (exit 1); bad arguments (exit 2).
pub fn execute(args: &BenchArgs) -> Result<Vec<TransportFigures>, CliError> {
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = args.duration;
    s.validate()?;
    let n = s.timing.periods() as usize;
    let exe = std::env::current_exe().map_err(|e| CliError::BadInput(format!("cannot find this executable: {e}")))?;
    let mut figures = Vec::new();

    // In-process.
    let mut rates = Vec::new();
    let mut missed = 0;
    for _ in 0..args.repeat {
        let mut link = InProcessLink::new(&s).map_err(CliError::Run)?;
        let (_, rate, misses) = timed(&s, &mut link)?;
        rates.push(rate);
        missed += misses;
    }
    figures.push(summarise("in-process", rates, n, missed, None, 300_000.0));

    // Lockstep over iceoryx2 (one firmware process per run, spawned before the clock starts).
    let mut rates = Vec::new();
    let mut missed = 0;
    let mut timings = rig::ipc_link::LinkTimings::default();
    for _ in 0..args.repeat {
        let mut link = IpcLink::connect(&s, &default_rig_name(), Some(&exe), false, &MonitorPolicy::default()).map_err(CliError::Run)?;
        let (_, rate, misses) = timed(&s, &mut link)?;
        rates.push(rate);
        missed += misses;
        timings.rtt.merge(&link.timings.rtt);
    }
    figures.push(summarise("iceoryx2 lockstep", rates, n, missed, Some(&timings), 100_000.0));

    // Real time at 1 kHz.
    if args.realtime_s > 0.0 {
        let mut rt = s.clone();
        rt.timing.duration_s = args.realtime_s;
        let mut link = IpcLink::connect(&rt, &default_rig_name(), Some(&exe), true, &MonitorPolicy::default()).map_err(CliError::Run)?;
        let (periods, rate, missed) = timed(&rt, &mut link)?;
        let mut f = summarise("iceoryx2 realtime", vec![rate], periods, missed, Some(&link.timings), 0.0);
        f.jitter_us = Some(link.timings.jitter.percentiles());
        f.step_us = Some(link.timings.step.percentiles());
        f.realtime_setup = link.realtime_setup.clone();
        f.meets_target = missed == 0;
        figures.push(f);
    }

    Ok(figures)
}

/// Runs `sil-host bench`.
///
/// # Errors
/// A run that fails (exit 1).
pub fn run(args: &BenchArgs) -> Result<(), CliError> {
    let figures = execute(args)?;
    if args.json {
        let json = serde_json::to_string_pretty(&figures).map_err(|e| CliError::BadInput(e.to_string()))?;
        println!("{json}");
        return Ok(());
    }
    let mut o = std::io::stdout().lock();
    for f in &figures {
        let _ = writeln!(
            o,
            "{:<18} {} runs x {} periods: median {:>9.0} periods/s (runs: {}) target {} -> {}",
            f.transport,
            f.runs,
            f.periods,
            f.median_periods_per_s,
            f.periods_per_s.iter().map(|r| format!("{r:.0}")).collect::<Vec<_>>().join(", "),
            if f.target > 0.0 { format!("{:.0}/s", f.target) } else { "0 misses".into() },
            if f.meets_target { "met" } else { "NOT met" }
        );
        let fmt = |p: &Percentiles| format!("p50 {:.1}, p99 {:.1}, p999 {:.1}, max {:.1} us", p.p50, p.p99, p.p999, p.max);
        if let Some(p) = &f.rtt_us {
            let _ = writeln!(o, "{:<18} round trip {}", "", fmt(p));
        }
        if let Some(p) = &f.jitter_us {
            let _ = writeln!(o, "{:<18} period jitter {} | deadline misses {}", "", fmt(p), f.deadline_misses);
        }
        if let Some(p) = &f.step_us {
            let _ = writeln!(o, "{:<18} firmware step {}", "", fmt(p));
        }
        if let Some(r) = &f.realtime_setup {
            let _ = writeln!(o, "{:<18} control loops on {}", "", r.describe());
            for w in &r.warnings {
                let _ = writeln!(o, "{:<18} warning: {w}", "");
            }
        }
    }
    Ok(())
}

fn summarise(
    transport: &str,
    rates: Vec<f64>,
    periods: usize,
    deadline_misses: usize,
    timings: Option<&rig::ipc_link::LinkTimings>,
    target: f64,
) -> TransportFigures {
    let mut sorted = rates.clone();
    sorted.sort_by(f64::total_cmp);
    let median = if sorted.is_empty() { 0.0 } else { sorted[sorted.len() / 2] };
    TransportFigures {
        transport: transport.into(),
        runs: rates.len(),
        periods,
        median_periods_per_s: median,
        periods_per_s: rates,
        rtt_us: timings.map(|t| t.rtt.percentiles()),
        jitter_us: None,
        step_us: None,
        realtime_setup: None,
        deadline_misses,
        target,
        meets_target: median >= target,
    }
}
