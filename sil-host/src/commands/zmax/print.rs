//! `sil-host zmax`'s table.

use std::io::Write;

use analyses::zmax::StopReason;
use experiments::zmax::summary::*;

pub(crate) fn print_table(s: &ZmaxSummary, written: &[std::path::PathBuf]) {
    let mut o = crate::stdout::out();
    let c = &s.criteria;
    let _ = writeln!(
        o,
        "Z_t,sliding (docs/model.md experiments 5 and 6): largest z_t* the tip slides to (within {} mm) with no lift-off (the paper's definition); tracking: largest z_t* also settled within {} mm over the last {} s; mu {}, v_belt {} m/s, move {} s, run {} s, bisection to {} mm",
        c.reach_tol_m * 1e3,
        c.settle_tol_m * 1e3,
        c.settle_window_s,
        s.base_scenario.plant.mu,
        s.base_scenario.plant.v_belt,
        c.move_time_s,
        c.duration_s,
        s.tol_m * 1e3
    );
    let _ = writeln!(
        o,
        "{:<8} {:<4} {:<8} {:>16} {:>10} {:>12} {:>8} {:>14} {:>12} {:>13} {:>16} {:>7} {:>8}",
        "control",
        "x0",
        "setting",
        "Z_t,sliding (m)",
        "error (mm)",
        "stop above",
        "paper",
        "tracking (m)",
        "stop above",
        "p = 0 at (m)",
        "theta1 max at (m)",
        "trials",
        "wall (s)"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    let reason = |r: Option<StopReason>| r.map_or("-".to_string(), |r| r.name().to_string());
    for r in &s.results {
        let paper = match analyses::paper::z_t_sliding(r.controller, r.x0) {
            Some(Some(v)) => format!("{v}"),
            Some(None) => "none".into(),
            None => "-".into(),
        };
        let _ = writeln!(
            o,
            "{:<8} {:<4} {:<8} {:>16} {:>10} {:>12} {:>8} {:>14} {:>12} {:>13} {:>16} {:>7} {:>8.2}",
            r.controller,
            format!("x0{}", r.x0),
            r.setting,
            limit_text(r.outcome, r.z_t_sliding_m, r.bracket_lo_m, r.bracket_hi_m),
            r.error_at_limit_m.map_or("-".into(), |e| format!("{:.1}", e * 1e3)),
            reason(r.stop_failing),
            paper,
            limit_text(r.tracking_outcome, r.z_t_tracking_m, r.bracket_lo_m, r.bracket_hi_m),
            reason(r.tracking_stop_failing),
            f(r.p_zero_end_m),
            f(r.theta1_fold_m),
            r.trials,
            r.wall_s
        );
    }
    for r in &s.results {
        if let (Some(why), Some(at)) = (&r.why_failing, r.first_failing_m.or(Some(r.bracket_lo_m))) {
            let _ = writeln!(o, "{} x0{} {}: Z_t,sliding fails at {at:.4} m: {why}", r.controller, r.x0, r.setting);
        }
        if let (Some(why), Some(at)) = (&r.tracking_why_failing, r.tracking_first_failing_m.or(Some(r.bracket_lo_m)))
            && r.tracking_first_failing_m != r.first_failing_m
        {
            let _ = writeln!(o, "{} x0{} {}: tracking fails at {at:.4} m: {why}", r.controller, r.x0, r.setting);
        }
    }
    let _ = writeln!(
        o,
        "error: max |z_t - z_t*| over the settle window at Z_t,sliding; stop above: why the first target above the limit failed"
    );
    let _ = writeln!(o, "samples: {}", s.samples);
    for d in &s.distributions {
        let _ = writeln!(
            o,
            "  {} x0{} {} over {} seeds: Z_t,sliding median [quartiles], range {}{}; tracking {}",
            d.controller,
            d.x0,
            d.setting,
            d.seeds,
            d.z_t_sliding.describe(),
            if d.z_t_sliding.none > 0 { format!(" ({} seeds with none)", d.z_t_sliding.none) } else { String::new() },
            d.z_t_tracking.describe()
        );
    }
    let _ = writeln!(
        o,
        "p = 0 at: end of the admissible range on the branch (paper Table II); theta1 max at: the fold of theta1 along the belt, which the PID (on theta1 alone) cannot pass"
    );
    let _ = writeln!(o, "{}", s.paper);
    let _ = writeln!(o, "validity (all trials): {}", s.validity);
    let invalid: u32 = s.results.iter().map(|r| r.invalid_trials).sum();
    if invalid > 0 {
        let _ = writeln!(o, "INVALID: {invalid} trials violate the model (counted as not free of lift-off; trials.csv lists them)");
    }
    let _ = writeln!(
        o,
        "wall time {:.1} s; wrote {}",
        s.wall_s,
        written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
}
