//! The paper side by side: every number the paper prints (docs/model.md "What the
//! paper reports", [`analyses::paper`]), ours from this report's own results, the
//! difference, and its cause in one line.

use std::fmt::Write as _;

use analyses::paper;
use firmware::ControllerKind;
use plant::initial::PaperX0;
use shared::{ElbowBranch, SlipDirection};

use super::format::{POSITION_RESOLUTION_M, cell, given, located, on_grid, position, signed};
use super::outcome::{Outcome, StepResult};
use crate::commands::sweep::outputs::SweepSummary;

/// One row: what, the paper's value, ours, the difference, the cause.
struct Row {
    what: String,
    paper: String,
    ours: String,
    difference: String,
    cause: String,
}

/// A value the paper prints, in m, as printed.
fn m(x: f64) -> String {
    format!("{} m", given(x))
}

/// Ours, a tip position in m ([`position`]).
fn ours_m(x: f64) -> String {
    format!("{} m", position(x))
}

/// The difference ours - theirs in mm, to `resolution_m` (ours's resolution).
fn diff_mm(ours: f64, theirs: f64, resolution_m: f64) -> String {
    format!("{} mm", signed(located((ours - theirs) * 1e3, resolution_m * 1e3)))
}

/// The step `id`'s typed result, if it ran.
fn find<'a>(results: &'a [Vec<StepResult>], id: &str) -> Option<&'a Outcome> {
    results.iter().flatten().find(|r| r.id == id).and_then(|r| r.outcome.as_ref())
}

fn sweep<'a>(results: &'a [Vec<StepResult>], id: &str) -> Option<&'a SweepSummary> {
    match find(results, id) {
        Some(Outcome::Sweep(s)) => Some(s),
        _ => None,
    }
}

/// The table, drawn from the report's steps `results` (a row whose step did not run
/// says so).
pub(crate) fn side_by_side(md: &mut String, results: &[Vec<StepResult>]) {
    let mut rows = Vec::new();
    table_ii(&mut rows, results);
    open_loop(&mut rows, results);
    z_t_sliding(&mut rows, results);
    closed_loop(&mut rows, results);
    let _ = writeln!(
        md,
        "\n## The paper side by side\n\n*docs/model.md \"What the paper reports\": every number the paper prints, ours from the sections below, and why they differ*\n"
    );
    let _ = writeln!(md, "| result | paper | ours | difference | cause |\n|---|---|---|---|---|");
    for r in rows {
        let _ =
            writeln!(md, "| {} | {} | {} | {} | {} |", cell(&r.what), cell(&r.paper), cell(&r.ours), cell(&r.difference), cell(&r.cause));
    }
    md.push('\n');
}

fn missing(what: &str, paper: String, step: &str) -> Row {
    Row { what: what.into(), paper, ours: format!("(step {step} did not run)"), difference: "-".into(), cause: "-".into() }
}

fn table_ii(rows: &mut Vec<Row>, results: &[Vec<StepResult>]) {
    let Some(Outcome::Admissible(a)) = find(results, "admissible") else {
        rows.push(missing("Table II", "see docs/model.md".into(), "admissible"));
        return;
    };
    for (branch, name, theirs) in
        [(ElbowBranch::Up, "elbow up", paper::TABLE_II_ELBOW_UP_M), (ElbowBranch::Down, "elbow down", paper::TABLE_II_ELBOW_DOWN_M)]
    {
        let Some(i) = a.intervals(branch, SlipDirection::Positive).first() else { continue };
        rows.push(Row {
            what: format!("Table II, {name}, mu = {}: lower end of p > 0", paper::TABLE_II_MU),
            paper: m(theirs[0]),
            ours: ours_m(i.lo),
            difference: diff_mm(i.lo, theirs[0], POSITION_RESOLUTION_M),
            cause: "none: the end of the reachable belt (the arm straight), printed to 3 decimals".into(),
        });
        let (difference, cause) = if (i.hi - theirs[1]).abs() <= 5e-4 {
            (diff_mm(i.hi, theirs[1], POSITION_RESOLUTION_M), "none: the paper prints 3 decimals".to_string())
        } else {
            (
                diff_mm(i.hi, theirs[1], POSITION_RESOLUTION_M),
                "not found: more than the paper's rounding; ours is the root of p on the belt, located to 1e-9 m and equal to an independent implementation's; the paper does not say how it located its end".to_string(),
            )
        };
        rows.push(Row {
            what: format!("Table II, {name}, mu = {}: upper end of p > 0", paper::TABLE_II_MU),
            paper: m(theirs[1]),
            ours: ours_m(i.hi),
            difference,
            cause,
        });
    }
}

fn open_loop(rows: &mut Vec<Row>, results: &[Vec<StepResult>]) {
    let Some(s) = sweep(results, "sweep-open-loop") else {
        rows.push(missing("Fig. 3", "see docs/model.md".into(), "sweep-open-loop"));
        return;
    };
    // The defaults: Newton, e_n = 0.2, the restitution IWC rule (docs/model.md).
    let Some(case) =
        s.results.cases.iter().find(|c| c.impact_law == "newton" && c.e_n == 0.2 && c.iwc == plant::impact::IwcRule::Restitution)
    else {
        return;
    };
    let ic = |name: &str| case.ics.iter().find(|i| i.ic == name);
    if let Some(x0a) = ic("x0a") {
        let ours = x0a.critical_mu;
        let (mu_step, v_step) = (s.spec.mu.step, s.spec.v_belt.step);
        rows.push(Row {
            what: format!("Fig. 3: critical mu (from x0a, on a {} grid of mu)", given(mu_step)),
            paper: given(paper::CRITICAL_MU),
            ours: ours.map_or("none".into(), |o| on_grid(o, mu_step)),
            difference: ours.map_or("-".into(), |o| signed(on_grid(o - paper::CRITICAL_MU, mu_step))),
            cause: if ours == Some(paper::CRITICAL_MU) {
                "none".into()
            } else {
                "the impact law and e_n the paper leaves open (sensitivity rows \"impact law, e_n\")".into()
            },
        });
        let band = x0a.per_mu.iter().find(|b| (b.mu - 0.6).abs() < 1e-9).and_then(|b| b.bands.iter().max_by_key(|x| x.points));
        let theirs = paper::BOUNCING_X0A_MU06_M_S;
        rows.push(Row {
            what: "Fig. 3: persistent bouncing at mu = 0.6 from x0a, v_belt (the longest band)".into(),
            paper: format!("[{}, {}] m/s", theirs[0], theirs[1]),
            ours: band.map_or("none".into(), |b| format!("[{}, {}] m/s", on_grid(b.v_min, v_step), on_grid(b.v_max, v_step))),
            difference: band.map_or("-".into(), |b| {
                format!("{}, {} m/s", signed(located(b.v_min - theirs[0], 1e-3)), signed(located(b.v_max - theirs[1], 1e-3)))
            }),
            cause: format!(
                "the impact law and e_n the paper leaves open (ours: Newton, e_n = 0.2{}), and our grid of {} m/s",
                law_spread(results),
                given(v_step)
            ),
        });
    }
    if let Some(x0d) = ic("x0d") {
        let bounces = x0d.critical_mu.is_some();
        rows.push(Row {
            what: "Fig. 3: persistent bouncing from x0d".into(),
            paper: "none".into(),
            ours: if bounces {
                format!("from mu = {}", on_grid(x0d.critical_mu.unwrap_or(f64::NAN), s.spec.mu.step))
            } else {
                "none".into()
            },
            difference: if bounces == paper::X0D_BOUNCES { "none".into() } else { "differs".into() },
            cause: if bounces == paper::X0D_BOUNCES { "none".into() } else { "the impact law the paper leaves open".into() },
        });
    }
}

/// How far the sensitivity study's impact-law rows move the band's ends, as
/// `; the sensitivity rows "impact law, e_n" put its ends from .. to ..`; empty
/// when the study did not run.
fn law_spread(results: &[Vec<StepResult>]) -> String {
    let Some(Outcome::Sensitivity(s)) = find(results, "sensitivity") else { return String::new() };
    let bands: Vec<[f64; 2]> = s
        .study
        .results
        .iter()
        .filter(|r| r.choice.dimension == analyses::sensitivity::Dimension::ImpactLaw)
        .filter_map(|r| r.open_loop.as_ref().and_then(|o| o.band_x0a_mu06))
        .collect();
    if bands.is_empty() {
        return String::new();
    }
    let step = s.study.grids.v_belt.step;
    let lo = |i: usize| bands.iter().map(|b| b[i]).fold(f64::INFINITY, f64::min);
    let hi = |i: usize| bands.iter().map(|b| b[i]).fold(f64::NEG_INFINITY, f64::max);
    format!(
        "; the sensitivity rows \"impact law, e_n\" put its lower end from {} to {} m/s and its upper end from {} to {} m/s",
        on_grid(lo(0), step),
        on_grid(hi(0), step),
        on_grid(lo(1), step),
        on_grid(hi(1), step)
    )
}

fn z_t_sliding(rows: &mut Vec<Row>, results: &[Vec<StepResult>]) {
    let Some(Outcome::Zmax(z)) = find(results, "zmax") else {
        rows.push(missing("Z_t,sliding", "see docs/model.md".into(), "zmax"));
        return;
    };
    use super::experiments::limit;
    let tol = z.tol_m;
    for (controller, x0) in [
        (ControllerKind::Pid, PaperX0::D),
        (ControllerKind::Pid, PaperX0::U),
        (ControllerKind::Hybrid, PaperX0::D),
        (ControllerKind::Hybrid, PaperX0::U),
    ] {
        let Some(theirs) = paper::z_t_sliding(controller, x0) else { continue };
        let of =
            |setting: analyses::zmax::Setting| z.results.iter().find(|r| r.controller == controller && r.x0 == x0 && r.setting == setting);
        let (Some(ideal), Some(sampled)) = (of(analyses::zmax::Setting::Ideal), of(analyses::zmax::Setting::Sampled)) else { continue };
        let text = |r: &crate::commands::zmax::summary::ZmaxRow| limit(r.outcome, r.z_t_sliding_m, r.bracket_lo_m, r.bracket_hi_m, tol);
        let ours = format!("{} m ideal, {} m sampled", text(ideal), text(sampled));
        let (difference, cause) = match (theirs, ideal.z_t_sliding_m) {
            (None, None) => ("none".to_string(), format!("none: {}", ideal.why_failing.as_deref().unwrap_or("the lowest target fails"))),
            (Some(t), Some(o)) if controller == ControllerKind::Pid => (
                diff_mm(o, t, tol),
                format!(
                    "the paper does not say how closely or for how long the target is reached: ours never lifts off from x0d, and stops where the steady error exceeds {} mm ({}); within {} mm it tracks to {} m",
                    given(z.criteria.reach_tol_m * 1e3),
                    ideal.why_failing.as_deref().unwrap_or("-"),
                    given(z.criteria.settle_tol_m * 1e3),
                    ideal.z_t_tracking_m.map_or("-".into(), |v| located(v, tol))
                ),
            ),
            (Some(t), Some(o)) => (
                diff_mm(o, t, tol),
                format!(
                    "not found: ours (ideal) lifts off where p = 0 on the belt ({} m, Table II's end on the branch), under every open choice of the sensitivity study; the paper's limit lies inside it",
                    ideal.p_zero_end_m.map_or("-".into(), position)
                ),
            ),
            _ => ("differs".to_string(), ideal.why_failing.clone().unwrap_or_default()),
        };
        rows.push(Row {
            what: format!("Z_t,sliding, {controller} from x0{}", x0.letter()),
            paper: theirs.map_or("none (lifts off)".into(), m),
            ours,
            difference,
            cause,
        });
    }
}

fn closed_loop(rows: &mut Vec<Row>, results: &[Vec<StepResult>]) {
    let lifting = |s: &SweepSummary| -> Vec<f64> {
        s.results.outcomes_per_mu.iter().filter(|m| m.outcomes.get("lift_off").is_some_and(|&n| n > 0)).map(|m| m.mu).collect()
    };
    let (Some(sampled), ideal) = (sweep(results, "sweep-hybrid"), sweep(results, "sweep-hybrid-ideal")) else {
        rows.push(missing("Fig. 9", "none".into(), "sweep-hybrid"));
        return;
    };
    let step = sampled.spec.mu.step;
    let text = |mus: &[f64]| {
        if mus.is_empty() {
            "no lift-off".to_string()
        } else {
            format!("lift-offs at mu = {}", mus.iter().map(|m| on_grid(*m, step)).collect::<Vec<_>>().join(", "))
        }
    };
    let s = lifting(sampled);
    let i = ideal.map(lifting);
    rows.push(Row {
        what: "Fig. 9: persistent bouncing of the hybrid closed loop, v_belt in [-1, -0.1] m/s".into(),
        paper: "none".into(),
        ours: format!("ideal law: {}; sampled firmware: {}", i.as_deref().map_or("(not run)".into(), text), text(&s)),
        difference: if s.is_empty() && i.as_ref().is_none_or(|i| i.is_empty()) { "none".into() } else { "differs".into() },
        cause: if s.is_empty() {
            "none".into()
        } else {
            "the sampled controller against the ideal one: the base motor saturates at 5 N m where mu f_n* is large (the closed-loop section)".into()
        },
    });
}
