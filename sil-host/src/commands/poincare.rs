//! `sil-host poincare`: the one-parameter bifurcation diagram of the open loop
//! (docs/model.md experiment 4, the paper's Fig. 4), with each belt speed classified.
//!
//! Writes under `--out`: `section.csv` (every section point: `v_belt`, crossing
//! time, state), `classes.csv` and `classes.json` (per `v_belt`: class, period,
//! distinct points, Lyapunov estimate, events in the record), `summary.json`
//! (settings, the initial condition and its projection, the bands of equal class,
//! wall time), `bifurcation.svg` (`theta1` at the section against `v_belt`,
//! coloured by class) and `lyapunov.svg` (the exponent against `v_belt`).
//! A belt speed whose simulation fails is written with class `failed` and the
//! command exits with 1 after writing everything.

use std::{io::Write, path::Path, time::Instant};

use plotters::prelude::*;
use rayon::prelude::*;
use serde::Serialize;
use shared::Params;

use crate::{
    cli::PoincareArgs,
    commands::{
        parse_range,
        simulate::{InitialCondition, chosen_initial_condition},
    },
    error::CliError,
    output::{OutputSet, progress_bar, write_csv},
    plot::{self, colors, plot_err},
};
use analyses::poincare::{
    self, Band, PoincareConfig, PointResult,
    classify::{Class, ClassifyConfig},
    lyapunov::LyapunovConfig,
};
use plant::initial;
use plant::{Plant, SimConfig};

/// One row of `section.csv`.
#[derive(Debug, Clone, Serialize)]
struct SectionRow {
    v_belt: f64,
    t: f64,
    theta1: f64,
    theta1_deg: f64,
    theta1_dot: f64,
    theta2: f64,
    theta2_dot: f64,
    kind: &'static str,
    mode: &'static str,
}

/// One row of `classes.csv`.
#[derive(Debug, Clone, Serialize)]
struct ClassRow {
    v_belt: f64,
    class: &'static str,
    period: Option<usize>,
    n_crossings: usize,
    distinct_points: usize,
    lyapunov_per_crossing: Option<f64>,
    lyapunov_per_s: Option<f64>,
    lyapunov_std_error: Option<f64>,
    lyapunov_iterations: Option<usize>,
    lyapunov_collapsed: Option<usize>,
    final_mode: &'static str,
    final_theta1: f64,
    lift_offs: u64,
    touchdowns: u64,
    error: String,
    wall_s: f64,
}

impl From<&PointResult> for ClassRow {
    fn from(r: &PointResult) -> Self {
        Self {
            v_belt: r.v_belt,
            class: r.class.name(),
            period: r.period,
            n_crossings: r.n_crossings,
            distinct_points: r.distinct_points,
            lyapunov_per_crossing: r.lyapunov.map(|l| l.per_iteration),
            lyapunov_per_s: r.lyapunov.map(|l| l.per_second),
            lyapunov_std_error: r.lyapunov.map(|l| l.std_error),
            lyapunov_iterations: r.lyapunov.map(|l| l.iterations),
            lyapunov_collapsed: r.lyapunov.map(|l| l.collapsed),
            final_mode: r.final_mode,
            final_theta1: r.final_theta1,
            lift_offs: r.lift_offs,
            touchdowns: r.touchdowns,
            error: r.error.clone().unwrap_or_default(),
            wall_s: r.wall_s,
        }
    }
}

/// Count of grid points per class.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ClassCounts {
    /// No crossings.
    pub equilibrium: usize,
    /// Too few crossings.
    pub settling: usize,
    /// Periodic, any period.
    pub periodic: usize,
    /// Chaotic.
    pub chaotic: usize,
    /// Aperiodic without a positive exponent.
    pub aperiodic: usize,
    /// Failed simulations.
    pub failed: usize,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// `ok`, or `failed` when some belt speed failed.
    pub status: &'static str,
    /// Friction coefficient.
    pub mu: f64,
    /// The initial condition and its projection onto the belt.
    pub initial_condition: InitialCondition,
    /// Belt-speed grid: `[min, max]`, m/s.
    pub v_belt_range: [f64; 2],
    /// Grid step, m/s.
    pub v_step: f64,
    /// Grid points.
    pub grid_points: usize,
    /// Transient, s.
    pub transient_s: f64,
    /// Record window, s.
    pub record_s: f64,
    /// Simulator settings.
    pub sim: SimConfig,
    /// Classification settings.
    pub classify: ClassifyConfig,
    /// Lyapunov settings.
    pub lyapunov: LyapunovConfig,
    /// Hysteresis of the section, rad/s.
    pub section_depth: f64,
    /// Longest wait of the section map for a return, s.
    pub max_return_s: f64,
    /// Grid points per class.
    pub counts: ClassCounts,
    /// Runs of neighbouring belt speeds with equal class and period.
    pub bands: Vec<Band>,
    /// Section points written.
    pub section_points: usize,
    /// Worker threads.
    pub threads: usize,
    /// Wall time of the sweep (without writing files), s.
    pub wall_s: f64,
    /// Median wall time of one belt speed (one thread), s.
    pub median_point_wall_s: f64,
    /// Files written.
    pub files: Vec<String>,
}

/// The belt-speed grid `min, min + step, ..., max` (the last point is `max`).
fn grid(min: f64, max: f64, step: f64) -> Vec<f64> {
    let n = ((max - min) / step + 1e-9).floor() as usize;
    // Rounded to 1e-12 m/s so that the grid prints as typed (-0.82, not -0.8200000000000001).
    let mut v: Vec<f64> = (0..=n).map(|i| ((min + i as f64 * step) * 1e12).round() / 1e12).collect();
    if max - v[n] > 1e-9 * step.max(1.0) {
        v.push(max);
    }
    v
}

fn validated(args: &PoincareArgs) -> Result<(PoincareConfig, Vec<f64>, InitialCondition), CliError> {
    let bad = |m: String| Err(CliError::BadInput(m));
    // One speed `V`, or a range `MIN,MAX`.
    let (v_min, v_max) = match args.v_belt.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => (v, v),
        _ => parse_range("v-belt", &args.v_belt)?,
    };
    if !(args.v_step.is_finite() && args.v_step > 0.0) {
        return bad(format!("--v-step must be a finite step > 0 m/s, got {}", args.v_step));
    }
    if (v_max - v_min) / args.v_step > 1e5 {
        return bad(format!("--v-belt {} with --v-step {} gives more than 100000 points", args.v_belt, args.v_step));
    }
    if !(args.transient.is_finite() && (0.0..=1e5).contains(&args.transient)) {
        return bad(format!("--transient must be in [0, 1e5] s, got {}", args.transient));
    }
    if !(args.record.is_finite() && args.record > 0.0 && args.record <= 1e5) {
        return bad(format!("--record must be in (0, 1e5] s, got {}", args.record));
    }
    if !(args.tol.is_finite() && args.tol > 0.0) {
        return bad(format!("--tol must be a finite value > 0 rad, got {}", args.tol));
    }
    if args.max_period == 0 || args.max_period > 10_000 {
        return bad(format!("--max-period must be in [1, 10000], got {}", args.max_period));
    }
    if !args.chaos_threshold.is_finite() {
        return bad(format!("--chaos-threshold must be finite, got {}", args.chaos_threshold));
    }
    if !(args.lyap_d0.is_finite() && args.lyap_d0 > 0.0 && args.lyap_d0 <= 1e-2) {
        return bad(format!("--lyap-d0 must be in (0, 1e-2], got {}", args.lyap_d0));
    }
    if args.lyap_iterations > 1_000_000 || args.lyap_skip > 1_000_000 {
        return bad("--lyap-iterations and --lyap-skip must be at most 1e6".into());
    }
    if !(args.section_depth.is_finite() && args.section_depth >= 0.0) {
        return bad(format!("--section-depth must be a finite value >= 0 rad/s, got {}", args.section_depth));
    }
    if args.threads == Some(0) {
        return bad("--threads must be at least 1".into());
    }
    // Parameters at both ends of the grid (mu, v_belt finite, ...).
    Params::new(args.mu, v_min)?;
    let params = Params::new(args.mu, v_max)?;
    let sim = SimConfig { rtol: args.rtol, atol: args.atol, impact_law: args.impact_law, e_n: args.e_n, ..SimConfig::default() };
    sim.validate()?;
    let (name, given_deg) = chosen_initial_condition(args.x0, args.x0_deg.as_deref())?;
    let x0 = initial::deg_to_state(given_deg);
    let projection = initial::describe_projection(&params, x0);
    // The initial state must be acceptable to the plant (not below the belt, reachable).
    let plant = Plant::new(params, sim, x0, 0.0, [0.0, 0.0])?;
    let ic = InitialCondition {
        name,
        given_deg,
        projection,
        used_deg: plant.state().map(f64::to_degrees),
        initial_mode: plant.mode().name(),
        startup_events: plant.startup_events().iter().map(|e| e.kind.name()).collect(),
    };
    let cfg = PoincareConfig {
        mu: args.mu,
        x0,
        sim,
        transient_s: args.transient,
        record_s: args.record,
        classify: ClassifyConfig {
            tol: args.tol,
            max_period: args.max_period,
            chaos_threshold: args.chaos_threshold,
            ..ClassifyConfig::default()
        },
        lyapunov: LyapunovConfig { d0: args.lyap_d0, iterations: args.lyap_iterations, skip: args.lyap_skip, ..LyapunovConfig::default() },
        max_return_s: 10.0,
        section_depth: args.section_depth,
    };
    Ok((cfg, grid(v_min, v_max, args.v_step), ic))
}

/// Runs `sil-host poincare`.
///
/// # Errors
/// [`CliError::BadInput`]/[`CliError::Param`]/[`CliError::Sim`] (exit 2) for bad
/// options or initial conditions, before anything is written; [`CliError::Sim`]
/// (exit 1) when some belt speed failed (everything is written first);
/// [`CliError::Io`]/[`CliError::Plot`] when writing fails.
pub fn run(args: &PoincareArgs) -> Result<(), CliError> {
    let (cfg, grid, ic) = validated(args)?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| CliError::BadInput(format!("cannot start {threads} worker threads: {e}")))?;
    let mut out = OutputSet::new(&args.output.out)?;

    let progress = progress_bar(grid.len() as u64, "poincare", "belt speeds", args.output.json);
    let started = Instant::now();
    let results: Vec<PointResult> = pool.install(|| {
        grid.par_iter()
            .map(|&v| {
                let r = poincare::analyse(v, &cfg);
                progress.inc(1);
                r
            })
            .collect()
    });
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();

    let section: Vec<SectionRow> = results
        .iter()
        .flat_map(|r| {
            r.crossings.iter().map(move |c| SectionRow {
                v_belt: r.v_belt,
                t: c.t,
                theta1: c.x[0],
                theta1_deg: c.x[0].to_degrees(),
                theta1_dot: c.x[1],
                theta2: c.x[2],
                theta2_dot: c.x[3],
                kind: c.kind.name(),
                mode: c.mode.name(),
            })
        })
        .collect();
    write_csv(&mut out, "section.csv", &section)?;
    let rows: Vec<ClassRow> = results.iter().map(ClassRow::from).collect();
    write_csv(&mut out, "classes.csv", &rows)?;
    let dir = out.dir().to_path_buf();
    let json_err = |name: &str| {
        let path = dir.join(name);
        move |e: serde_json::Error| CliError::Io { path, source: e.into() }
    };
    let classes_json = serde_json::to_string_pretty(&results).map_err(json_err("classes.json"))?;
    out.write_bytes("classes.json", classes_json.as_bytes())?;
    let svg = out.stage("bifurcation.svg");
    draw_bifurcation(&svg, &cfg, &ic.name, &results)?;
    let svg = out.stage("lyapunov.svg");
    draw_lyapunov(&svg, &cfg, &results)?;

    let mut counts = ClassCounts::default();
    for r in &results {
        *match r.class {
            Class::Equilibrium => &mut counts.equilibrium,
            Class::Settling => &mut counts.settling,
            Class::Periodic => &mut counts.periodic,
            Class::Chaotic => &mut counts.chaotic,
            Class::Aperiodic => &mut counts.aperiodic,
            Class::Failed => &mut counts.failed,
        } += 1;
    }
    let mut point_walls: Vec<f64> = results.iter().map(|r| r.wall_s).collect();
    point_walls.sort_by(f64::total_cmp);
    let files = ["section.csv", "classes.csv", "classes.json", "bifurcation.svg", "lyapunov.svg", "summary.json"];
    let summary = Summary {
        status: if counts.failed > 0 { "failed" } else { "ok" },
        mu: cfg.mu,
        initial_condition: ic,
        v_belt_range: [grid[0], grid[grid.len() - 1]],
        v_step: args.v_step,
        grid_points: grid.len(),
        transient_s: cfg.transient_s,
        record_s: cfg.record_s,
        sim: cfg.sim,
        classify: cfg.classify,
        lyapunov: cfg.lyapunov,
        section_depth: cfg.section_depth,
        max_return_s: cfg.max_return_s,
        counts,
        bands: poincare::bands(&results),
        section_points: section.len(),
        threads,
        wall_s,
        median_point_wall_s: point_walls[point_walls.len() / 2],
        files: files.iter().map(|f| out.path(f).display().to_string()).collect(),
    };
    let json = out.write_json("summary.json", &summary)?;
    out.commit()?;

    if args.output.json {
        println!("{json}");
    } else {
        print_human(&summary);
    }
    match results.iter().find(|r| r.class == Class::Failed) {
        Some(r) => Err(CliError::PartFailed(format!(
            "{} belt speed(s) failed (written with class `failed`), the first at v_belt = {} m/s: {}",
            summary.counts.failed,
            r.v_belt,
            r.error.as_deref().unwrap_or("")
        ))),
        None => Ok(()),
    }
}

fn band_name(b: &Band) -> String {
    match (b.class, b.period) {
        (Class::Periodic, Some(p)) => format!("period-{p}"),
        (c, _) => c.name().to_string(),
    }
}

fn print_human(s: &Summary) {
    let mut o = std::io::stdout().lock();
    let ic = &s.initial_condition;
    let _ = writeln!(
        o,
        "Poincare section theta1_dot = 0 (upward), open loop u = 0, mu = {}, from {} (tip {}), v_belt in [{}, {}] m/s step {} ({} points)",
        s.mu,
        ic.name,
        if ic.projection.projected { "projected onto the belt" } else { "as given" },
        s.v_belt_range[0],
        s.v_belt_range[1],
        s.v_step,
        s.grid_points
    );
    let _ = writeln!(o, "transient {} s, record {} s; {} section points", s.transient_s, s.record_s, s.section_points);
    let c = &s.counts;
    let _ = writeln!(
        o,
        "classes: periodic {} | chaotic {} | aperiodic {} | settling {} | equilibrium {} | failed {}",
        c.periodic, c.chaotic, c.aperiodic, c.settling, c.equilibrium, c.failed
    );
    let _ = writeln!(o, "bands (v_belt from, to, points):");
    for b in &s.bands {
        let _ = writeln!(o, "  {:>8.4} .. {:>8.4} m/s  {:<12} ({} points)", b.v_belt_min, b.v_belt_max, band_name(b), b.points);
    }
    let _ = writeln!(o, "wall {:.1} s on {} threads (median {:.3} s per belt speed)", s.wall_s, s.threads, s.median_point_wall_s);
    let _ = writeln!(o, "wrote {}", s.files.join(", "));
}

/// Colour and legend label of a result's class.
fn class_style(r: &PointResult) -> (RGBColor, &'static str) {
    match (r.class, r.period) {
        (Class::Periodic, Some(1)) => (colors::BLUE, "period 1"),
        (Class::Periodic, Some(2)) => (colors::GREEN, "period 2"),
        (Class::Periodic, Some(3 | 4)) => (colors::ORANGE, "period 3-4"),
        (Class::Periodic, _) => (colors::PURPLE, "period >= 5"),
        (Class::Chaotic, _) => (colors::RED, "chaotic"),
        (Class::Aperiodic, _) => (colors::GREY, "aperiodic"),
        (Class::Settling, _) => (RGBColor(190, 190, 190), "settling"),
        (Class::Equilibrium, _) => (BLACK, "equilibrium (final theta1)"),
        (Class::Failed, _) => (RGBColor(255, 0, 255), "failed"),
    }
}

fn draw_bifurcation(path: &Path, cfg: &PoincareConfig, x0_name: &str, results: &[PointResult]) -> Result<(), CliError> {
    let err = plot_err(path);
    let v_lo = results.first().map_or(-1.0, |r| r.v_belt);
    let v_hi = results.last().map_or(0.0, |r| r.v_belt);
    let pad = ((v_hi - v_lo) * 0.02).max(1e-3);
    // (v_belt, theta1 in degrees, style) for every section point, and the final
    // theta1 of the belt speeds without crossings.
    let mut pts: Vec<(f64, f64, RGBColor, &'static str)> = Vec::new();
    for r in results {
        let (c, label) = class_style(r);
        if r.class == Class::Equilibrium {
            if r.final_theta1.is_finite() {
                pts.push((r.v_belt, r.final_theta1.to_degrees(), c, label));
            }
        } else {
            pts.extend(r.crossings.iter().map(|x| (r.v_belt, x.x[0].to_degrees(), c, label)));
        }
    }
    let (mut lo, mut hi) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if !lo.is_finite() {
        (lo, hi) = (-1.0, 1.0);
    }
    // One marker per pixel row and belt speed (the figure is 750 px high): a
    // periodic orbit repeats its points hundreds of times.
    let resolution = (hi - lo).max(1e-9) / 1500.0;
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup_by(|b, a| a.0 == b.0 && (b.1 - a.1).abs() < resolution);
    let ypad = ((hi - lo) * 0.05).max(0.5);
    let root = SVGBackend::new(path, (1200, 750)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let title = format!("Poincare section theta1_dot = 0 (upward), open loop, mu = {}, from {x0_name}", cfg.mu);
    let axes = plot::Axes {
        caption: Some((title, 22)),
        x: (v_lo - pad)..(v_hi + pad),
        y: (lo - ypad)..(hi + ypad),
        x_desc: "v_belt (m/s)",
        y_desc: "theta1 at the section (deg)",
        x_label_area: 45,
        y_label_area: 70,
        margin: 12,
    };
    let mut chart = plot::xy_chart(&root, &axes).map_err(|e| err(&e))?;
    let mut labels: Vec<&'static str> = pts.iter().map(|p| p.3).collect();
    labels.sort_unstable();
    labels.dedup();
    for label in labels {
        let color = pts.iter().find(|p| p.3 == label).map_or(BLACK, |p| p.2);
        let series = pts.iter().filter(|p| p.3 == label).map(|p| Circle::new((p.0, p.1), 1, color.filled()));
        chart.draw_series(series).map_err(|e| err(&e))?.label(label).legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    plot::legend_upper_right(&mut chart).map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

fn draw_lyapunov(path: &Path, cfg: &PoincareConfig, results: &[PointResult]) -> Result<(), CliError> {
    let err = plot_err(path);
    let pts: Vec<(f64, f64, RGBColor, &'static str)> = results
        .iter()
        .filter_map(|r| {
            let (c, label) = class_style(r);
            r.lyapunov.filter(|l| l.per_iteration.is_finite()).map(|l| (r.v_belt, l.per_iteration, c, label))
        })
        .collect();
    let v_lo = results.first().map_or(-1.0, |r| r.v_belt);
    let v_hi = results.last().map_or(0.0, |r| r.v_belt);
    let pad = ((v_hi - v_lo) * 0.02).max(1e-3);
    let (mut lo, mut hi) = pts.iter().fold((0.0f64, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if hi - lo < 1e-3 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let ypad = (hi - lo) * 0.05;
    let root = SVGBackend::new(path, (1200, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let title = format!("largest Lyapunov exponent of the section map, mu = {} (chaotic above {})", cfg.mu, cfg.classify.chaos_threshold);
    let axes = plot::Axes {
        caption: Some((title, 20)),
        x: (v_lo - pad)..(v_hi + pad),
        y: (lo - ypad)..(hi + ypad),
        x_desc: "v_belt (m/s)",
        y_desc: "lambda per crossing",
        x_label_area: 45,
        y_label_area: 70,
        margin: 12,
    };
    let mut chart = plot::xy_chart(&root, &axes).map_err(|e| err(&e))?;
    chart.draw_series(LineSeries::new([(v_lo - pad, 0.0), (v_hi + pad, 0.0)], BLACK.mix(0.5).stroke_width(1))).map_err(|e| err(&e))?;
    let mut labels: Vec<&'static str> = pts.iter().map(|p| p.3).collect();
    labels.sort_unstable();
    labels.dedup();
    for label in labels {
        let color = pts.iter().find(|p| p.3 == label).map_or(BLACK, |p| p.2);
        chart
            .draw_series(pts.iter().filter(|p| p.3 == label).map(|p| Circle::new((p.0, p.1), 2, color.filled())))
            .map_err(|e| err(&e))?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
