//! What `sil-host run` and `sil-host pil` share: the scenario from the command
//! line, the run's human summary and its figure (the streamed run itself is
//! [`crate::streamed_run`]).

use std::{io::Write, path::PathBuf};

use crate::error::CliError;
use figures::plot;
use rig::{scenario::Scenario, summary::Percentiles, summary::RunSummary};

pub(crate) fn print_summary(summary: &RunSummary, scenario: &Scenario, written: &[PathBuf]) {
    let mut o = crate::stdout::out();
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
    let _ = writeln!(o, "energy ledger: {}", summary.ledger);
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
        "{what} run {} (cf. paper Figs. 6 to 8): {} from x0{}, {} = {} m",
        s.name,
        s.controller_name(),
        s.plant.x0,
        plot::symbols::Z_T_REF,
        s.controller.target_z_t
    );
    plot::time_panels(path, &title, (0.0, t_end), &panels).map_err(CliError::from)
}
