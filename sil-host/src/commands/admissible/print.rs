//! `sil-host admissible`'s human summary (the admissible intervals as a table).

use analyses::admissible::{AdmissibleReport, MIRROR_TOL_M, ROOT_TOL_M, SCAN_STEPS};
use experiments::admissible::summary::fmt_intervals;
use shared::{ElbowBranch, SlipDirection};

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
