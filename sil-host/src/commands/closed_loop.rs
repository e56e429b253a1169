//! What `sil-host run` and `sil-host pil` share: the scenario from the command
//! line, the streamed closed-loop run, its human summary and its figure.

use std::{
    io::Write,
    path::PathBuf,
    sync::atomic::{AtomicBool, Ordering},
    time::Instant,
};

use crate::{
    cli::ScenarioArgs,
    error::CliError,
    fastcsv::CsvRow,
    output::{OutputSet, StreamedCsv},
    plot,
};
use plant::Validity;
use rig::{
    FirmwareLink, RunObserver,
    overrides::{self, Override},
    record::{PeriodRecord, RunError},
    scenario::Scenario,
    stats::RunStats,
    stream_loop,
    summary::Percentiles,
    summary::RunSummary,
};

/// Reads a scenario (`path`; `-` is standard input; `None`: the embedded
/// default) with the `--set` overrides applied to its TOML document.
///
/// # Errors
/// [`CliError::BadInput`] (an unreadable file) or [`CliError::Scenario`] naming
/// the key (exit 2).
pub fn read_scenario(path: Option<&std::path::Path>, set: &[Override]) -> Result<Scenario, CliError> {
    let text = match path {
        Some(path) if path.as_os_str() == "-" => std::io::read_to_string(std::io::stdin())
            .map_err(|e| CliError::BadInput(format!("cannot read the scenario from stdin: {e}")))?,
        Some(path) => {
            std::fs::read_to_string(path).map_err(|e| CliError::BadInput(format!("cannot read scenario {}: {e}", path.display())))?
        }
        None => return Ok(Scenario::from_toml_with(rig::scenario::DEFAULT_TOML, set)?),
    };
    Ok(Scenario::from_toml_with(&text, set)?)
}

/// Loads the scenario, applies the `--set` overrides, then the flags. A key set
/// both by a flag and by `--set` is refused (exit 2): a key is set in one place.
///
/// # Errors
/// [`CliError::BadInput`] or [`CliError::Scenario`] (exit 2).
pub fn load_scenario(args: &ScenarioArgs) -> Result<Scenario, CliError> {
    let flags = [
        ("controller.kind", "--controller", args.controller.is_some()),
        ("plant.x0", "--x0", args.x0.is_some()),
        ("controller.target_z_t", "--target-zt", args.target_zt.is_some()),
        ("timing.duration_s", "--duration", args.duration.is_some()),
        ("sensors.seed", "--seed", args.seed.is_some()),
        ("plant.iwc", "--iwc", args.iwc.is_some()),
    ];
    let given: Vec<(&str, &str)> = flags.iter().filter(|f| f.2).map(|f| (f.0, f.1)).collect();
    overrides::check_keys(&args.set, &given).map_err(rig::scenario::ScenarioError::from)?;
    let mut s = read_scenario(args.scenario.as_deref(), &args.set)?;
    if let Some(c) = args.controller {
        s.controller.kind = c;
    }
    if let Some(x0) = args.x0 {
        s.plant.x0 = x0;
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
    if let Some(iwc) = args.iwc {
        s.plant.iwc = iwc;
    }
    s.validate()?;
    Ok(s)
}

// `trace.csv` of `run` and `pil`: [`PeriodRecord`]'s fields in order (the header
// the `csv` crate derived from them); the test below checks the bytes against it.
crate::csv_row!(PeriodRecord {
    t: f64,
    theta1: f64,
    theta1_dot: f64,
    theta2: f64,
    theta2_dot: f64,
    z_t: f64,
    z_n: f64,
    z_t_ref: f64,
    f_t: f64,
    f_n: f64,
    mode: str,
    u1_cmd: f64,
    u2_cmd: f64,
    u1_applied: f64,
    u2_applied: f64,
    lift_off_true: bool,
    lift_off_detected: bool,
    deadline_miss: bool,
    firmware_deadline_miss: bool,
    overruns: int,
    status: int,
});

/// Runs `scenario` over `link` as `run` and `pil` do, keeping nothing that grows
/// with the run: every period's row goes to `trace.csv` of `out` as it is made
/// (`trace.csv.partial`, flushed every 1 ms of wall time, so a plant killed
/// outright keeps every period up to the last flush), the summary's figures are
/// accumulated ([`RunStats`]) and the figure's curves decimated
/// ([`plot::HistoryEnvelope`]); the progress bar moves every `every` periods,
/// Ctrl-C or SIGTERM stops the run. Returns those, why the run stopped early if
/// it did, the loop's wall-clock time (s) and the plant's validity counters; the
/// progress bar is cleared.
///
/// # Errors
/// I/O errors of the trace file.
pub(crate) fn run_streamed(
    scenario: &Scenario,
    link: &mut dyn FirmwareLink,
    out: &mut OutputSet,
    progress: &indicatif::ProgressBar,
    every: usize,
) -> Result<Streamed, CliError> {
    let stop = crate::cancel::stop_flag();
    let mut trace = StreamedCsv::new(out, "trace.csv", <PeriodRecord as CsvRow>::HEADER, std::time::Duration::from_millis(1))?;
    let started = Instant::now();
    /// Streams each record, summarises it, keeps a decimated copy, moves the
    /// bar, stops on Ctrl-C, keeps the validity.
    struct Streaming<'a> {
        trace: &'a mut StreamedCsv,
        progress: &'a indicatif::ProgressBar,
        every: usize,
        stop: &'a AtomicBool,
        stats: RunStats,
        history: plot::HistoryEnvelope,
        validity: Validity,
    }
    impl RunObserver for Streaming<'_> {
        fn on_finished(&mut self, validity: &Validity) {
            self.validity = *validity;
        }

        fn on_record(&mut self, r: &PeriodRecord) {
            self.trace.push(r);
            self.stats.push(r);
            self.history.push(&plot::HistorySample {
                t: r.t,
                z_t: r.z_t,
                z_t_ref: r.z_t_ref,
                f_n: r.f_n,
                u: [r.u1_cmd, r.u2_cmd],
                mode: r.mode,
            });
        }

        fn on_period(&mut self, k: usize, _n: usize) -> bool {
            if k.is_multiple_of(self.every) {
                self.progress.set_position(k as u64);
            }
            !self.stop.load(Ordering::Relaxed)
        }
    }
    let mut observer = Streaming {
        trace: &mut trace,
        progress,
        every,
        stop: &stop,
        stats: RunStats::default(),
        history: plot::HistoryEnvelope::default(),
        validity: Validity::default(),
    };
    let (_, failure) = stream_loop(scenario, link, &mut observer);
    let Streaming { stats, history, validity, .. } = observer;
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();
    trace.finish()?;
    Ok(Streamed { stats, history, failure, wall_s, validity })
}

/// What [`run_streamed`] returns: nothing in it grows with the run's length.
pub(crate) struct Streamed {
    /// The summary's figures over every period, up to the failure if there was one.
    pub stats: RunStats,
    /// The figure's curves, decimated.
    pub history: plot::HistoryEnvelope,
    /// Why the run stopped early, if it did.
    pub failure: Option<RunError>,
    /// Wall-clock time of the loop, s.
    pub wall_s: f64,
    /// The plant's validity counters at the end.
    pub validity: Validity,
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
    let _ = writeln!(o, "validity: {}", summary.validity);
    if !summary.validity.is_valid() {
        let _ = writeln!(o, "INVALID: {} (the trajectory violates the model)", summary.validity.describe_violations());
    }
    if let Some(e) = &summary.error {
        let _ = writeln!(o, "STOPPED: {e}");
    }
    let _ = writeln!(o, "wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
}

/// Draws the closed-loop figure of a run (`trace.svg`) from its decimated
/// `history`, on a time axis ending at `t_end` (s; the last record's, or 1 s).
pub(crate) fn draw(
    path: &std::path::Path,
    what: &str,
    s: &Scenario,
    history: &plot::HistoryEnvelope,
    t_end: Option<f64>,
) -> Result<(), CliError> {
    let t_end = t_end.unwrap_or(1.0).max(1e-9);
    let panels = history.panels(true);
    let title = format!("{what} run {}: {} from x0{}, z_t* = {} m", s.name, s.controller.kind, s.plant.x0, s.controller.target_z_t);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fastcsv::{push_header, push_row};
    use proptest::prelude::*;

    fn float() -> impl Strategy<Value = f64> {
        prop_oneof![any::<u64>().prop_map(f64::from_bits), -10.0..10.0f64, Just(0.0), Just(-0.0)]
    }

    proptest! {
        /// `trace.csv` of `run`/`pil`: the bytes of the old path (`csv::Writer::serialize`, header derived).
        #[test]
        fn period_records_match_the_csv_crate(
            f in proptest::array::uniform14(float()),
            b in proptest::array::uniform4(any::<bool>()),
            n in any::<(u32, u32)>(),
            m in 0..3usize,
        ) {
            let r = PeriodRecord {
                t: f[0], theta1: f[1], theta1_dot: f[2], theta2: f[3], theta2_dot: f[4], z_t: f[5], z_n: f[6], z_t_ref: f[7],
                f_t: f[8], f_n: f[9], mode: ["flight", "sliding", "sticking"][m], u1_cmd: f[10], u2_cmd: f[11],
                u1_applied: f[12], u2_applied: f[13], lift_off_true: b[0], lift_off_detected: b[1], deadline_miss: b[2],
                firmware_deadline_miss: b[3], overruns: n.0, status: n.1,
            };
            let mut w = csv::Writer::from_writer(Vec::new());
            w.serialize(r).unwrap();
            w.serialize(r).unwrap();
            let old = w.into_inner().unwrap();
            let mut new = Vec::new();
            push_header(&mut new, <PeriodRecord as CsvRow>::HEADER);
            push_row(&mut new, &r);
            push_row(&mut new, &r);
            prop_assert_eq!(String::from_utf8(old).unwrap(), String::from_utf8(new).unwrap());
        }
    }
}
