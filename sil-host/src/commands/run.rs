//! `sil-host run`: a closed-loop SIL run of a scenario.
//!
//! Writes `trace.csv` (one row per control period; `trace.arrow` with `--format
//! arrow`, an Arrow IPC file; `trace.mcap` with `--format mcap`), `summary.json`,
//! `trace.svg` (tip position against its reference, normal force, torques and
//! contact mode against time) and `trace.html` (the arm animated on the belt
//! beside the trace's plots, one self-contained page: [`figures::trace_page`]). A
//! run that stops part way (the firmware in its safe state or lost, a plant
//! failure, Ctrl-C) still writes every period up to then and exits with code 1. The trace is streamed to `trace.csv.partial` while
//! the run goes (flushed every millisecond of wall time) and renamed at the end,
//! so a plant killed outright (SIGKILL) still leaves its rows on disk.

use super::closed_loop::{draw, print_summary};
use crate::commands::Done;
use crate::streamed_run::{Streamed, TraceFiles, run_streamed};
use crate::{
    cli::{RunArgs, RunLink},
    error::CliError,
    link_spec::{LinkSpec, OpenLink},
    output::{OutputSet, progress_bar},
};
pub use experiments::run::prepare;
use rig::scenario::Scenario;
use rig::{
    ipc::{MonitorPolicy, check_rig_name, default_rig_name},
    summary::{MonitorSummary, RunSummary},
};

/// Runs `sil-host run`.
///
/// # Errors
/// Bad scenario or overrides (exit 2, nothing written); a run that stopped part
/// way (exit 1, everything up to then written); I/O or plotting failures.
pub fn execute(args: &RunArgs) -> Result<Done<(RunSummary, Scenario)>, CliError> {
    let (setup, chosen) = prepare(args)?;
    crate::features::require_format(args.format)?;
    if matches!(chosen, RunLink::Twin | RunLink::Emulator) {
        crate::features::require(
            cfg!(feature = "board"),
            "board",
            &format!("--link {}", if chosen == RunLink::Twin { "twin" } else { "emulator" }),
        )?;
    }
    let scenario = setup.scenario();
    if !matches!(chosen, RunLink::Twin | RunLink::Emulator) {
        crate::commands::warn(experiments::scenario::board_tables_note(scenario, chosen.without_board()));
    }
    let rig = match (&args.attach, &args.rig) {
        (Some(name), _) | (None, Some(name)) => name.clone(),
        (None, None) => default_rig_name(),
    };
    check_rig_name(&rig).map_err(CliError::bad_input)?;
    if !(args.monitor_timeout > 0.0 && args.monitor_timeout <= 600.0) {
        return Err(CliError::bad_input(format!("--monitor-timeout {}: expected seconds in (0, 600]", args.monitor_timeout)));
    }
    // Real time never waits for a monitor: the wall clock paces the periods.
    let monitors = MonitorPolicy {
        wait_for: usize::from(args.monitors),
        lossless: args.monitors > 0 && !args.realtime,
        timeout: std::time::Duration::from_secs_f64(args.monitor_timeout),
    };

    let spec = match chosen {
        RunLink::InProcess => LinkSpec::InProcess,
        RunLink::Twin => LinkSpec::Twin,
        #[cfg(feature = "board")]
        RunLink::Emulator => LinkSpec::Emulator { elf: args.elf.clone().unwrap_or_else(board_link::emulator_link::default_image) },
        #[cfg(not(feature = "board"))]
        RunLink::Emulator => LinkSpec::Emulator { elf: args.elf.clone().unwrap_or_default() },
        RunLink::Iceoryx2 => LinkSpec::Iceoryx2 { rig: rig.clone(), attach: args.attach.is_some(), realtime: args.realtime, monitors },
    };
    let mut open = spec.open(&setup)?;
    let link = open.link();
    let transport = link.transport();
    // Before anything is written: an address in use is refused with nothing written.
    let mut live = crate::live::LiveRun::start(&args.live, scenario, args.realtime)?;
    // Only once the firmware is there: a run that cannot start writes nothing.
    let mut out = OutputSet::new(&args.output.out)?;

    let n = scenario.timing.periods();
    let progress = progress_bar(n, "SIL run", "periods", args.output.json);
    let Streamed { stats, history, failure, wall_s, validity, ledger, page } =
        run_streamed(&setup, link, &mut out, &progress, 500, TraceFiles { format: args.format, page: !args.no_page }, live.as_mut())?;
    // The viewers are told while the outputs are written (docs/rig.md "Live").
    let closing = live.map(crate::live::LiveRun::close);
    let firmware_announcement = link.announcement().cloned();
    let (mut timings, mut realtime_setup, mut monitor_counts) = (None, None, None);
    match &mut open {
        OpenLink::Iceoryx2(l) => {
            timings = Some(std::mem::take(&mut l.timings));
            realtime_setup = l.realtime_setup.clone();
            monitor_counts = (monitors.wait_for > 0).then(|| l.monitor_counts());
        }
        #[cfg(feature = "board")]
        OpenLink::Twin(t) => {
            for (k, n) in &t.notices {
                eprintln!("twin: period {k}: {}", board_link::twin_link::describe(n));
            }
        }
        _ => {}
    }
    drop(open);

    let svg = out.stage_figure("trace.svg")?;
    draw(&svg, "SIL", scenario, &history, stats.last_t())?;
    if let Some(page) = page {
        out.write_bytes(figures::trace_page::FILE, page.html().as_bytes())?;
    }
    let summary = RunSummary {
        rig: (chosen == RunLink::Iceoryx2).then(|| rig.clone()),
        ipc_rtt_us: timings.as_ref().map(|t| t.rtt.percentiles()),
        firmware_step_us: timings.as_ref().map(|t| t.step.percentiles()),
        period_jitter_us: timings.as_ref().filter(|_| args.realtime).map(|t| t.jitter.percentiles()),
        late_answers: timings.as_ref().map_or(0, |t| t.late_answers),
        realtime_setup,
        monitors: monitor_counts.map(|c| MonitorSummary {
            waited_for: monitors.wait_for,
            lossless: monitors.lossless,
            timeout_s: args.monitor_timeout,
            given_up: c.given_up,
            samples_dropped: c.samples_dropped,
        }),
        firmware_announcement,
        ledger,
        ..RunSummary::from_stats(
            scenario,
            &stats,
            failure.as_ref(),
            transport,
            if args.realtime { "realtime" } else { "lockstep" },
            wall_s,
            validity,
        )
    };
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    if let Some(closing) = closing {
        closing.finish();
    }
    Ok(Done { result: (summary, scenario.clone()), files, failure: failure.map(CliError::from) }.strict(args.strict.strict, &validity))
}

/// Runs `sil-host run`: [`execute`], then prints the summary (human, or the
/// JSON document with `--json`).
///
/// # Errors
/// As [`execute`]; a run that stopped part way (exit 1, everything up to then written).
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    crate::commands::finish(
        execute(args)?,
        args.output.json,
        |(summary, _)| summary,
        |(summary, scenario), files| print_summary(summary, scenario, files),
    )
}
