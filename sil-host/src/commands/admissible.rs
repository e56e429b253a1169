//! `sil-host admissible`: the admissible configurations of the tip on the belt
//! (docs/model.md experiment 2, paper Table II), computed by [`analyses::admissible`];
//! this command prints them, writes `admissible.json` and draws `admissible.svg`.

use std::io::Write;

use plotters::prelude::*;
use serde::Serialize;
use shared::{Arm, ElbowBranch, SlipDirection};

use crate::{cli::AdmissibleArgs, error::CliError, output::OutputSet};
use analyses::admissible::{AdmissibleReport, MIRROR_TOL_M, PositiveInterval, ROOT_TOL_M, SCAN_STEPS, compute, p_on_belt};

#[derive(Serialize)]
struct JsonBranches {
    elbow_up: Vec<[f64; 2]>,
    elbow_down: Vec<[f64; 2]>,
}

#[derive(Serialize)]
struct JsonMirror {
    ok: bool,
    max_endpoint_difference_m: Option<f64>,
    tolerance_m: f64,
}

#[derive(Serialize)]
struct JsonReport<'a> {
    experiment: &'static str,
    mu: f64,
    h_m: f64,
    l_m: f64,
    /// Half-length of the reachable belt segment, m.
    reach_m: f64,
    method: String,
    z_r_dot_positive: JsonBranches,
    z_r_dot_negative: JsonBranches,
    paper_direction: &'static str,
    mirror_check: JsonMirror,
    files: &'a [String],
}

const PAPER_DIRECTION: &str = "The paper's experiments have v_belt < 0 with the tip at rest or moving slower than the belt, \
so z_r_dot = z_t_dot - v_belt > 0: its Table II corresponds to z_r_dot_positive. \
z_r_dot_negative is the mirror image (z_t -> -z_t, elbow up <-> elbow down).";

fn json_report<'a>(r: &AdmissibleReport, files: &'a [String]) -> JsonReport<'a> {
    let pairs = |b, d| r.intervals(b, d).iter().map(|i| [i.lo, i.hi]).collect::<Vec<_>>();
    let branches = |d| JsonBranches { elbow_up: pairs(ElbowBranch::Up, d), elbow_down: pairs(ElbowBranch::Down, d) };
    JsonReport {
        experiment: "docs/model.md experiment 2 (paper Table II): ranges of z_t (m) on the belt (z_n = -H) where p > 0",
        mu: r.params.mu,
        h_m: r.params.h,
        l_m: r.params.l,
        reach_m: r.reach,
        method: format!(
            "scan of {SCAN_STEPS} steps over [-reach, reach] plus bisection of each sign change of p to {ROOT_TOL_M:e} m; \
             an interval end equal to +-reach_m is the end of the reachable belt, not a zero of p"
        ),
        z_r_dot_positive: branches(SlipDirection::Positive),
        z_r_dot_negative: branches(SlipDirection::Negative),
        paper_direction: PAPER_DIRECTION,
        mirror_check: JsonMirror {
            ok: r.mirror_max_diff.is_some_and(|d| d <= MIRROR_TOL_M),
            max_endpoint_difference_m: r.mirror_max_diff,
            tolerance_m: MIRROR_TOL_M,
        },
        files,
    }
}

fn fmt_intervals(iv: &[PositiveInterval]) -> String {
    if iv.is_empty() {
        return "none".into();
    }
    iv.iter()
        .map(|i| {
            let end = |x: f64, root: bool| if root { format!("{x:.4}") } else { format!("{x:.4}*") };
            format!("[{}, {}]", end(i.lo, i.lo_is_root), end(i.hi, i.hi_is_root))
        })
        .collect::<Vec<_>>()
        .join(" U ")
}

/// The human summary printed by the command.
pub fn human_summary(r: &AdmissibleReport) -> String {
    let mut s = String::new();
    s += "Admissible configurations on the belt (docs/model.md experiment 2, paper Table II)\n";
    s += &format!(
        "mu = {}, H = {} m, l = {} m; reachable belt: z_t in [{:.4}, {:.4}] m\n",
        r.params.mu, r.params.h, r.params.l, -r.reach, r.reach
    );
    s += "Ranges of z_t (m) where p > 0 (* = end of the reachable belt, not a zero of p):\n";
    let rows = [("z_r_dot > 0 (paper's case)", SlipDirection::Positive), ("z_r_dot < 0 (mirror image)", SlipDirection::Negative)];
    for (label, dir) in rows {
        s += &format!("  {label}\n");
        s += &format!("    elbow up   : {}\n", fmt_intervals(r.intervals(ElbowBranch::Up, dir)));
        s += &format!("    elbow down : {}\n", fmt_intervals(r.intervals(ElbowBranch::Down, dir)));
    }
    s += "Note: the paper's experiments have v_belt < 0 with the tip at rest or slower than the belt,\n";
    s += "so z_r_dot = z_t_dot - v_belt > 0: paper Table II is the z_r_dot > 0 case.\n";
    match r.mirror_max_diff {
        Some(d) if d <= MIRROR_TOL_M => {
            s += &format!("Mirror check (z_t -> -z_t, up <-> down, z_r_dot -> -z_r_dot): ok, ends agree to {d:.1e} m\n")
        }
        Some(d) => s += &format!("Mirror check FAILED: ends differ by up to {d:.3e} m (tolerance {MIRROR_TOL_M:e} m)\n"),
        None => s += "Mirror check FAILED: the numbers of intervals differ\n",
    }
    s += &format!("Method: scan of {SCAN_STEPS} steps plus bisection of each sign change of p to {ROOT_TOL_M:e} m.\n");
    s
}

/// Tick label with two decimals and no "-0.00".
fn tick_label(x: &f64) -> String {
    let x = if x.abs() < 1e-9 { 0.0 } else { *x };
    format!("{x:.2}")
}

/// Largest `|p|` (1/kg) shown in `admissible.svg`; larger values are clamped.
const P_PLOT_MAX: f64 = 1e6;

fn plot_err(path: &std::path::Path) -> impl Fn(String) -> CliError + '_ {
    move |message| CliError::Plot { path: path.to_path_buf(), message }
}

/// Draws `p(z_t)` for `z_r_dot > 0` as an SVG at `path` (a staged file): one
/// panel per elbow branch (up on top, down below) sharing the `z_t` axis (m),
/// each with the line `p = 0`, the ends of the reachable belt (dashed) and the
/// admissible intervals (`p > 0`) shaded.
///
/// # Errors
/// [`CliError::Plot`] when plotters fails (including writing the file).
pub fn draw_figure(r: &AdmissibleReport, path: &std::path::Path) -> Result<(), CliError> {
    let perr = plot_err(path);
    let arm = Arm::new(r.params);
    let dir = SlipDirection::Positive;
    let n = 2000;
    let curve = |branch| {
        (0..=n)
            .map(|i| {
                let z = -r.reach + 2.0 * r.reach * (i as f64) / (n as f64);
                (z, p_on_belt(&arm, z, branch, dir))
            })
            .filter(|(_, p)| p.is_finite())
            .collect::<Vec<_>>()
    };
    let panels = [(ElbowBranch::Up, curve(ElbowBranch::Up)), (ElbowBranch::Down, curve(ElbowBranch::Down))];
    // One p range for both panels, so that they compare at a glance; always
    // including p = 0 and capped at +-P_PLOT_MAX (absurd mu gives absurd p, and
    // plotters cannot lay out an infinite axis): values beyond are clamped.
    let (mut ymin, mut ymax) = panels.iter().flat_map(|(_, c)| c.iter()).fold((0.0f64, 0.0f64), |(a, b), &(_, p)| (a.min(p), b.max(p)));
    ymin = ymin.max(-P_PLOT_MAX);
    ymax = ymax.min(P_PLOT_MAX);
    let pad = 0.08 * (ymax - ymin).max(1e-9);
    ymin -= pad;
    ymax += pad;
    let clamp = |p: f64| p.clamp(ymin, ymax);
    let (x0, x1) = (-r.reach * 1.03, r.reach * 1.03);

    let root = SVGBackend::new(path, (960, 780)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| perr(e.to_string()))?;
    let root = root
        .titled(&format!("Admissible configurations on the belt: p(z_t) for z_r_dot > 0, mu = {}", r.params.mu), ("sans-serif", 20))
        .map_err(|e| perr(e.to_string()))?;
    let (panels_area, note_area) = root.split_vertically(root.dim_in_pixel().1.saturating_sub(24));
    let areas = panels_area.split_evenly((2, 1));
    let line_color = RGBColor(31, 119, 180);
    let shade = RGBColor(44, 160, 44).mix(0.22);
    for ((branch, pts), area) in panels.iter().zip(areas.iter()) {
        let iv = r.intervals(*branch, dir);
        let caption = format!("elbow {}: p > 0 (shaded) for z_t in {} m", branch.name(), fmt_intervals(iv));
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, ymin..ymax)
            .map_err(|e| perr(e.to_string()))?;
        chart
            .configure_mesh()
            .max_light_lines(0)
            .x_label_formatter(&tick_label)
            .x_desc("z_t (m)")
            .y_desc("p (1/kg)")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(|e| perr(e.to_string()))?;
        chart
            .draw_series(iv.iter().map(|i| Rectangle::new([(i.lo, ymin), (i.hi, ymax)], shade.filled())))
            .map_err(|e| perr(e.to_string()))?;
        chart.draw_series(LineSeries::new([(x0, 0.0), (x1, 0.0)], BLACK.stroke_width(1))).map_err(|e| perr(e.to_string()))?;
        for x in [-r.reach, r.reach] {
            chart
                .draw_series(DashedLineSeries::new([(x, ymin), (x, ymax)], 4, 4, BLACK.mix(0.5).stroke_width(1)))
                .map_err(|e| perr(e.to_string()))?;
        }
        chart
            .draw_series(LineSeries::new(pts.iter().map(|&(z, p)| (z, clamp(p))), line_color.stroke_width(2)))
            .map_err(|e| perr(e.to_string()))?;
    }
    let note = "solid black: p = 0; dashed: ends of the reachable belt (+-sqrt((2l)^2 - H^2)); * = end of the belt, not a zero of p";
    note_area.draw_text(note, &("sans-serif", 12).into_font().color(&BLACK.mix(0.7)), (70, 4)).map_err(|e| perr(e.to_string()))?;
    root.present().map_err(|e| perr(e.to_string()))?;
    Ok(())
}

/// Runs `sil-host admissible` (docs/model.md experiment 2): computes the admissible
/// intervals for `--mu`, prints them (human table, or one JSON document with
/// `--json`), and writes `admissible.json` and `admissible.svg` under `--out`,
/// all or nothing.
///
/// # Errors
/// [`CliError::Param`] (exit 2) for a negative or non-finite `--mu`, before
/// anything is written; [`CliError::Io`] / [`CliError::Plot`] when writing fails
/// (nothing is left half-written).
pub fn run(args: &AdmissibleArgs) -> Result<(), CliError> {
    run_with(args, &mut std::io::stdout().lock())
}

/// [`run`], printing to `stdout` instead of the process's standard output.
///
/// # Errors
/// As [`run`].
pub fn run_with<W: Write>(args: &AdmissibleArgs, stdout: &mut W) -> Result<(), CliError> {
    let report = compute(args.mu)?;
    let mut out = OutputSet::new(&args.output.out)?;
    let files: Vec<String> = ["admissible.json", "admissible.svg"].iter().map(|f| out.path(f).display().to_string()).collect();
    let json = serde_json::to_string_pretty(&json_report(&report, &files))
        .map_err(|e| CliError::Io { path: out.path("admissible.json"), source: std::io::Error::other(e) })?;
    out.write_bytes("admissible.json", json.as_bytes())?;
    let svg = out.stage("admissible.svg");
    draw_figure(&report, &svg)?;
    out.commit()?;
    let text = if args.output.json { json + "\n" } else { human_summary(&report) + &format!("wrote {}\n", files.join(", ")) };
    stdout.write_all(text.as_bytes()).map_err(|source| CliError::Io { path: "<stdout>".into(), source })?;
    Ok(())
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_mu_is_rejected_with_exit_code_2_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        for mu in [-0.1, f64::NAN, f64::INFINITY] {
            let args = AdmissibleArgs { mu, output: crate::cli::OutputArgs { out: dir.path().join("o"), json: true } };
            let e = run_with(&args, &mut Vec::new()).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains("mu"), "{e}");
            if mu.is_finite() {
                assert!(e.to_string().contains("-0.1"), "{e}");
            }
            assert!(!dir.path().join("o").exists());
        }
    }

    #[test]
    fn run_writes_json_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let args = AdmissibleArgs { mu: 0.6, output: crate::cli::OutputArgs { out: dir.path().to_path_buf(), json: true } };
        let mut printed = Vec::new();
        run_with(&args, &mut printed).unwrap();
        let printed: serde_json::Value = serde_json::from_slice(&printed).unwrap();
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("admissible.json")).unwrap()).unwrap();
        assert_eq!(json["mu"], 0.6);
        assert!(json["z_r_dot_positive"]["elbow_up"].is_array());
        assert_eq!(json["mirror_check"]["ok"], true);
        assert_eq!(printed, json, "--json prints the document written to admissible.json");
        let svg = std::fs::read_to_string(dir.path().join("admissible.svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("z_t (m)"));
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
            .collect();
        assert!(leftovers.is_empty());
    }
}
