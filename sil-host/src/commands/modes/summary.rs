//! The outputs of `sil-host modes` other than the figure: `modes.csv`, the JSON document and the human summary.

use super::figures::branch_label;
use crate::error::CliError;
use analyses::modes::*;
use nalgebra::Vector2;
use serde::Serialize;
use shared::ElbowBranch;
use std::{io::Write, path::Path};

/// One row of `modes.csv`: a grid point; quantities that do not exist for the
/// point (unreachable, singular) are `None` (empty in the CSV).
#[derive(Debug, Clone, Serialize)]
pub struct CsvRow {
    /// `theta1`, rad.
    pub theta1_rad: f64,
    /// `theta1`, degrees.
    pub theta1_deg: f64,
    /// `theta1_dot`, rad/s.
    pub theta1_dot: f64,
    /// `theta2` putting the tip on the belt, rad.
    pub theta2_rad: Option<f64>,
    /// `b` (paper eq. 6), m/s^2.
    pub b: Option<f64>,
    /// `p` (paper eq. 7) for the slip direction of `z_r_dot`, 1/kg.
    pub p: Option<f64>,
    /// `z_r_dot = z_t_dot - v_belt`, m/s.
    pub z_r_dot: Option<f64>,
    /// `sliding`, `flight`, `indeterminate`, `inconsistent`, `unreachable` or `singular`.
    pub mode: &'static str,
    /// `theta2_dot` keeping the tip on the belt, rad/s.
    pub theta2_dot: Option<f64>,
    /// Elbow branch of the configuration (`up`, `down`).
    pub branch: Option<&'static str>,
}

pub(crate) fn finite(x: f64) -> Option<f64> {
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
    for row in csv_rows(map) {
        wr.serialize(row).map_err(ioe)?;
    }
    wr.flush().map_err(|source| CliError::Io { path: path.to_path_buf(), source })
}

/// The rows of `modes.csv`, one per grid point, `theta1` outer, `theta1_dot` inner.
pub fn csv_rows(map: &ModeMap) -> impl Iterator<Item = CsvRow> + '_ {
    let n2 = map.theta1_dot.len();
    map.points.iter().enumerate().map(move |(k, pt)| {
        let (t1, w1) = (map.theta1[k / n2], map.theta1_dot[k % n2]);
        CsvRow {
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
        }
    })
}

#[derive(Serialize)]
pub(crate) struct JsonCount {
    pub(crate) mode: &'static str,
    pub(crate) count: usize,
    pub(crate) fraction_of_grid: f64,
    /// Fraction of the points with the tip on the belt (neither unreachable nor singular).
    pub(crate) fraction_of_on_belt: Option<f64>,
}

#[derive(Serialize)]
pub(crate) struct JsonSummary<'a> {
    pub(crate) experiment: &'static str,
    pub(crate) mu: f64,
    pub(crate) v_belt: f64,
    /// The requested branch; `None` when `theta2_sign` is plus/minus (branch ignored).
    pub(crate) branch: Option<&'static str>,
    pub(crate) theta2_sign: Theta2Sign,
    pub(crate) theta2_rule: String,
    pub(crate) theta1_deg_range: [f64; 2],
    pub(crate) theta1_dot_range: [f64; 2],
    pub(crate) grid: [usize; 2],
    pub(crate) points: usize,
    pub(crate) on_belt_points: usize,
    pub(crate) counts: Vec<JsonCount>,
    pub(crate) p_zero: &'a [PZero],
    pub(crate) b_zero_curve_points: usize,
    pub(crate) files: &'a [String],
    /// The parameters used (paper Table I with `--set`, `mu`, `v_belt`; SI, radians).
    pub(crate) params: shared::Params<f64>,
}

/// The JSON document of `--json` for the map, listing `files`.
pub fn summary<'a>(map: &'a ModeMap, files: &'a [String]) -> impl Serialize + 'a {
    json_summary(map, files)
}

pub(crate) fn json_summary<'a>(map: &'a ModeMap, files: &'a [String]) -> JsonSummary<'a> {
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
        params: map.params,
        files,
    }
}

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
