//! The tables of the closed-loop sections: runs side by side, the rig's speed, the MCU image's step counts.

use super::format::{cell, error_mm, given, position, rough};
use crate::bench::figure::{Figure, Goal, Status};
use rig::summary::{PilFigures, RunSummary};
use std::fmt::Write as _;

pub(crate) fn bench(md: &mut String, figures: &[Figure]) {
    let _ = writeln!(md, "| figure | value | target | status | details |\n|---|---|---|---|---|");
    for f in figures {
        let goal = match f.goal {
            Goal::AtMost => "<=",
            Goal::AtLeast => ">=",
        };
        let value = f.value.map_or_else(|| "-".into(), |v| format!("{} {}", rough(v), f.unit));
        let status = match &f.status {
            Status::Met => "met".to_string(),
            Status::NotMet => "**not met**".into(),
            Status::Skipped(why) => format!("skipped: {}", cell(why)),
        };
        let _ =
            writeln!(md, "| {} | {value} | {goal} {} {} | {status} | {} |", f.name, given(f.target), f.unit, cell(&f.detail.join("; ")));
    }
    md.push('\n');
}

pub(crate) fn pil(md: &mut String, p: &PilFigures) {
    let unit = p.count_unit.as_str();
    let _ = writeln!(md, "| {unit} per | median | p99 | worst | budget |\n|---|---|---|---|---|");
    for (what, s) in [("control step", &p.step_counts), ("frame (decode + step)", &p.frame_counts)] {
        let _ = writeln!(md, "| {what} | {} | {} | {} | {} |", s.median.round(), s.p99.round(), s.worst.round(), given(p.step_budget));
    }
    let _ = writeln!(
        md,
        "\nWorst step: {} % of the control period at 168 MHz; within the budget: {}.\n",
        rough(100.0 * p.worst_step_period_share),
        p.within_budget
    );
}

/// Closed-loop runs side by side.
pub(crate) fn run_comparison(md: &mut String, runs: &[(&str, &RunSummary)]) {
    let _ = write!(md, "| quantity |");
    for (id, _) in runs {
        let _ = write!(md, " {id} |");
    }
    let _ = writeln!(md, "\n|---|{}", "---|".repeat(runs.len()));
    type Row = (&'static str, fn(&RunSummary) -> String);
    let rows: [Row; 14] = [
        ("status", |s| s.status.to_string()),
        ("controller", |s| s.controller.to_string()),
        ("transport, timing", |s| format!("{}, {}", s.transport, s.timing)),
        ("periods", |s| s.periods.to_string()),
        ("lift-offs", |s| s.lift_off.lift_offs.to_string()),
        ("detected", |s| s.lift_off.lift_offs_detected.to_string()),
        ("missed", |s| s.lift_off.missed_lift_offs.to_string()),
        ("false alarms", |s| s.lift_off.false_alarms.to_string()),
        ("deadline misses", |s| s.deadline_misses.to_string()),
        ("firmware overruns", |s| s.firmware_overruns.to_string()),
        ("rms tracking error (mm)", |s| error_mm(s.rms_tracking_error_m)),
        ("final z_t (m)", |s| position(s.final_z_t_m)),
        ("stopped because", |s| s.error.clone().unwrap_or_else(|| "-".into())),
        ("model violations", |s| if s.validity.is_valid() { "none".into() } else { s.validity.describe_violations() }),
    ];
    for (name, f) in rows {
        let _ = write!(md, "| {name} |");
        for (_, s) in runs {
            let _ = write!(md, " {} |", cell(&f(s)));
        }
        md.push('\n');
    }
    md.push('\n');
}
