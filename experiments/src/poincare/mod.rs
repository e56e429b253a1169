//! The one-parameter bifurcation diagram of the open loop (docs/model.md
//! experiment 4, the paper's Fig. 4), each belt speed classified by
//! [`analyses::poincare`]: the settings' check, the loop over the belt speeds
//! both fronts run ([`analyse_grid`]), the section and class rows and the summary.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use crate::{
    arm::parse_range,
    error::Error,
    settings::PoincareArgs,
    simulate::{chosen_initial_condition, summary::InitialCondition},
};
use analyses::poincare::{
    self, PoincareConfig, PointResult,
    classify::{Class, ClassifyConfig},
    lyapunov::LyapunovConfig,
};
use plant::initial;
use plant::{Plant, SimConfig};

pub mod summary;
use summary::*;

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

/// Checks `sil-host poincare`'s options: the analysis's configuration, the
/// belt-speed grid (m/s) and the initial condition as given and used.
///
/// # Errors
/// [`crate::error::Error::Analysis`]/[`crate::error::Error::Analysis`]/[`crate::error::Error::Analysis`]/[`crate::error::Error::Analysis`]
/// (exit 2) for bad options or initial conditions.
pub fn validated(args: &PoincareArgs) -> Result<(PoincareConfig, Vec<f64>, InitialCondition), Error> {
    let bad = |m: String| Err(Error::bad_input(m));
    // One speed `V`, or a range `MIN,MAX`.
    let (v_min, v_max) = match args.v_belt.0.as_slice() {
        [v] if v.is_finite() => (*v, *v),
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
    crate::arm::arm_params(&args.set, "poincare", &[], args.mu, v_min)?;
    let params = crate::arm::arm_params(&args.set, "poincare", &[], args.mu, v_max)?;
    let sim = SimConfig {
        rtol: args.rtol,
        atol: args.atol,
        impact_law: args.impact_law,
        e_n: args.e_n,
        iwc: args.iwc,
        singular: args.singular,
        ..SimConfig::default()
    };
    sim.validate()?;
    let (name, given_deg) = chosen_initial_condition(args.x0, args.x0_deg.as_ref())?;
    let x0 = initial::deg_to_state(given_deg);
    // The initial state must be acceptable to the plant (not below the belt, reachable).
    let plant = Plant::new(params, sim, x0, 0.0, [0.0, 0.0])?;
    let ic = InitialCondition::of(name, given_deg, &params, &plant);
    let cfg = PoincareConfig {
        mu: args.mu,
        params,
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

/// The rows of `section.csv`: every crossing of every belt speed, in grid order.
pub fn section_rows(results: &[PointResult]) -> Vec<SectionRow> {
    results
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
        .collect()
}

/// The command's failure when some belt speed failed (class `failed`): exit 1
/// after writing everything.
pub fn failure(summary: &Summary, results: &[PointResult]) -> Option<Error> {
    results.iter().find(|r| r.class == Class::Failed).map(|r| {
        Error::PartFailed(format!(
            "{} belt speed(s) failed (written with class `failed`), the first at v_belt = {} m/s: {}",
            summary.counts.failed,
            r.v_belt,
            r.error.as_deref().unwrap_or("")
        ))
    })
}

/// Analyses every belt speed of `grid` (m/s) on `pool`'s threads, calling
/// `done` after each; a speed not started when `stop` is set is left out. The
/// results come in grid order, with the wall time, s.
pub fn analyse_grid(
    pool: &rayon::ThreadPool,
    cfg: &PoincareConfig,
    grid: &[f64],
    stop: &AtomicBool,
    done: &(dyn Fn() + Sync),
) -> (Vec<PointResult>, f64) {
    let started = Instant::now();
    let results: Vec<Option<PointResult>> = pool.install(|| {
        grid.par_iter()
            .map(|&v| {
                if stop.load(Ordering::Relaxed) {
                    return None;
                }
                let r = poincare::analyse(v, cfg);
                done();
                Some(r)
            })
            .collect()
    });
    (results.into_iter().flatten().collect(), started.elapsed().as_secs_f64())
}

/// `summary.json` of the analysed `results` (one per speed of the grid, in
/// order) for the validated set-up (`cfg`, the grid, the initial condition),
/// computed on `threads` threads in `wall_s` s, listing `files`.
pub fn summary(
    args: &PoincareArgs,
    setup: (PoincareConfig, &[f64], InitialCondition),
    results: &[PointResult],
    threads: usize,
    wall_s: f64,
    files: Vec<String>,
) -> Summary {
    let (cfg, grid, ic) = setup;
    let mut counts = ClassCounts::default();
    for r in results {
        *match r.class {
            Class::Equilibrium => &mut counts.equilibrium,
            Class::Settling => &mut counts.settling,
            Class::Periodic => &mut counts.periodic,
            Class::Chaotic => &mut counts.chaotic,
            Class::Aperiodic => &mut counts.aperiodic,
            Class::Failed => &mut counts.failed,
            Class::Invalid => &mut counts.invalid,
        } += 1;
    }
    let mut validity = plant::Validity::default();
    for r in results {
        validity.add(&r.validity);
    }
    let mut point_walls: Vec<f64> = results.iter().map(|r| r.wall_s).collect();
    point_walls.sort_by(f64::total_cmp);
    Summary {
        status: if counts.failed > 0 { "failed" } else { "ok" },
        mu: cfg.mu,
        params: cfg.params,
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
        validity,
        bands: poincare::bands(results),
        section_points: results.iter().map(|r| r.crossings.len()).sum(),
        threads,
        wall_s,
        median_point_wall_s: point_walls.get(point_walls.len() / 2).copied().unwrap_or(f64::NAN),
        files,
    }
}
