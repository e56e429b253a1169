//! `sil-host pil`: a processor-in-the-loop run. The MCU image runs in QEMU, or
//! on a board at the end of a serial port (hardware in the loop, `--serial`),
//! and closes the loop with the plant over its USART1 ([`rig::pil_link`]);
//! the plant, the scenario and the outputs are those of `sil-host run`, plus the
//! image's counts per step (instructions under QEMU, cycles on silicon) and, under
//! QEMU, its defmt log.
//!
//! Writes `trace.csv` (`trace.arrow` with `--format arrow`, `trace.mcap` with `--format mcap`), `summary.json` (with a `pil` object: counts per step and
//! per frame, median, p99 and worst, against the budget, in `count_unit`),
//! `trace.svg`, `instructions.svg` (the counts of each step against time, with the
//! budget) and, under QEMU, `defmt.log`.

use std::{io::Write, path::PathBuf};

use super::closed_loop::{draw, print_summary};
use crate::commands::Done;
use crate::streamed_run::{Streamed, TraceFiles, run_streamed};
use crate::{
    cli::PilArgs,
    error::CliError,
    link_spec::{LinkSpec, OpenLink},
    output::{OutputSet, progress_bar},
};
use experiments::scenario::load_scenario;
use figures::plot::{self, Panel, Series, colors};
use rig::{
    FirmwareLink,
    pil_link::{self, BAUD_RANGE, ICOUNT_SHIFT, LogLine, PilCounts, PilOptions, PilTarget},
    scenario::Scenario,
    summary::{CountUnit, Spread},
    summary::{PilFigures, RunSummary},
};

/// Checks the arguments that say where the image runs.
///
/// # Errors
/// [`CliError::BadInput`] (exit 2): a serial device that does not exist, a baud
/// rate outside [`BAUD_RANGE`], a missing image, or one that is not a 32-bit
/// little-endian ARM ELF.
fn target_of(args: &PilArgs) -> Result<PilTarget, CliError> {
    if let Some(path) = &args.serial {
        if !path.exists() {
            return Err(CliError::bad_input(format!(
                "--serial {}: no such device (is the USB-serial adapter plugged in? `ls /dev/ttyUSB* /dev/ttyACM*` lists them)",
                path.display()
            )));
        }
        if !BAUD_RANGE.contains(&args.baud) {
            return Err(CliError::bad_input(format!(
                "--baud {}: outside {}..={} baud (the reference board's USART1 runs at {})",
                args.baud,
                BAUD_RANGE.start(),
                BAUD_RANGE.end(),
                pil_link::DEFAULT_BAUD
            )));
        }
        // Not there at all; one that is not a regular file is refused as it is read.
        if let Some(elf) = args.image.as_ref().filter(|e| !e.exists()) {
            return Err(CliError::bad_input(format!(
                "--image {}: no such file (with --serial: the ELF flashed on the board)",
                elf.display()
            )));
        }
        return Ok(PilTarget::Serial { path: path.clone(), baud: args.baud, elf: args.image.clone() });
    }
    qemu_target(args.image.clone(), args.qemu.clone(), args.qemu_link.into())
}

/// The QEMU target of `image` (default: `cargo build-pil`'s output), checked:
/// `pil`'s and `replay --link pil`'s.
///
/// # Errors
/// [`CliError::BadInput`] (exit 2): no image there, or one that is not a
/// 32-bit little-endian ARM ELF.
pub(crate) fn qemu_target(image: Option<PathBuf>, qemu: PathBuf, link: pil_link::QemuLink) -> Result<PilTarget, CliError> {
    let image = image.unwrap_or_else(pil_link::default_image);
    // Not there at all; a FIFO, a device, a directory or a file over
    // `tables::input::ELF_IMAGE`'s bound is refused by `pil_link::check_image`, naming it.
    if !image.exists() {
        return Err(CliError::bad_input(format!(
            "no PIL image at {}: build it with `{}` (from the workspace root) or pass --image",
            image.display(),
            pil_link::BUILD_HINT
        )));
    }
    pil_link::check_image(&image).map_err(|e| match e {
        pil_link::ImageError::Input(e) => CliError::from(e),
        pil_link::ImageError::NotArm(why) => CliError::bad_input(format!(
            "--image {}: {why}; the PIL image is the `arm` firmware's ELF for the Cortex-M4: build it with `{}`",
            image.display(),
            pil_link::BUILD_HINT
        )),
    })?;
    Ok(PilTarget::Qemu { image, qemu, link })
}

/// Runs the PIL (or HIL) loop and writes its files; prints nothing.
///
/// # Errors
/// Bad scenario or overrides, a missing image or serial device, a bad baud rate,
/// a fault the target cannot inject (exit 2, nothing written); QEMU that cannot
/// start or boot, a board that does not answer, or a run that stopped part way
/// (exit 1, everything up to then written); I/O or plotting failures.
pub fn execute(args: &PilArgs) -> Result<Done<(RunSummary, Scenario)>, CliError> {
    experiments::scenario::refuse_board_overrides(&args.scenario.set, "the PIL board (its own firmware image)")?;
    crate::features::require_format(args.format)?;
    let scenario = load_scenario(&args.scenario)?;
    crate::commands::warn(experiments::scenario::board_tables_note(&scenario, "the PIL board (its own firmware image)"));
    let setup = experiments::run::setup(scenario)?;
    let scenario = setup.scenario();
    if !(args.answer_timeout.is_finite() && args.answer_timeout > 0.0 && args.answer_timeout <= 600.0) {
        return Err(CliError::bad_input(format!("--answer-timeout {}: in (0, 600] s", args.answer_timeout)));
    }
    let target = target_of(args)?;
    pil_link::check_faults(scenario, &target).map_err(|e| CliError::bad_input(e.to_string()))?;
    // Before anything is written: an address in use is refused with nothing written.
    let mut live = crate::live::LiveRun::start(&args.live, scenario, false)?;
    let mut out = OutputSet::new(&args.output.out)?;

    let n = scenario.timing.periods();
    let progress = progress_bar(n, "PIL run", "periods", args.output.json);
    let sink: Option<pil_link::LogSink> = (!args.quiet && !args.output.json).then(|| {
        let bar = progress.clone();
        Box::new(move |l: &LogLine| bar.println(format!("image: {}", l.display()))) as pil_link::LogSink
    });
    let opts = PilOptions { answer_timeout_s: args.answer_timeout, ..PilOptions::for_target(target.clone()) };
    let OpenLink::Pil(mut link) = (LinkSpec::Pil { options: opts, on_log: sink }).open(&setup)? else {
        unreachable!("a PIL spec opens a PIL link")
    };
    let Streamed { stats, history, failure, wall_s, validity, ledger, page } = run_streamed(
        &setup,
        link.as_mut(),
        &mut out,
        &progress,
        100,
        TraceFiles { format: args.format, page: !args.no_page },
        live.as_mut(),
    )?;
    // The viewers are told while the outputs are written (docs/rig.md "Live").
    let closing = live.map(crate::live::LiveRun::close);
    let log = link.captures_log().then(|| link.log());
    let exit = link.exit_status().map(|s| s.to_string());
    let figures = PilFigures::new(&target, &link.counts, scenario.timing.rate_hz, log.as_deref(), exit);
    let counts = std::mem::take(&mut link.counts);
    let transport = link.transport();
    drop(link);

    let svg = out.stage_figure("trace.svg")?;
    draw(&svg, if log.is_some() { "PIL" } else { "HIL" }, scenario, &history, stats.last_t())?;
    if let Some(page) = page {
        out.write_bytes(figures::trace_page::FILE, page.html().as_bytes())?;
    }
    let svg = out.stage_figure("instructions.svg")?;
    draw_counts(&svg, scenario, stats.last_t(), &counts, &target)?;
    if let Some(log) = &log {
        let text: String = log.iter().map(|l| l.display() + "\n").collect();
        out.write_bytes("defmt.log", text.as_bytes())?;
    }
    let summary = RunSummary {
        pil: Some(figures),
        ledger,
        ..RunSummary::from_stats(scenario, &stats, failure.as_ref(), transport, "lockstep", wall_s, validity)
    };
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    if let Some(closing) = closing {
        closing.finish();
    }
    Ok(Done { result: (summary, scenario.clone()), files, failure: failure.map(CliError::from) }.strict(args.strict.strict, &validity))
}

/// Runs `sil-host pil`: [`execute`], then prints the summary (human, or the
/// JSON document with `--json`).
///
/// # Errors
/// As [`execute`]; a run that stopped part way (exit 1, everything up to then written).
pub fn run(args: &PilArgs) -> Result<(), CliError> {
    crate::commands::finish(
        execute(args)?,
        args.output.json,
        |(summary, _)| summary,
        |(summary, scenario), files| {
            print_pil(summary);
            print_summary(summary, scenario, files);
        },
    )
}

/// What counted the ticks, for the human output and the figure.
fn clock_description(p: &PilFigures) -> String {
    match (p.count_unit, p.qemu_icount_shift) {
        (CountUnit::Instructions, Some(shift)) => format!("emulated SysTick, QEMU -icount shift={shift}"),
        (CountUnit::Instructions, None) => "emulated SysTick, an emulator behind the serial port".into(),
        (CountUnit::Cycles, _) => "DWT cycle counter on silicon".into(),
    }
}

fn print_pil(summary: &RunSummary) {
    let Some(p) = &summary.pil else { return };
    let mut o = crate::stdout::out();
    let unit = p.count_unit.as_str();
    let sp = |s: &Spread| format!("median {:.0}, p99 {:.0}, worst {:.0}", s.median, s.p99, s.worst);
    let link = match (&p.serial_port, p.baud, p.transport) {
        (Some(port), Some(baud), _) => format!("serial port {port} at {baud} baud"),
        (_, _, "qemu-semihosting") => "QEMU's semihosting, a frame per call through two host FIFOs".into(),
        _ => "QEMU's USART1 on a Unix socket".into(),
    };
    let _ = writeln!(o, "image link: {link}");
    let share_note = match p.count_unit {
        CountUnit::Instructions => ", if an instruction took one cycle",
        CountUnit::Cycles => "",
    };
    let _ = writeln!(
        o,
        "image {unit} per step ({}): {} (budget {:.0} {unit}: {}; worst = {:.1} % of the period at 168 MHz{share_note})",
        clock_description(p),
        sp(&p.step_counts),
        p.step_budget,
        if p.within_budget { "ok" } else { "EXCEEDED" },
        p.worst_step_period_share * 100.0
    );
    let _ = writeln!(o, "image {unit} per frame (decode + step): {}", sp(&p.frame_counts));
    match (p.defmt_lines, p.defmt_warnings) {
        (Some(lines), Some(warnings)) => {
            let _ = writeln!(
                o,
                "image log: {lines} defmt lines ({warnings} warnings or errors), QEMU {}",
                p.qemu_exit.as_deref().unwrap_or("still running at the end")
            );
        }
        _ => {
            let _ = writeln!(o, "image log: {}", p.defmt_log);
        }
    }
}

/// Draws `instructions.svg`: the image's counts per step and per frame against
/// time (their decimated series), with the budget, on a time axis ending at
/// `t_end` (s; the last record's, or 1 s).
fn draw_counts(path: &std::path::Path, s: &Scenario, t_end: Option<f64>, counts: &PilCounts, target: &PilTarget) -> Result<(), CliError> {
    let per_tick = counts.counts_per_tick();
    let unit = counts.unit().as_str();
    let budget = pil_link::step_budget(s.timing.rate_hz);
    let t_end = t_end.unwrap_or(1.0).max(1e-9);
    let series = |ticks: &rig::envelope::Envelope| -> Vec<(f64, f64)> {
        let pts: Vec<_> = ticks.points().into_iter().map(|(t, n)| (t, n * per_tick)).collect();
        plot::decimate(&pts, 4000)
    };
    let budget_label = format!("budget (5 % of {:.0} µs at 168 MHz)", 1e6 / s.timing.rate_hz);
    let y_label = format!("{unit} per step");
    let panels = [Panel {
        y_label: y_label.into(),
        series: vec![
            Series::line("frame (decode + step)", series(&counts.frame_series), colors::ORANGE),
            Series::line("step", series(&counts.step_series), colors::BLUE),
            Series::reference(&budget_label, vec![(0.0, budget), (t_end, budget)], colors::RED),
        ],
        y_range: Some((0.0, (counts.frame.max().unwrap_or(0) as f64 * per_tick).max(budget) * 1.15)),
        categories: None,
        between_samples: None,
    }];
    let source = match (counts.unit(), target) {
        (CountUnit::Instructions, PilTarget::Qemu { .. }) => format!("QEMU -icount shift={ICOUNT_SHIFT}"),
        (CountUnit::Instructions, PilTarget::Serial { path, .. }) => format!("emulated SysTick over {}", path.display()),
        (CountUnit::Cycles, PilTarget::Serial { path, .. }) => format!("DWT on the board at {}", path.display()),
        (CountUnit::Cycles, PilTarget::Qemu { .. }) => "DWT".into(),
    };
    let what = if matches!(target, PilTarget::Serial { .. }) { "HIL" } else { "PIL" };
    let title = format!("{what} run {}: {} image {unit} per control step ({source})", s.name, s.controller_name());
    plot::time_panels(path, &title, (0.0, t_end), &panels).map_err(CliError::from)
}
