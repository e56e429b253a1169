//! What `sil-host run` and `sil-host pil` share: the scenario from the command
//! line, the run's human summary and its figure (the streamed run itself is
//! [`crate::streamed_run`]).

use std::{io::Write, path::PathBuf};

use crate::{cli::ScenarioArgs, error::CliError, plot};
use rig::{
    overrides::{self, Override},
    scenario::Scenario,
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
    let title = format!(
        "{what} run {} (cf. paper Figs. 6 to 8): {} from x0{}, z_t* = {} m",
        s.name, s.controller.kind, s.plant.x0, s.controller.target_z_t
    );
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
