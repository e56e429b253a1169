//! `sil-host modes`: the map of contact modes over `(theta1, theta1_dot)` with the
//! tip on the belt (docs/model.md experiment 1, paper Fig. 2), computed by
//! [`analyses::modes`]; this command writes `modes.csv`, draws `modes.svg` and prints
//! the counts.

use std::{io::Write, path::Path};

use nalgebra::Vector2;
use plotters::prelude::*;
use serde::Serialize;
use shared::{ContactMode, ElbowBranch};

use crate::{cli::ModesArgs, commands::parse_range, error::CliError, output::OutputSet};
use analyses::modes::*;

#[derive(Serialize)]
struct CsvRow {
    theta1_rad: f64,
    theta1_deg: f64,
    theta1_dot: f64,
    theta2_rad: Option<f64>,
    b: Option<f64>,
    p: Option<f64>,
    z_r_dot: Option<f64>,
    mode: &'static str,
    theta2_dot: Option<f64>,
    branch: Option<&'static str>,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Writes the map as CSV (one row per grid point, `theta1` outer, `theta1_dot`
/// inner): `theta1_rad, theta1_deg, theta1_dot (rad/s), theta2_rad, b (m/s^2),
/// p (1/kg), z_r_dot (m/s), mode, theta2_dot (rad/s), branch` (`up`/`down`, the
/// elbow branch of the configuration); quantities that do not exist for the
/// point are empty.
///
/// # Errors
/// [`CliError::Io`] when writing fails.
pub fn write_csv<W: Write>(map: &ModeMap, w: W, path: &Path) -> Result<(), CliError> {
    let ioe = |e: csv::Error| CliError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) };
    let mut wr = csv::Writer::from_writer(w);
    let n2 = map.theta1_dot.len();
    for (k, pt) in map.points.iter().enumerate() {
        let (t1, w1) = (map.theta1[k / n2], map.theta1_dot[k % n2]);
        wr.serialize(CsvRow {
            theta1_rad: t1,
            theta1_deg: map.theta1_deg[k / n2],
            theta1_dot: w1,
            theta2_rad: finite(pt.theta2),
            b: finite(pt.b),
            p: finite(pt.p),
            z_r_dot: finite(pt.z_r_dot),
            mode: pt.mode.name(),
            theta2_dot: finite(pt.theta2_dot),
            branch: pt.theta2.is_finite().then(|| ElbowBranch::of(&Vector2::new(t1, pt.theta2)).name()),
        })
        .map_err(ioe)?;
    }
    wr.flush().map_err(|source| CliError::Io { path: path.to_path_buf(), source })
}

/// The fill colour of a mode in `modes.svg`.
fn color(mode: PointMode) -> RGBColor {
    match mode {
        PointMode::Contact(ContactMode::Sliding) => RGBColor(161, 217, 155),
        PointMode::Contact(ContactMode::Flight) => RGBColor(158, 202, 225),
        PointMode::Contact(ContactMode::Indeterminate) => RGBColor(253, 174, 97),
        PointMode::Contact(ContactMode::Inconsistent) => RGBColor(215, 48, 39),
        PointMode::Contact(ContactMode::Sticking) => RGBColor(255, 255, 153),
        PointMode::Unreachable => RGBColor(228, 228, 228),
        PointMode::Singular => RGBColor(60, 60, 60),
    }
}

fn plot_err(path: &Path) -> impl Fn(String) -> CliError + '_ {
    move |message| CliError::Plot { path: path.to_path_buf(), message }
}

fn branch_label(map: &ModeMap) -> String {
    let root = if map.sign.sign(map.branch) > 0.0 { "+" } else { "-" };
    match map.sign {
        Theta2Sign::Auto => format!("elbow {}, theta2 = {root}acos(H/l - cos theta1)", map.branch.name()),
        _ => format!("theta2 = {root}acos(H/l - cos theta1), both elbow branches"),
    }
}

/// `theta1` (rad) of the straight arm on the map's root of `theta2`, if the map
/// follows one root across it (`plus`: `+acos(H/2l)`, `minus`: `-acos(H/2l)`).
fn straight_arm_theta1(map: &ModeMap) -> Option<f64> {
    let t = (map.params.h / (2.0 * map.params.l)).acos();
    match map.sign {
        Theta2Sign::Auto => None,
        Theta2Sign::Plus => Some(t),
        Theta2Sign::Minus => Some(-t),
    }
}

/// Draws the map as an SVG at `path` (a staged file): cells coloured by mode
/// (merged into runs along `theta1` to keep the file small), the curves `b = 0`,
/// `p = 0` and `z_r_dot = 0`, and a legend with the counts.
///
/// # Errors
/// [`CliError::Plot`] when plotters fails (including writing the file).
pub fn draw_figure(map: &ModeMap, path: &Path) -> Result<(), CliError> {
    let perr = plot_err(path);
    let (n1, n2) = (map.theta1.len(), map.theta1_dot.len());
    let deg = &map.theta1_deg;
    let half = |v: &[f64]| if v.len() > 1 { 0.5 * (v[1] - v[0]) } else { 0.5 };
    let (hx, hy) = (half(deg), half(&map.theta1_dot));
    let (x0, x1) = (deg[0] - hx, deg[n1 - 1] + hx);
    let (y0, y1) = (map.theta1_dot[0] - hy, map.theta1_dot[n2 - 1] + hy);
    let x_edge = |i: usize| {
        if i == 0 {
            x0
        } else if i == n1 {
            x1
        } else {
            0.5 * (deg[i - 1] + deg[i])
        }
    };
    let y_edge = |j: usize| {
        if j == 0 {
            y0
        } else if j == n2 {
            y1
        } else {
            0.5 * (map.theta1_dot[j - 1] + map.theta1_dot[j])
        }
    };

    let root = SVGBackend::new(path, (1100, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| perr(e.to_string()))?;
    let title = format!(
        "Contact modes on the belt (paper Fig. 2): mu = {}, v_belt = {} m/s, u = 0, {}",
        map.params.mu,
        map.params.v_belt,
        branch_label(map)
    );
    let root = root.titled(&title, ("sans-serif", 18)).map_err(|e| perr(e.to_string()))?;
    let (left, right) = root.split_horizontally(800);
    let mut chart = ChartBuilder::on(&left)
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| perr(e.to_string()))?;

    // Cells, run-length merged along theta1 within each theta1_dot row.
    let mut rects = Vec::new();
    for j in 0..n2 {
        let mut i = 0;
        while i < n1 {
            let mode = map.points[i * n2 + j].mode;
            let mut k = i + 1;
            while k < n1 && map.points[k * n2 + j].mode == mode {
                k += 1;
            }
            rects.push(Rectangle::new([(x_edge(i), y_edge(j)), (x_edge(k), y_edge(j + 1))], color(mode).filled()));
            i = k;
        }
    }
    chart.draw_series(rects).map_err(|e| perr(e.to_string()))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("theta1 (deg)")
        .y_desc("theta1_dot (rad/s)")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| perr(e.to_string()))?;

    let zr_style = RGBColor(80, 80, 80).stroke_width(2);
    for line in &map.zr_zero {
        chart.draw_series(DashedLineSeries::new(line.iter().copied(), 6, 5, zr_style)).map_err(|e| perr(e.to_string()))?;
    }
    let b_style = BLACK.stroke_width(2);
    for line in &map.b_zero {
        if line.len() == 1 {
            chart.draw_series(std::iter::once(Circle::new(line[0], 1, BLACK.filled()))).map_err(|e| perr(e.to_string()))?;
        } else {
            chart.draw_series(LineSeries::new(line.iter().copied(), b_style)).map_err(|e| perr(e.to_string()))?;
        }
    }
    let straight_style = BLACK.mix(0.6).stroke_width(1);
    let straight = straight_arm_theta1(map).map(f64::to_degrees).filter(|d| *d > x0 && *d < x1);
    if let Some(d) = straight {
        chart.draw_series(DashedLineSeries::new([(d, y0), (d, y1)], 2, 3, straight_style)).map_err(|e| perr(e.to_string()))?;
    }
    let p_style = RGBColor(148, 0, 211).stroke_width(3);
    for z in &map.p_zero {
        if let Some([a, b]) = z.theta1_dot_range {
            chart.draw_series(LineSeries::new([(z.theta1_deg, a), (z.theta1_deg, b)], p_style)).map_err(|e| perr(e.to_string()))?;
        }
    }

    // Legend panel.
    let total = map.points.len().max(1);
    let text = |s: &str, size: u32| (s.to_string(), ("sans-serif", size).into_font().color(&BLACK));
    let mut y = 40;
    let (t, f) = text("Mode (count, share of grid)", 15);
    right.draw_text(&t, &f, (10, y)).map_err(|e| perr(e.to_string()))?;
    y += 28;
    for (mode, count) in map.counts() {
        right.draw(&Rectangle::new([(12, y - 2), (32, y + 14)], color(mode).filled())).map_err(|e| perr(e.to_string()))?;
        right.draw(&Rectangle::new([(12, y - 2), (32, y + 14)], BLACK.mix(0.5))).map_err(|e| perr(e.to_string()))?;
        let (t, f) = text(&format!("{} ({count}, {:.1}%)", mode.name(), 100.0 * count as f64 / total as f64), 14);
        right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
        y += 26;
    }
    y += 14;
    let (t, f) = text("Curves", 15);
    right.draw_text(&t, &f, (10, y)).map_err(|e| perr(e.to_string()))?;
    y += 28;
    right.draw(&PathElement::new([(12, y + 6), (32, y + 6)], b_style)).map_err(|e| perr(e.to_string()))?;
    let (t, f) = text("b = 0", 14);
    right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    y += 26;
    right.draw(&PathElement::new([(12, y + 6), (32, y + 6)], p_style)).map_err(|e| perr(e.to_string()))?;
    let (t, f) = text("p = 0 (p for the local sign(z_r_dot))", 14);
    right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    y += 26;
    right.draw(&PathElement::new([(12, y + 6), (18, y + 6)], zr_style)).map_err(|e| perr(e.to_string()))?;
    right.draw(&PathElement::new([(24, y + 6), (32, y + 6)], zr_style)).map_err(|e| perr(e.to_string()))?;
    let (t, f) = text("z_r_dot = 0 (p jumps)", 14);
    right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    if straight.is_some() {
        y += 26;
        right.draw(&PathElement::new([(12, y + 6), (14, y + 6)], straight_style)).map_err(|e| perr(e.to_string()))?;
        right.draw(&PathElement::new([(18, y + 6), (20, y + 6)], straight_style)).map_err(|e| perr(e.to_string()))?;
        right.draw(&PathElement::new([(24, y + 6), (26, y + 6)], straight_style)).map_err(|e| perr(e.to_string()))?;
        let (t, f) = text("straight arm: elbow up left, down right", 14);
        right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    }
    y += 40;
    let notes = [
        "theta2: tip on the belt (z_n = -H)".to_string(),
        "theta2_dot: z_n_dot = 0".to_string(),
        format!("grid {n1} x {n2}"),
        "sliding: p > 0, b < 0".to_string(),
        "flight: p > 0, b >= 0".to_string(),
        "indeterminate: p <= 0, b >= 0".to_string(),
        "inconsistent: p <= 0, b < 0".to_string(),
    ];
    for n in notes {
        let (t, f) = text(&n, 13);
        right.draw_text(&t, &f, (10, y)).map_err(|e| perr(e.to_string()))?;
        y += 20;
    }
    root.present().map_err(|e| perr(e.to_string()))?;
    Ok(())
}

#[derive(Serialize)]
struct JsonCount {
    mode: &'static str,
    count: usize,
    fraction_of_grid: f64,
    /// Fraction of the points with the tip on the belt (neither unreachable nor singular).
    fraction_of_on_belt: Option<f64>,
}

#[derive(Serialize)]
struct JsonSummary<'a> {
    experiment: &'static str,
    mu: f64,
    v_belt: f64,
    /// The requested branch; `None` when `theta2_sign` is plus/minus (branch ignored).
    branch: Option<&'static str>,
    theta2_sign: Theta2Sign,
    theta2_rule: String,
    theta1_deg_range: [f64; 2],
    theta1_dot_range: [f64; 2],
    grid: [usize; 2],
    points: usize,
    on_belt_points: usize,
    counts: Vec<JsonCount>,
    p_zero: &'a [PZero],
    b_zero_curve_points: usize,
    files: &'a [String],
}

fn summary<'a>(map: &'a ModeMap, files: &'a [String]) -> JsonSummary<'a> {
    let counts = map.counts();
    let on_belt: usize = counts.iter().filter(|(m, _)| matches!(m, PointMode::Contact(_))).map(|(_, c)| c).sum();
    let total = map.points.len();
    JsonSummary {
        experiment: "docs/model.md experiment 1 (paper Fig. 2): contact mode over (theta1, theta1_dot), tip on the belt, z_n_dot = 0, u = 0",
        mu: map.params.mu,
        v_belt: map.params.v_belt,
        branch: (map.sign == Theta2Sign::Auto).then(|| map.branch.name()),
        theta2_sign: map.sign,
        theta2_rule: branch_label(map),
        theta1_deg_range: [map.theta1_deg[0], map.theta1_deg[map.theta1_deg.len() - 1]],
        theta1_dot_range: [map.theta1_dot[0], map.theta1_dot[map.theta1_dot.len() - 1]],
        grid: [map.theta1.len(), map.theta1_dot.len()],
        points: total,
        on_belt_points: on_belt,
        counts: counts
            .iter()
            .map(|&(m, c)| JsonCount {
                mode: m.name(),
                count: c,
                fraction_of_grid: c as f64 / total.max(1) as f64,
                fraction_of_on_belt: match m {
                    PointMode::Contact(_) if on_belt > 0 => Some(c as f64 / on_belt as f64),
                    _ => None,
                },
            })
            .collect(),
        p_zero: &map.p_zero,
        b_zero_curve_points: map.b_zero.iter().map(Vec::len).sum(),
        files,
    }
}

/// The human summary printed by the command.
pub fn human_summary(map: &ModeMap) -> String {
    let files: [String; 0] = [];
    let s = summary(map, &files);
    let mut out = String::new();
    out += "Contact modes on the belt (docs/model.md experiment 1, paper Fig. 2)\n";
    out += &format!("mu = {}, v_belt = {} m/s, u = 0, {}\n", s.mu, s.v_belt, s.theta2_rule);
    out += &format!(
        "grid {} x {}: theta1 in [{}, {}] deg, theta1_dot in [{}, {}] rad/s; {} of {} points have the tip on the belt\n",
        s.grid[0],
        s.grid[1],
        s.theta1_deg_range[0],
        s.theta1_deg_range[1],
        s.theta1_dot_range[0],
        s.theta1_dot_range[1],
        s.on_belt_points,
        s.points
    );
    out += &format!("  {:<14} {:>8} {:>9} {:>12}\n", "mode", "count", "of grid", "of on-belt");
    for c in &s.counts {
        let ob = c.fraction_of_on_belt.map(|f| format!("{:.2}%", 100.0 * f)).unwrap_or_else(|| "-".into());
        out += &format!("  {:<14} {:>8} {:>8.2}% {:>12}\n", c.mode, c.count, 100.0 * c.fraction_of_grid, ob);
    }
    if map.p_zero.is_empty() {
        out += "p = 0: no zero of p in the theta1 range\n";
    }
    for z in &map.p_zero {
        let w = match z.theta1_dot_range {
            Some([a, b]) => format!("boundary for theta1_dot in [{a:.3}, {b:.3}] rad/s"),
            None => "not a boundary here (z_r_dot has the other sign over the whole window)".into(),
        };
        out += &format!("p = 0 for {} at theta1 = {:.4} deg: {w}\n", dir_name(z.dir), z.theta1_deg);
    }
    out += &format!("b = 0: {} curve points located (marching squares, bisection along cell edges to 1e-12)\n", s.b_zero_curve_points);
    out
}

/// Runs `sil-host modes` (docs/model.md experiment 1): computes the map, prints the
/// counts per mode (human table, or one JSON document with `--json`) and writes
/// `modes.csv` and `modes.svg` under `--out`, all or nothing.
///
/// # Errors
/// [`CliError::BadInput`] / [`CliError::Param`] (exit 2) for bad ranges, grid
/// size, `mu` or `v_belt`, before anything is written; [`CliError::Io`] /
/// [`CliError::Plot`] when writing fails (nothing is left half-written).
pub fn run(args: &ModesArgs) -> Result<(), CliError> {
    run_with(args, &mut std::io::stdout().lock())
}

/// [`run`], printing to `stdout` instead of the process's standard output.
///
/// # Errors
/// As [`run`].
pub fn run_with<W: Write>(args: &ModesArgs, stdout: &mut W) -> Result<(), CliError> {
    let t1 = parse_range("theta1-deg", &args.theta1_deg)?;
    let t1d = parse_range("theta1-dot", &args.theta1_dot)?;
    let map = compute(args.mu, args.v_belt, args.branch, args.theta2_sign, t1, t1d, args.grid)?;
    let mut out = OutputSet::new(&args.output.out)?;
    let files: Vec<String> = ["modes.csv", "modes.svg"].iter().map(|f| out.path(f).display().to_string()).collect();
    let (tmp, w) = out.create("modes.csv")?;
    write_csv(&map, w, &tmp)?;
    let svg = out.stage("modes.svg");
    draw_figure(&map, &svg)?;
    out.commit()?;
    let text = if args.output.json {
        serde_json::to_string_pretty(&summary(&map, &files))
            .map_err(|e| CliError::Io { path: "<stdout>".into(), source: std::io::Error::other(e) })?
            + "\n"
    } else {
        human_summary(&map) + &format!("wrote {}\n", files.join(", "))
    };
    stdout.write_all(text.as_bytes()).map_err(|source| CliError::Io { path: "<stdout>".into(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MU: f64 = 0.6;
    const V: f64 = -0.4;

    fn args(out: &Path) -> ModesArgs {
        ModesArgs {
            mu: MU,
            v_belt: V,
            branch: shared::ElbowBranch::Down,
            theta1_deg: "-40,40".into(),
            theta1_dot: "-10,10".into(),
            grid: 60,
            theta2_sign: Theta2Sign::Auto,
            output: crate::cli::OutputArgs { out: out.to_path_buf(), json: true },
        }
    }

    #[test]
    fn bad_input_exits_2_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("o");
        let cases: [fn(&mut ModesArgs); 8] = [
            |a| a.mu = -1.0,
            |a| a.mu = f64::NAN,
            |a| a.v_belt = f64::INFINITY,
            |a| a.grid = 1,
            |a| a.grid = GRID_MAX + 1,
            |a| a.theta1_deg = "10,-10".into(),
            |a| a.theta1_dot = "x".into(),
            |a| a.theta1_dot = "-1e308,1e308".into(),
        ];
        for set in cases {
            let mut a = args(&out);
            set(&mut a);
            let e = run_with(&a, &mut Vec::new()).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            assert!(!out.exists());
        }
    }

    #[test]
    fn run_writes_csv_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let mut printed = Vec::new();
        run_with(&args(dir.path()), &mut printed).unwrap();
        let json: serde_json::Value = serde_json::from_slice(&printed).unwrap();
        assert_eq!(json["points"], 3600);
        let total: u64 = json["counts"].as_array().unwrap().iter().map(|c| c["count"].as_u64().unwrap()).sum();
        assert_eq!(total, 3600);
        let csv = std::fs::read_to_string(dir.path().join("modes.csv")).unwrap();
        let mut lines = csv.lines();
        assert_eq!(lines.next().unwrap(), "theta1_rad,theta1_deg,theta1_dot,theta2_rad,b,p,z_r_dot,mode,theta2_dot,branch");
        assert_eq!(lines.count(), 60 * 60);
        let svg = std::fs::read_to_string(dir.path().join("modes.svg")).unwrap();
        assert!(svg.contains("theta1 (deg)") && svg.contains("sliding"));
    }
}
