//! `sil-host run`: a closed-loop SIL run of a scenario, and `sil-host firmware`,
//! the firmware process it talks to.
//!
//! Writes `trace.csv` (one row per control period), `summary.json` and
//! `trace.svg` (tip position against its reference, normal force, torques and
//! contact mode against time). A run that stops part way (the firmware in its
//! safe state or lost, a plant failure, Ctrl-C) still writes every period up to
//! then and exits with code 1. The trace is streamed to `trace.csv.partial` while
//! the run goes (flushed every millisecond of wall time) and renamed at the end,
//! so a plant killed outright (SIGKILL) still leaves its rows on disk.

use std::{
    io::Write,
    path::PathBuf,
    sync::{
        Arc,
        atomic::{AtomicBool, Ordering},
    },
    time::Instant,
};

use serde::Serialize;

use crate::{
    cli::{ControllerArg, FirmwareArgs, PaperX0, RunArgs, ScenarioArgs},
    error::CliError,
    output::{OutputSet, StreamedCsv, progress_bar},
    plot,
    sil::{
        firmware_process::{self, Ending},
        in_process::InProcessLink,
        ipc::{RealtimeSetup, check_rig_name, default_rig_name},
        ipc_link::{IpcLink, Percentiles, percentiles},
        record::{LiftOffStats, PeriodRecord, RunError, lift_off_stats},
        rig::{FirmwareLink, run_loop_streaming},
        scenario::Scenario,
        setup::{firmware_config, plant_for},
    },
};

/// `summary.json` of a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// `ok` or `failed`.
    pub status: &'static str,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
    /// Scenario name.
    pub scenario: String,
    /// `hybrid` or `pid`.
    pub controller: String,
    /// `iceoryx2` or `in-process`; `pil-qemu` or `pil-serial` for `sil-host pil`.
    pub transport: &'static str,
    /// `lockstep` or `realtime` (`in-process` runs are lockstep).
    pub timing: &'static str,
    /// The rig's name (its iceoryx2 services); `null` in-process.
    pub rig: Option<String>,
    /// Control periods run.
    pub periods: usize,
    /// Lift-off statistics.
    #[serde(flatten)]
    pub lift_off: LiftOffStats,
    /// Deadline misses seen by the plant (no command, lost, or late past `t_k + Ts`).
    pub deadline_misses: usize,
    /// Deadline misses the firmware counted itself (its overrun counter at the end).
    pub firmware_overruns: u32,
    /// RMS of `z_t - z_t*` over the run, m.
    pub rms_tracking_error_m: f64,
    /// `z_t` at the end, m.
    pub final_z_t_m: f64,
    /// Wall-clock time of the loop, s.
    pub wall_s: f64,
    /// Simulated seconds per wall second.
    pub realtime_factor: f64,
    /// Control periods per wall-clock second.
    pub periods_per_s: f64,
    /// iceoryx2 runs: frame published to command received, us.
    pub ipc_rtt_us: Option<Percentiles>,
    /// iceoryx2 runs: the firmware's step time as it measured it, us.
    pub firmware_step_us: Option<Percentiles>,
    /// Real-time runs: frame publication minus its ideal wall time, us.
    pub period_jitter_us: Option<Percentiles>,
    /// iceoryx2 runs: commands that arrived after their period was given up.
    pub late_answers: u64,
    /// Real-time iceoryx2 runs: the plant loop's CPU and `SCHED_FIFO` priority,
    /// and what the kernel refused (`rig.realtime_cpu`, `rig.realtime_fifo_priority`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub realtime_setup: Option<RealtimeSetup>,
    /// PIL runs: the image's instruction counts and log (`sil-host pil`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pil: Option<crate::commands::pil::PilFigures>,
    /// The scenario as run (after command-line overrides).
    pub scenario_used: Scenario,
}

impl RunSummary {
    /// The figures every run has, from its `records` (the trace as recorded, up to
    /// the failure if there was one) and its wall-clock time `wall_s` (s); the
    /// transport's own figures (round trip, jitter, step time, PIL counts) empty.
    pub fn from_records(
        scenario: &Scenario,
        records: &[PeriodRecord],
        failure: Option<&RunError>,
        transport: &'static str,
        timing: &'static str,
        wall_s: f64,
    ) -> Self {
        let simulated = records.len() as f64 / scenario.timing.rate_hz;
        Self {
            status: if failure.is_some() { "failed" } else { "ok" },
            error: failure.map(|e| e.to_string()),
            scenario: scenario.name.clone(),
            controller: scenario.controller.kind.clone(),
            transport,
            timing,
            rig: None,
            periods: records.len(),
            lift_off: lift_off_stats(records),
            deadline_misses: records.iter().filter(|r| r.deadline_miss).count(),
            firmware_overruns: records.iter().map(|r| r.overruns).max().unwrap_or(0),
            rms_tracking_error_m: rms_tracking_error(records),
            final_z_t_m: records.last().map_or(f64::NAN, |r| r.z_t),
            wall_s,
            realtime_factor: simulated / wall_s.max(1e-9),
            periods_per_s: records.len() as f64 / wall_s.max(1e-9),
            ipc_rtt_us: None,
            firmware_step_us: None,
            period_jitter_us: None,
            late_answers: 0,
            realtime_setup: None,
            pil: None,
            scenario_used: scenario.clone(),
        }
    }
}

/// Loads the scenario and applies the overrides.
///
/// # Errors
/// [`CliError::BadInput`] or [`CliError::Scenario`] (exit 2).
pub fn load_scenario(args: &ScenarioArgs) -> Result<Scenario, CliError> {
    let mut s = match &args.scenario {
        Some(path) if path.as_os_str() == "-" => {
            let text = std::io::read_to_string(std::io::stdin())
                .map_err(|e| CliError::BadInput(format!("cannot read the scenario from stdin: {e}")))?;
            Scenario::from_toml(&text)?
        }
        Some(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| CliError::BadInput(format!("cannot read scenario {}: {e}", path.display())))?;
            Scenario::from_toml(&text)?
        }
        None => Scenario::default_scenario(),
    };
    if let Some(c) = args.controller {
        s.controller.kind = match c {
            ControllerArg::Pid => "pid",
            ControllerArg::Hybrid => "hybrid",
        }
        .into();
    }
    if let Some(x0) = args.x0 {
        s.plant.x0 = match x0 {
            PaperX0::A => "a",
            PaperX0::D => "d",
            PaperX0::U => "u",
        }
        .into();
    }
    if let Some(z) = args.target_zt {
        s.controller.target_z_t = z;
    }
    if let Some(d) = args.duration {
        s.timing.duration_s = d;
    }
    if let Some(seed) = args.seed {
        s.sensors.seed = seed;
    }
    s.validate()?;
    Ok(s)
}

/// RMS of `z_t - z_t*` over `records`, m (0 when empty).
pub fn rms_tracking_error(records: &[PeriodRecord]) -> f64 {
    if records.is_empty() {
        return 0.0;
    }
    (records.iter().map(|r| (r.z_t - r.z_t_ref).powi(2)).sum::<f64>() / records.len() as f64).sqrt()
}

/// Ctrl-C and SIGTERM set a flag the loop checks each period (so the trace so far is written).
pub(crate) fn stop_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, Arc::clone(&flag));
    }
    flag
}

/// Runs `scenario` over `link` as `run` and `pil` do: every period's row goes to
/// `trace.csv` of `out` as it is made (`trace.csv.partial`, flushed every 1 ms of
/// wall time, so a plant killed outright keeps every period up to the last
/// flush), the progress bar moves every `every` periods, Ctrl-C or SIGTERM stops
/// the run. Returns the records, why the run stopped early if it did, and the
/// loop's wall-clock time (s); the progress bar is cleared.
///
/// # Errors
/// I/O errors of the trace file.
pub(crate) fn run_streamed(
    scenario: &Scenario,
    link: &mut dyn FirmwareLink,
    out: &mut OutputSet,
    progress: &indicatif::ProgressBar,
    every: usize,
) -> Result<(Vec<PeriodRecord>, Option<RunError>, f64), CliError> {
    let stop = stop_flag();
    let mut trace = StreamedCsv::new(out, "trace.csv", std::time::Duration::from_millis(1))?;
    let started = Instant::now();
    let (records, failure) = run_loop_streaming(
        scenario,
        link,
        |r| trace.push(r),
        |k, _| {
            if k % every == 0 {
                progress.set_position(k as u64);
            }
            !stop.load(Ordering::Relaxed)
        },
        |_| {},
    );
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();
    trace.finish()?;
    Ok((records, failure, wall_s))
}

/// Runs `sil-host run`.
///
/// # Errors
/// Bad scenario or overrides (exit 2, nothing written); a run that stopped part
/// way (exit 1, everything up to then written); I/O or plotting failures.
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let scenario = load_scenario(&args.scenario)?;
    // Check the plant and firmware set-up before touching the output folder.
    plant_for(&scenario).map_err(CliError::Sim)?;
    firmware::Firmware::new(firmware_config(&scenario)).map_err(|e| CliError::BadInput(format!("firmware configuration: {e}")))?;
    if args.in_process && scenario.faults.iter().any(|f| f.needs_ipc()) {
        return Err(CliError::BadInput("the scenario's stall/kill_firmware faults act on the firmware process: drop --in-process".into()));
    }
    let rig = match (&args.attach, &args.rig) {
        (Some(name), _) | (None, Some(name)) => name.clone(),
        (None, None) => default_rig_name(),
    };
    check_rig_name(&rig).map_err(CliError::BadInput)?;
    let mut out = OutputSet::new(&args.output.out)?;

    let mut ipc: Option<IpcLink> = None;
    let mut in_process: Option<InProcessLink> = None;
    let link: &mut dyn FirmwareLink = if args.in_process {
        in_process.insert(InProcessLink::new(&scenario).map_err(CliError::Run)?)
    } else {
        let exe = match &args.attach {
            Some(_) => None,
            None => Some(
                std::env::current_exe()
                    .map_err(|e| CliError::BadInput(format!("cannot find this executable to spawn the firmware: {e}")))?,
            ),
        };
        ipc.insert(IpcLink::connect(&scenario, &rig, exe.as_deref(), args.realtime).map_err(CliError::Run)?)
    };
    let transport = link.transport();

    let n = (scenario.timing.duration_s * scenario.timing.rate_hz).round() as u64;
    let progress = progress_bar(n, "SIL run", "periods", args.output.json);
    let (records, failure, wall_s) = run_streamed(&scenario, link, &mut out, &progress, 500)?;
    let timings = ipc.as_ref().map(|l| l.timings.clone());
    let realtime_setup = ipc.as_ref().and_then(|l| l.realtime_setup.clone());
    drop(ipc);

    let svg = out.stage("trace.svg");
    draw(&svg, "SIL", &scenario, &records)?;
    let summary = RunSummary {
        rig: (!args.in_process).then(|| rig.clone()),
        ipc_rtt_us: timings.as_ref().map(|t| percentiles(&t.rtt_us)),
        firmware_step_us: timings.as_ref().map(|t| percentiles(&t.step_us)),
        period_jitter_us: timings.as_ref().filter(|_| args.realtime).map(|t| percentiles(&t.jitter_us)),
        late_answers: timings.as_ref().map_or(0, |t| t.late_answers),
        realtime_setup,
        ..RunSummary::from_records(
            &scenario,
            &records,
            failure.as_ref(),
            transport,
            if args.realtime { "realtime" } else { "lockstep" },
            wall_s,
        )
    };
    let json = out.write_json("summary.json", &summary)?;
    let written = out.commit()?;
    if args.output.json {
        println!("{json}");
    } else {
        print_summary(&summary, &scenario, &written);
    }
    match failure {
        Some(e) => Err(CliError::Run(e)),
        None => Ok(()),
    }
}

pub(crate) fn print_summary(summary: &RunSummary, scenario: &Scenario, written: &[PathBuf]) {
    let mut o = std::io::stdout().lock();
    let l = &summary.lift_off;
    let _ = writeln!(
        o,
        "{} run `{}` ({}, {} {}): {} periods in {:.2} s wall ({:.0}x real time, {:.0} periods/s)",
        match summary.transport {
            "pil-serial" => "HIL",
            _ if summary.pil.is_some() => "PIL",
            _ => "SIL",
        },
        summary.scenario,
        summary.controller,
        summary.transport,
        summary.timing,
        summary.periods,
        summary.wall_s,
        summary.realtime_factor,
        summary.periods_per_s
    );
    let _ = writeln!(
        o,
        "lift-offs {} (detected {}, missed {}, false alarms {}, max latency {} periods) | deadline misses {} (firmware counted {})",
        l.lift_offs,
        l.lift_offs_detected,
        l.missed_lift_offs,
        l.false_alarms,
        l.max_detection_latency_periods,
        summary.deadline_misses,
        summary.firmware_overruns
    );
    let _ = writeln!(
        o,
        "tracking: rms error {:.3} mm, final z_t {:.5} m (target {:.5} m)",
        summary.rms_tracking_error_m * 1e3,
        summary.final_z_t_m,
        scenario.controller.target_z_t
    );
    let fmt = |p: &Percentiles| format!("p50 {:.1}, p99 {:.1}, p999 {:.1}, max {:.1} us", p.p50, p.p99, p.p999, p.max);
    if let Some(p) = &summary.ipc_rtt_us {
        let _ = writeln!(o, "iceoryx2 round trip: {}", fmt(p));
    }
    if let Some(p) = &summary.firmware_step_us {
        let _ = writeln!(o, "firmware step: {}", fmt(p));
    }
    if let Some(p) = &summary.period_jitter_us {
        let _ = writeln!(o, "period jitter: {}", fmt(p));
    }
    if let Some(r) = &summary.realtime_setup {
        let _ = writeln!(o, "real-time loops: {}", r.describe());
        for w in &r.warnings {
            let _ = writeln!(o, "real-time set-up warning: {w}");
        }
    }
    if let Some(e) = &summary.error {
        let _ = writeln!(o, "STOPPED: {e}");
    }
    let _ = writeln!(o, "wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
}

/// Runs `sil-host firmware`: exit 0 when the plant ends the run, 3 when the plant died.
///
/// # Errors
/// Bad scenario (exit 2); transport failures (exit 1).
pub fn firmware(args: &FirmwareArgs) -> Result<i32, CliError> {
    let scenario = load_scenario(&args.scenario)?;
    check_rig_name(&args.rig).map_err(CliError::BadInput)?;
    match firmware_process::serve(&scenario, &args.rig, args.realtime).map_err(CliError::Run)? {
        Ending::EndOfRun { .. } => Ok(0),
        Ending::PeerLost { .. } => Ok(3),
    }
}

pub(crate) fn draw(path: &std::path::Path, what: &str, s: &Scenario, records: &[PeriodRecord]) -> Result<(), CliError> {
    let t_end = records.last().map_or(1.0, |r| r.t).max(1e-9);
    let samples: Vec<plot::HistorySample> = records
        .iter()
        .map(|r| plot::HistorySample { t: r.t, z_t: r.z_t, z_t_ref: r.z_t_ref, f_n: r.f_n, u: [r.u1_cmd, r.u2_cmd], mode: r.mode })
        .collect();
    let panels = plot::history_panels(&samples, true);
    let title = format!("{what} run {}: {} from x0{}, z_t* = {} m", s.name, s.controller.kind, s.plant.x0, s.controller.target_z_t);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
