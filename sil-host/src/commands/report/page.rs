//! The report's page: one section per experiment, each result drawn from its
//! typed value (the analysis result or the command's summary), every number
//! through [`super::format::number`].

use std::fmt::Write as _;

use analyses::{admissible::AdmissibleReport, modes::ModeMap};
use rig::summary::{PilFigures, RunSummary};
use shared::{ElbowBranch, SlipDirection};

use super::{
    Outcome, StepResult,
    format::{cell, mm, number, opt, short},
    sections::Section,
    stamp::Stamp,
};
use crate::commands::{
    admissible::summary::fmt_intervals, bench::TransportFigures, poincare::summary::Summary as PoincareSummary,
    simulate::summary::Summary as SimulateSummary, sweep::outputs::SweepSummary, zmax::summary::ZmaxSummary,
};

/// Rows shown of a long table (the files hold the rest).
const MAX_ROWS: usize = 60;

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
    let _ = writeln!(md, "| experiment | source | status | wall time |\n|---|---|---|---|");
    for (s, rs) in sections.iter().zip(results) {
        for r in rs {
            let status = if r.error.is_none() { "ok".to_string() } else { "**failed**".to_string() };
            let _ = writeln!(md, "| {} ({}) | {} | {} | {} s |", s.title, r.id, cell(s.source), status, short(r.wall_s));
        }
    }
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
                _ => {}
            }
            if figures {
                for f in r.files.iter().filter(|f| f.ends_with(".svg")) {
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

/// A two-column table of named values.
fn pairs(md: &mut String, rows: &[(&str, String)]) {
    let _ = writeln!(md, "| quantity | value |\n|---|---|");
    for (k, v) in rows {
        let _ = writeln!(md, "| {k} | {} |", cell(v));
    }
    md.push('\n');
}

fn modes(md: &mut String, m: &ModeMap) {
    let total = m.points.len().max(1);
    let _ = writeln!(md, "| mode | grid points | share |\n|---|---|---|");
    for (mode, n) in m.counts() {
        let _ = writeln!(md, "| {} | {n} | {} % |", mode.name(), number(100.0 * n as f64 / total as f64));
    }
    md.push('\n');
    for z in &m.p_zero {
        let dir = analyses::modes::dir_name(z.dir);
        let _ = writeln!(md, "- `p = 0` for {dir} at theta1 = {} deg", number(z.theta1_deg));
    }
    md.push('\n');
}

fn admissible(md: &mut String, a: &AdmissibleReport) {
    let _ = writeln!(
        md,
        "`z_t` (m) on the belt where `p > 0` (`*`: end of the reachable belt, |z_t| <= {} m), mu = {}:\n",
        number(a.reach),
        number(a.params.mu)
    );
    let _ = writeln!(md, "| slip direction | elbow up | elbow down |\n|---|---|---|");
    for (label, dir) in
        [("z_r_dot > 0 (the paper's Table II)", SlipDirection::Positive), ("z_r_dot < 0 (mirror image)", SlipDirection::Negative)]
    {
        let _ = writeln!(
            md,
            "| {label} | {} | {} |",
            fmt_intervals(a.intervals(ElbowBranch::Up, dir)),
            fmt_intervals(a.intervals(ElbowBranch::Down, dir))
        );
    }
    let _ = writeln!(md, "\nMirror check: largest end mismatch {} m.\n", opt(a.mirror_max_diff));
}

fn simulate(md: &mut String, s: &SimulateSummary) {
    let c = &s.counters;
    pairs(
        md,
        &[
            ("status", s.status.to_string()),
            ("initial condition", s.initial_condition.name.clone()),
            ("mu, v_belt (m/s)", format!("{}, {}", number(s.params.mu), number(s.params.v_belt))),
            ("impact law, e_n", format!("{}, {}", s.sim.impact_law.name(), number(s.sim.e_n))),
            ("rtol, atol", format!("{}, {}", number(s.sim.rtol), number(s.sim.atol))),
            ("simulated (s)", number(s.simulated_s)),
            ("lift-offs", c.lift_offs.to_string()),
            ("touchdowns (bounces)", format!("{} ({})", c.touchdowns, c.bounces)),
            ("impacts without collision", c.impacts_without_collision.to_string()),
            ("stick phases, stick-to-slip", format!("{}, {}", c.stick_phases, c.stick_to_slip)),
            ("Zeno stops", c.zeno_stops.to_string()),
            ("energy-creating impacts (largest gain, J)", format!("{} ({})", c.energy_gains, number(c.max_energy_gain))),
            ("friction-cone violations", c.cone_violations.to_string()),
            ("final mode, z_t (m)", format!("{}, {}", s.final_mode, number(s.final_tip[0]))),
        ],
    );
}

fn sweep(md: &mut String, s: &SweepSummary) {
    let r = &s.results;
    let outcomes: Vec<String> = r.outcomes.iter().map(|(k, v)| format!("{k} {v}")).collect();
    pairs(
        md,
        &[
            ("runs (missing)", format!("{} ({})", r.runs, r.missing)),
            ("outcomes", outcomes.join(", ")),
            ("indicator threshold (rad/s)", number(r.threshold)),
            ("rtol, atol", format!("{}, {}", number(s.spec.rtol), number(s.spec.atol))),
        ],
    );
    let _ = writeln!(md, "Persistent bouncing, by impact law and `e_n`:\n");
    let _ = writeln!(md, "| impact law | e_n | initial condition | critical mu | bands of v_belt (m/s) per mu |\n|---|---|---|---|---|");
    for case in &r.cases {
        for ic in &case.ics {
            let per_mu: Vec<String> = ic
                .per_mu
                .iter()
                .filter(|m| !m.bands.is_empty())
                .map(|m| {
                    let bands: Vec<String> = m.bands.iter().map(|b| format!("[{}, {}]", number(b.v_min), number(b.v_max))).collect();
                    format!("{}: {}", number(m.mu), bands.join(" "))
                })
                .collect();
            let bands = if per_mu.is_empty() { "none".to_string() } else { per_mu.join("; ") };
            let critical = ic.critical_mu.map_or_else(|| "none".to_string(), number);
            let _ = writeln!(md, "| {} | {} | {} | {critical} | {bands} |", case.impact_law, number(case.e_n), ic.ic);
        }
    }
    md.push('\n');
}

fn poincare(md: &mut String, p: &PoincareSummary) {
    let c = &p.counts;
    pairs(
        md,
        &[
            ("mu, initial condition", format!("{}, {}", number(p.mu), p.initial_condition.name)),
            ("v_belt (m/s)", format!("{} to {} in steps of {}", number(p.v_belt_range[0]), number(p.v_belt_range[1]), number(p.v_step))),
            ("transient, record (s)", format!("{}, {}", number(p.transient_s), number(p.record_s))),
            ("rtol, atol", format!("{}, {}", number(p.sim.rtol), number(p.sim.atol))),
            (
                "classes",
                format!(
                    "equilibrium {}, settling {}, periodic {}, chaotic {}, aperiodic {}, failed {}",
                    c.equilibrium, c.settling, c.periodic, c.chaotic, c.aperiodic, c.failed
                ),
            ),
            ("section points", p.section_points.to_string()),
        ],
    );
    let _ = writeln!(md, "| class | period | v_belt from (m/s) | to (m/s) | points |\n|---|---|---|---|---|");
    for b in p.bands.iter().take(MAX_ROWS) {
        let period = b.period.map_or_else(|| "-".into(), |n| n.to_string());
        let _ = writeln!(md, "| {} | {period} | {} | {} | {} |", b.class.name(), number(b.v_belt_min), number(b.v_belt_max), b.points);
    }
    if p.bands.len() > MAX_ROWS {
        let _ = writeln!(md, "\n({} more bands in the files)", p.bands.len() - MAX_ROWS);
    }
    md.push('\n');
}

fn zmax(md: &mut String, z: &ZmaxSummary) {
    let _ = writeln!(md, "{}\n", z.definition);
    let _ = writeln!(
        md,
        "| controller | x0 | setting | outcome | Z_t,sliding (m) | first failing (m) | why it fails | trials |\n|---|---|---|---|---|---|---|---|"
    );
    for r in &z.results {
        let _ = writeln!(
            md,
            "| {} | x0{} | {} | {} | {} | {} | {} | {} |",
            r.controller,
            r.x0,
            r.setting,
            r.outcome,
            opt(r.z_t_sliding_m),
            opt(r.first_failing_m),
            cell(r.why_failing.as_deref().unwrap_or("-")),
            r.trials
        );
    }
    let _ = writeln!(md, "\nBisection tolerance {} m. {}\n", number(z.tol_m), z.paper);
}

fn bench(md: &mut String, figures: &[TransportFigures]) {
    let _ = writeln!(
        md,
        "| transport | runs x periods | median periods/s | round trip p50 / p99 (us) | deadline misses | target |\n|---|---|---|---|---|---|"
    );
    for f in figures {
        let rtt = f.rtt_us.map_or_else(|| "-".into(), |p| format!("{} / {}", number(p.p50), number(p.p99)));
        let target = if f.target > 0.0 { format!("{} /s", number(f.target)) } else { "0 misses".into() };
        let met = if f.meets_target { "met" } else { "**not met**" };
        let _ = writeln!(
            md,
            "| {} | {} x {} | {} | {rtt} | {} | {target}: {met} |",
            f.transport,
            f.runs,
            f.periods,
            number(f.median_periods_per_s.round()),
            f.deadline_misses
        );
    }
    md.push('\n');
}

fn pil(md: &mut String, p: &PilFigures) {
    let unit = p.count_unit.as_str();
    let _ = writeln!(md, "| {unit} per | median | p99 | worst | budget |\n|---|---|---|---|---|");
    for (what, s) in [("control step", &p.step_counts), ("frame (decode + step)", &p.frame_counts)] {
        let _ = writeln!(
            md,
            "| {what} | {} | {} | {} | {} |",
            number(s.median.round()),
            number(s.p99.round()),
            number(s.worst.round()),
            number(p.step_budget)
        );
    }
    let _ = writeln!(
        md,
        "\nWorst step: {} % of the control period at 168 MHz; within the budget: {}.\n",
        number(100.0 * p.worst_step_period_share),
        p.within_budget
    );
}

/// Closed-loop runs side by side.
fn run_comparison(md: &mut String, runs: &[(&str, &RunSummary)]) {
    let _ = write!(md, "| quantity |");
    for (id, _) in runs {
        let _ = write!(md, " {id} |");
    }
    let _ = writeln!(md, "\n|---|{}", "---|".repeat(runs.len()));
    type Row = (&'static str, fn(&RunSummary) -> String);
    let rows: [Row; 13] = [
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
        ("rms tracking error (mm)", |s| mm(s.rms_tracking_error_m)),
        ("final z_t (m)", |s| number(s.final_z_t_m)),
        ("stopped because", |s| s.error.clone().unwrap_or_else(|| "-".into())),
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
