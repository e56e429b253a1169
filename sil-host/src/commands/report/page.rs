//! The report's page: one section per experiment, each result drawn from its
//! typed value (the analysis result or the command's summary), every number
//! through [`super::format::number`].

use std::fmt::Write as _;

use rig::summary::RunSummary;

use crate::commands::sweep::outputs::SweepSummary;

use super::{
    closed_loop,
    experiments::{admissible, modes, poincare, sensitivity, simulate, sweep, zmax},
    runs::{bench, pil, run_comparison},
};
use super::{
    format::{cell, number, short},
    outcome::{Outcome, StepResult},
    sections::Section,
    stamp::Stamp,
};

/// The page: a heading with the stamp, the index table, then each section with
/// its command lines, results, figures (when `figures`) and data links.
pub fn render(sections: &[Section], results: &[Vec<StepResult>], size: &str, wall_s: f64, stamp: &Stamp, figures: bool) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Reproduction of Marchese, Coraggio, Hogan, di Bernardo (ECC 2019)\n");
    let _ = writeln!(
        md,
        "Every experiment of docs/model.md from our own simulation (`sil-host report --size {size}`, {} s of wall time), \
         made {}. Each section gives the command that made it; its files are in the folder of the same name.\n",
        number(wall_s.round()),
        stamp.line()
    );
    let _ = writeln!(md, "| experiment | source | status | model violations | wall time |\n|---|---|---|---|---|");
    for (s, rs) in sections.iter().zip(results) {
        for r in rs {
            let status = if r.error.is_none() { "ok".to_string() } else { "**failed**".to_string() };
            let violations = match r.outcome.as_ref().and_then(Outcome::validity) {
                None => "-".to_string(),
                Some(v) if v.is_valid() => "none".to_string(),
                Some(v) => format!("**{}**", v.describe_violations()),
            };
            // The section's source, and what this run is where the section's runs differ.
            let source = match s.steps.iter().find(|st| st.id == r.id).and_then(|st| st.what) {
                Some(what) => format!("{}; this run: {what}", s.source),
                None => s.source.to_string(),
            };
            let _ = writeln!(md, "| {} ({}) | {} | {} | {} | {} s |", s.title, r.id, cell(&source), status, violations, short(r.wall_s));
        }
    }
    super::paper::side_by_side(&mut md, results);
    for (s, rs) in sections.iter().zip(results) {
        let _ = writeln!(md, "\n## {}\n\n*{}*\n", s.title, s.source);
        let runs: Vec<(&str, &RunSummary)> = rs
            .iter()
            .filter_map(|r| match &r.outcome {
                Some(Outcome::Run(summary)) => Some((r.id, summary.as_ref())),
                _ => None,
            })
            .collect();
        if runs.len() > 1 {
            run_comparison(&mut md, &runs);
        }
        let sweeps: Vec<(&str, &SweepSummary, &[String])> = rs
            .iter()
            .filter_map(|r| match &r.outcome {
                Some(Outcome::Sweep(s)) => Some((r.id, s.as_ref(), r.files.as_slice())),
                _ => None,
            })
            .collect();
        if sweeps.len() > 1 {
            closed_loop::compare(&mut md, &sweeps, figures);
        }
        for r in rs {
            if rs.len() > 1 {
                let _ = writeln!(md, "\n### {}\n", r.id);
            }
            let _ = writeln!(md, "```\n{}\n```\n", r.command);
            if let Some(e) = &r.error {
                let _ = writeln!(md, "**Failed**:\n\n```\n{e}\n```\n");
            }
            match &r.outcome {
                Some(Outcome::Modes(m)) => modes(&mut md, m),
                Some(Outcome::Admissible(a)) => admissible(&mut md, a),
                Some(Outcome::Simulate(s)) => simulate(&mut md, s),
                Some(Outcome::Sweep(s)) => sweep(&mut md, s),
                Some(Outcome::Poincare(p)) => poincare(&mut md, p),
                Some(Outcome::Zmax(z)) => zmax(&mut md, z),
                Some(Outcome::Run(summary)) if runs.len() <= 1 => {
                    run_comparison(&mut md, &[(r.id, summary.as_ref())]);
                    if let Some(p) = &summary.pil {
                        pil(&mut md, p);
                    }
                }
                Some(Outcome::Bench(b)) => bench(&mut md, b),
                Some(Outcome::Sensitivity(s)) => sensitivity(&mut md, &s.study),
                _ => {}
            }
            if figures {
                for f in r.files.iter().filter(|f| f.ends_with(".svg") && !(sweeps.len() > 1 && closed_loop::is_map(f))) {
                    let _ = writeln!(md, "![{f}]({f})\n");
                }
            }
            let data: Vec<String> = r.files.iter().filter(|f| !f.ends_with(".svg")).map(|f| format!("[{f}]({f})")).collect();
            if figures && !data.is_empty() {
                let _ = writeln!(md, "Data: {}\n", data.join(", "));
            }
        }
    }
    md
}
