//! The outputs of `sil-host modes` other than the figure: `modes.csv`, the JSON document and the human summary.

use super::branch_label;
use crate::error::Error;
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

// `modes.csv`: the columns serde writes, declared (CSV reader, Arrow schema).
tables::declare!(CsvRow {
    theta1_rad: f64,
    theta1_deg: f64,
    theta1_dot: f64,
    theta2_rad: f64,
    b: f64,
    p: f64,
    z_r_dot: f64,
    mode: str,
    theta2_dot: f64,
    branch: str,
});

/// `Some(x)` when `x` is finite: an empty cell for a quantity the point does not have.
pub fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Writes the map as CSV (one row per grid point, `theta1` outer, `theta1_dot`
/// inner): `theta1_rad, theta1_deg, theta1_dot (rad/s), theta2_rad, b (m/s^2),
/// p (1/kg), z_r_dot (m/s), mode, theta2_dot (rad/s), branch` (`up`/`down`, the
/// elbow branch of the configuration); quantities that do not exist for the
/// point are empty.
///
/// # Errors
/// [`Error::Io`] when writing fails.
pub fn write_csv<W: Write>(map: &ModeMap, w: W, path: &Path) -> Result<(), Error> {
    let ioe = |e: csv::Error| Error::Io { path: path.to_path_buf(), source: std::io::Error::other(e) };
    let mut wr = csv::Writer::from_writer(w);
    for row in csv_rows(map) {
        wr.serialize(row).map_err(ioe)?;
    }
    wr.flush().map_err(|source| Error::Io { path: path.to_path_buf(), source })
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

/// The count of one contact mode over the grid.
#[derive(Serialize)]
pub struct JsonCount {
    /// The mode's name.
    pub mode: &'static str,
    /// Grid points in the mode.
    pub count: usize,
    /// Fraction of the grid.
    pub fraction_of_grid: f64,
    /// Fraction of the points with the tip on the belt (neither unreachable nor singular).
    pub fraction_of_on_belt: Option<f64>,
}

/// The JSON document of `modes` (`--json`): the settings, the counts per mode and the boundaries.
#[derive(Serialize)]
pub struct JsonSummary<'a> {
    /// The experiment, as docs/model.md names it.
    pub experiment: &'static str,
    /// Friction coefficient `mu`.
    pub mu: f64,
    /// Belt speed `v_belt`, m/s.
    pub v_belt: f64,
    /// The requested branch; `None` when `theta2_sign` is plus/minus (branch ignored).
    pub branch: Option<&'static str>,
    /// Which root of `theta2` the map follows.
    pub theta2_sign: Theta2Sign,
    /// That rule in words.
    pub theta2_rule: String,
    /// `theta1` range, degrees.
    pub theta1_deg_range: [f64; 2],
    /// `theta1_dot` range, rad/s.
    pub theta1_dot_range: [f64; 2],
    /// Grid size, `[theta1, theta1_dot]` points.
    pub grid: [usize; 2],
    /// Grid points.
    pub points: usize,
    /// Points with the tip on the belt (neither unreachable nor singular).
    pub on_belt_points: usize,
    /// The counts per mode.
    pub counts: Vec<JsonCount>,
    /// The zeros of `p` in the `theta1` range, with where each is a boundary.
    pub p_zero: &'a [PZero],
    /// Points located on the `b = 0` curves.
    pub b_zero_curve_points: usize,
    /// Files written.
    pub files: &'a [String],
    /// The parameters used (paper Table I with `--set`, `mu`, `v_belt`; SI, radians).
    pub params: shared::Params<f64>,
}

/// The JSON document of `--json` for the map, listing `files`.
pub fn summary<'a>(map: &'a ModeMap, files: &'a [String]) -> impl Serialize + 'a {
    json_summary(map, files)
}

/// The JSON document of the map, typed (what [`summary`] returns), listing `files`.
pub fn json_summary<'a>(map: &'a ModeMap, files: &'a [String]) -> JsonSummary<'a> {
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
