//! The report's page: the index of the experiments, the paper side by side, one
//! section per experiment of the reproduction, then the appendix (the rig and the
//! firmware). Each result is drawn from its typed value (the analysis result or
//! the command's summary), every number by the rule of its kind
//! ([`super::format`]), every figure numbered with its caption ([`super::captions`]).

use std::{fmt::Write as _, path::Path};

use rig::summary::RunSummary;

use crate::commands::sweep::outputs::SweepSummary;

use super::{
    captions::{Figures, caption, order},
    closed_loop,
    experiments::{admissible, modes, poincare, sensitivity, simulate, sweep, zmax},
    runs::{bench, pil, run_comparison},
};
use super::{
    format::{cell, rough},
    outcome::{Outcome, StepResult},
    sections::Section,
    stamp::Stamp,
};

/// Which page: report.md in the report's folder, or the results page
/// (docs/results.md) that ships its figures in `figures/` beside it.
#[derive(Debug, Clone, Copy)]
pub struct Page<'a> {
    /// The report's folder as the commands on the page name it (`OUT` on the results page).
    pub out: &'a Path,
    /// Before each figure's path in the report's folder (`""` on report.md, `figures/`).
    pub figure_prefix: &'a str,
    /// Whether the page links the data files (CSV, JSON), which only the report's folder holds.
    pub data: bool,
}

/// The page and the figures it shows (paths in the report's folder, in order).
pub fn render(
    sections: &[Section],
    results: &[Vec<StepResult>],
    options: &str,
    wall_s: f64,
    stamp: &Stamp,
    page: Page,
) -> (String, Vec<String>) {
    let mut md = String::new();
    let mut figures = if page.data { Figures::new(page.figure_prefix).with_pdf() } else { Figures::new(page.figure_prefix) };
    let _ = writeln!(md, "# Reproduction of Marchese, Coraggio, Hogan, di Bernardo (ECC 2019)\n");
    let where_ = if page.data {
        "its files are in the folder of the same name".to_string()
    } else {
        format!(
            "its figures are in `{}<id>/` beside this page, each figure's PDF and its data files in the report's folder (`{}` in the commands)",
            page.figure_prefix,
            page.out.display()
        )
    };
    let _ = writeln!(
        md,
        "Every experiment of docs/model.md from our own simulation (`sil-host report {options}`, {} s of wall time), \
         made {}. Each section gives the command that made it (`<id>` in the first column below); {where_}. \
         Figures are numbered in the page's order, each with a caption below it: what it shows, its parameters, and \
         the paper's counterpart. Numbers print to their resolution (docs/analyses.md \"The report's numbers\").\n",
        rough(wall_s),
        stamp.line()
    );
    let (main, appendix): (Vec<_>, Vec<_>) = sections.iter().zip(results).partition(|(s, _)| !s.appendix);
    index(&mut md, &main);
    if !appendix.is_empty() {
        let _ = writeln!(md, "\nIn the appendix (the rig and the firmware, not results of the paper):\n");
        index(&mut md, &appendix);
    }
    super::paper::side_by_side(&mut md, results);
    for (s, rs) in &main {
        section(&mut md, s, rs, page, &mut figures, 2);
    }
    against_siconos(&mut md);
    against_mujoco(&mut md);
    if !appendix.is_empty() {
        let _ = writeln!(
            md,
            "\n## Appendix: the rig and the firmware\n\n\
             Engineering figures of the rig itself, not results of the paper: how fast the loop runs, and what the \
             firmware costs on the MCU.\n"
        );
        for (s, rs) in &appendix {
            section(&mut md, s, rs, page, &mut figures, 3);
        }
    }
    let shown = figures.shown().to_vec();
    (md, shown)
}

/// The comparison with Siconos as `tests/siconos/check.py --record` last wrote it
/// (issue 67): a measurement of this repository's code, compiled in, since the
/// check needs Debian's `python3-siconos` that a report's machine may lack.
const SICONOS_RECORD: &str = include_str!("../../../../tests/siconos/results.md");

/// The section "Against Siconos": [`SICONOS_RECORD`] under its heading.
fn against_siconos(md: &mut String) {
    let _ = writeln!(
        md,
        "\n## Against Siconos\n\n*issue 67: sil-host against an independent implementation, Siconos 4.4 \
         (tests/siconos/check.py, run by the test suite on every landing; this record is the one its `--record` \
         last wrote, at the commit it names)*\n"
    );
    md.push_str(SICONOS_RECORD);
}

/// The comparison with MuJoCo as `examples/compare/compare.py --record` last wrote it
/// (issue 69, "Why not MuJoCo?"): compiled in, as [`SICONOS_RECORD`] is, since the example
/// needs PyPI's `mujoco` that a report's machine may lack.
const MUJOCO_RECORD: &str = include_str!("../../../../examples/compare/results.md");

/// The section "Against MuJoCo": why a soft contact cannot answer the paper's question, then
/// [`MUJOCO_RECORD`].
fn against_mujoco(md: &mut String) {
    let _ = writeln!(
        md,
        "\n## Against MuJoCo\n\n*issues 69 and 82: the same arm in MuJoCo's soft contact beside sil-host, over the \
         contact settings a MuJoCo user would try (examples/compare/compare.py, run by the Python tests in its quick \
         size; this record is the one its `--record` last wrote, at the commit it names)*\n\n\
         A compliant contact always has a solution, so MuJoCo has no Painlevé paradox, no rule for the impact \
         without collision and no restitution coefficient: what follows the paradox is whatever the contact's \
         settings make of it. Tuned, it reproduces much of the rigid model: the elliptic cone with `solref 0.002 \
         0.456` or `0.001 0.456` (a time constant of 10 to 20 steps, the damping ratio of a spring that rebounds \
         with `e_n = 0.2`), Euler at `h = 1e-4` s, gives the rigid model's outcome (slides or bounces) in 22 and 23 \
         of 25 cells and its bounce within the bounds in 2 and 3 of 6, more than any other setting; MuJoCo's \
         default contact never bounces, the stiffest (`solref 2h`) bounces everywhere, the pyramidal cone slides at \
         `mu = 0.4`. Where the rigid model's bounce hinges on `e_n` (the locked bounce at `v_belt = -0.4` m/s, the \
         irregular one at `-0.7` m/s), MuJoCo's effective restitution (0.20 to 0.28, rising with the impact speed) \
         lands on another bounce, and `h = 1e-5` s does not close the gap. One case costs 16 times sil-host's wall \
         time. examples/compare/README.md says why at length.\n"
    );
    md.push_str(MUJOCO_RECORD);
}

/// The index table of `sections`: one row per step.
fn index(md: &mut String, sections: &[(&Section, &Vec<StepResult>)]) {
    let _ = writeln!(md, "| experiment (`<id>`) | source | status | model violations | wall time |\n|---|---|---|---|---|");
    for (s, rs) in sections {
        for r in rs.iter() {
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
            let _ = writeln!(md, "| {} (`{}`) | {} | {} | {} | {} s |", s.title, r.id, cell(&source), status, violations, rough(r.wall_s));
        }
    }
}

/// One section: its heading at `level`, its tables, its commands, its figures.
fn section(md: &mut String, s: &Section, rs: &[StepResult], page: Page, figures: &mut Figures, level: usize) {
    let h = "#".repeat(level);
    let _ = writeln!(md, "\n{h} {}\n\n*{}*\n", s.title, s.source);
    let runs: Vec<(&str, &RunSummary)> = rs
        .iter()
        .filter_map(|r| match &r.outcome {
            Some(Outcome::Run(summary)) => Some((r.id, summary.as_ref())),
            _ => None,
        })
        .collect();
    if runs.len() > 1 {
        run_comparison(md, &runs);
    }
    let sweeps: Vec<(&str, &SweepSummary, &[String])> = rs
        .iter()
        .filter_map(|r| match &r.outcome {
            Some(Outcome::Sweep(s)) => Some((r.id, s.as_ref(), r.files.as_slice())),
            _ => None,
        })
        .collect();
    if sweeps.len() > 1 {
        closed_loop::compare(md, &sweeps, figures);
    }
    for r in rs {
        if rs.len() > 1 {
            let _ = writeln!(md, "\n{h}# {}\n", r.id);
        }
        let command = s.steps.iter().find(|st| st.id == r.id).map_or_else(|| r.command.clone(), |st| super::command_line(page.out, st));
        let _ = writeln!(md, "```\n{command}\n```\n");
        if let Some(e) = &r.error {
            let _ = writeln!(md, "**Failed**:\n\n```\n{e}\n```\n");
        }
        match &r.outcome {
            Some(Outcome::Modes(m)) => modes(md, m),
            Some(Outcome::Admissible(a)) => admissible(md, a),
            Some(Outcome::Simulate(s)) => simulate(md, s),
            Some(Outcome::Sweep(s)) => sweep(md, s),
            Some(Outcome::Poincare(p)) => poincare(md, p),
            Some(Outcome::Zmax(z)) => zmax(md, z),
            Some(Outcome::Run(summary)) if runs.len() <= 1 => {
                run_comparison(md, &[(r.id, summary.as_ref())]);
                if let Some(p) = &summary.pil {
                    pil(md, p);
                }
            }
            Some(Outcome::Bench(b)) => bench(md, b),
            Some(Outcome::Sensitivity(s)) => sensitivity(md, &s.study),
            _ => {}
        }
        for f in order(r.outcome.as_ref(), &r.files).into_iter().filter(|f| !(sweeps.len() > 1 && closed_loop::is_map(f))) {
            figures.show(md, f, &caption(r.outcome.as_ref(), f));
        }
        // Data files: not the figures (SVG, the PDF beside an SVG, the animations' GIF).
        let data: Vec<String> = r
            .files
            .iter()
            .filter(|f| !f.ends_with(".svg") && !f.ends_with(".pdf") && !f.ends_with(".gif"))
            .map(|f| format!("[{f}]({f})"))
            .collect();
        if page.data && !data.is_empty() {
            let _ = writeln!(md, "Data: {}\n", data.join(", "));
        }
    }
}
