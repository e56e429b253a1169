//! `sil-host modes`' human summary (the counts per mode, the `p = 0` and `b = 0` boundaries).

use analyses::modes::*;
use experiments::modes::summary::*;

/// The human summary printed by the command.
pub fn human_summary(map: &ModeMap) -> String {
    let files: [String; 0] = [];
    let s = json_summary(map, &files);
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
