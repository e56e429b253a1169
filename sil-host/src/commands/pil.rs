//! `sil-host pil`: a processor-in-the-loop run. The MCU image runs in QEMU and
//! closes the loop with the plant over the emulated USART
//! ([`crate::sil::pil_link`]); the plant, the scenario and the outputs are those
//! of `sil-host run`, plus the image's instruction counts per step and its defmt
//! log.
//!
//! Writes `trace.csv`, `summary.json` (with a `pil` object: instruction counts per
//! step, worst and median, against the budget), `trace.svg`, `instructions.svg`
//! (instructions of each step against time, with the budget) and `defmt.log`.

use std::io::Write;

use serde::Serialize;

use super::run::{RunSummary, draw, load_scenario, print_summary, run_streamed};
use crate::{
    cli::PilArgs,
    error::CliError,
    output::{OutputSet, progress_bar},
    plot::{self, Panel, Series, colors},
    sil::{
        pil_link::{self, ICOUNT_SHIFT, LogLine, PilCounts, PilLink, PilOptions, STEP_BUDGET_INSTRUCTIONS, Spread},
        record::PeriodRecord,
        scenario::Scenario,
        setup::{firmware_config, plant_for},
    },
};

/// The PIL part of `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct PilFigures {
    /// The image that ran.
    pub image: String,
    /// QEMU's `-icount` shift: one instruction per `2^shift` ns of virtual time.
    pub qemu_icount_shift: u32,
    /// The image's tick rate (SysTick at the core clock), Hz.
    pub ticks_per_second: u32,
    /// Instructions per tick under that shift (`1e9 / (ticks_per_second 2^shift)`).
    pub instructions_per_tick: f64,
    /// Instructions of `Firmware::step` (sensor decode to command encode): median,
    /// 99th percentile, worst.
    pub step_instructions: Spread,
    /// Instructions from a frame's last byte to its answer ready to send (COBS,
    /// CRC and postcard decoding plus the step).
    pub frame_instructions: Spread,
    /// The budget of a step, instructions (HARDWARE.md: 5 % of 1 ms at 168 MHz).
    pub step_budget_instructions: f64,
    /// Whether the worst step is within the budget.
    pub within_budget: bool,
    /// Worst step as a share of the control period at 168 MHz, if an
    /// instruction took one cycle (a lower bound on silicon: README "PIL").
    pub worst_step_period_share: f64,
    /// QEMU's exit status at the end (`exit status: 0` when the image ended the run).
    pub qemu_exit: Option<String>,
    /// Lines of the image's defmt log (written to `defmt.log`).
    pub defmt_lines: usize,
    /// Of which at `warn` or `error` level.
    pub defmt_warnings: usize,
}

impl PilFigures {
    /// The figures of a run's counts.
    pub fn new(image: &std::path::Path, counts: &PilCounts, rate_hz: f64, log: &[LogLine], exit: Option<String>) -> Self {
        let per_tick = counts.instructions_per_tick();
        let step = Spread::of(&counts.step_ticks, per_tick);
        Self {
            image: image.display().to_string(),
            qemu_icount_shift: ICOUNT_SHIFT,
            ticks_per_second: counts.ticks_per_second,
            instructions_per_tick: per_tick,
            step_instructions: step,
            frame_instructions: Spread::of(&counts.frame_ticks, per_tick),
            step_budget_instructions: STEP_BUDGET_INSTRUCTIONS,
            within_budget: step.worst <= STEP_BUDGET_INSTRUCTIONS,
            worst_step_period_share: step.worst / (168e6 / rate_hz),
            qemu_exit: exit,
            defmt_lines: log.len(),
            defmt_warnings: log.iter().filter(|l| l.level == "warn" || l.level == "error").count(),
        }
    }
}

/// Runs `sil-host pil`.
///
/// # Errors
/// Bad scenario, overrides or a missing image (exit 2, nothing written); QEMU
/// that cannot start or boot, or a run that stopped part way (exit 1, everything
/// up to then written); I/O or plotting failures.
pub fn run(args: &PilArgs) -> Result<(), CliError> {
    let scenario = load_scenario(&args.scenario)?;
    plant_for(&scenario).map_err(CliError::Sim)?;
    firmware::Firmware::new(firmware_config(&scenario)).map_err(|e| CliError::BadInput(format!("firmware configuration: {e}")))?;
    if scenario.faults.iter().any(|f| f.kind == crate::sil::faults::FaultKind::Stall) {
        return Err(CliError::BadInput("the scenario's stall fault acts on a host process: not available in PIL".into()));
    }
    if !(args.answer_timeout.is_finite() && args.answer_timeout > 0.0 && args.answer_timeout <= 600.0) {
        return Err(CliError::BadInput(format!("--answer-timeout {}: in (0, 600] s", args.answer_timeout)));
    }
    let image = args.image.clone().unwrap_or_else(pil_link::default_image);
    if !image.is_file() {
        return Err(CliError::BadInput(format!(
            "no PIL image at {}: build it with `{}` (from the workspace root) or pass --image",
            image.display(),
            pil_link::BUILD_HINT
        )));
    }
    let mut out = OutputSet::new(&args.output.out)?;

    let n = (scenario.timing.duration_s * scenario.timing.rate_hz).round() as u64;
    let progress = progress_bar(n, "PIL run", "periods", args.output.json);
    let sink: Option<pil_link::LogSink> = (!args.quiet && !args.output.json).then(|| {
        let bar = progress.clone();
        Box::new(move |l: &LogLine| bar.println(format!("[image {}] {}", l.level, l.message))) as pil_link::LogSink
    });
    let opts =
        PilOptions { image: image.clone(), qemu: args.qemu.clone(), answer_timeout_s: args.answer_timeout, ..PilOptions::new(&image) };
    let mut link = PilLink::start(&scenario, &opts, sink).map_err(CliError::Run)?;
    let (records, failure, wall_s) = run_streamed(&scenario, &mut link, &mut out, &progress, 100)?;
    let log = link.log();
    let exit = link.exit_status().map(|s| s.to_string());
    let figures = PilFigures::new(&image, &link.counts, scenario.timing.rate_hz, &log, exit);
    let counts = link.counts.clone();
    drop(link);

    let svg = out.stage("trace.svg");
    draw(&svg, "PIL", &scenario, &records)?;
    let svg = out.stage("instructions.svg");
    draw_instructions(&svg, &scenario, &records, &counts)?;
    let text: String = log.iter().map(|l| format!("[{}] {}\n", l.level, l.message)).collect();
    out.write_bytes("defmt.log", text.as_bytes())?;
    let summary = RunSummary {
        pil: Some(figures),
        ..RunSummary::from_records(&scenario, &records, failure.as_ref(), "pil-qemu", "lockstep", wall_s)
    };
    let json = out.write_json("summary.json", &summary)?;
    let written = out.commit()?;
    if args.output.json {
        println!("{json}");
    } else {
        print_pil(&summary);
        print_summary(&summary, &scenario, &written);
    }
    match failure {
        Some(e) => Err(CliError::Run(e)),
        None => Ok(()),
    }
}

fn print_pil(summary: &RunSummary) {
    let Some(p) = &summary.pil else { return };
    let mut o = std::io::stdout().lock();
    let sp = |s: &Spread| format!("median {:.0}, p99 {:.0}, worst {:.0}", s.median, s.p99, s.worst);
    let _ = writeln!(
        o,
        "image instructions per step (-icount shift={}): {} (budget {:.0}: {}; worst = {:.1} % of the period at 168 MHz)",
        p.qemu_icount_shift,
        sp(&p.step_instructions),
        p.step_budget_instructions,
        if p.within_budget { "ok" } else { "EXCEEDED" },
        p.worst_step_period_share * 100.0
    );
    let _ = writeln!(o, "image instructions per frame (decode + step): {}", sp(&p.frame_instructions));
    let _ = writeln!(
        o,
        "image log: {} defmt lines ({} warnings or errors), QEMU {}",
        p.defmt_lines,
        p.defmt_warnings,
        p.qemu_exit.as_deref().unwrap_or("still running at the end")
    );
}

fn draw_instructions(path: &std::path::Path, s: &Scenario, records: &[PeriodRecord], counts: &PilCounts) -> Result<(), CliError> {
    let per_tick = counts.instructions_per_tick();
    let t_end = records.last().map_or(1.0, |r| r.t).max(1e-9);
    let series = |ticks: &[u32]| -> Vec<(f64, f64)> {
        let pts: Vec<_> = records.iter().zip(ticks).map(|(r, &n)| (r.t, n as f64 * per_tick)).collect();
        plot::decimate(&pts, 4000)
    };
    let panels = [Panel {
        y_label: "instructions",
        series: vec![
            Series { label: "frame (decode + step)", points: series(&counts.frame_ticks), color: colors::ORANGE, step: false },
            Series { label: "step", points: series(&counts.step_ticks), color: colors::BLUE, step: false },
            Series {
                label: "budget (5 % of 1 ms at 168 MHz)",
                points: vec![(0.0, STEP_BUDGET_INSTRUCTIONS), (t_end, STEP_BUDGET_INSTRUCTIONS)],
                color: colors::RED,
                step: false,
            },
        ],
        y_range: Some((
            0.0,
            (counts.frame_ticks.iter().copied().max().unwrap_or(0) as f64 * per_tick).max(STEP_BUDGET_INSTRUCTIONS) * 1.15,
        )),
    }];
    let title =
        format!("PIL run {}: {} image instructions per control step (QEMU -icount shift={ICOUNT_SHIFT})", s.name, s.controller.kind);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
