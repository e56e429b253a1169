//! The figures of `sil-host zmax`: the run at the limit of each case.

use crate::error::CliError;
use analyses::zmax::{Bisection, Search};
use figures::plot;
use figures::plot::symbols::{Z_T_REF, Z_T_SLIDING};

pub(crate) fn draw(path: &std::path::Path, s: &Search) -> Result<(), CliError> {
    let rows = &s.limit_trace;
    let t_end = rows.last().map_or(1.0, |r| r.t).max(1e-9);
    let samples: Vec<plot::HistorySample> = rows
        .iter()
        .map(|r| plot::HistorySample { t: r.t, z_t: r.z_t, z_t_ref: r.z_t_ref, f_n: r.f_n, u: [r.u1, r.u2], mode: r.mode })
        .collect();
    let panels = plot::history_panels(&samples, false);
    let c = &s.combination;
    let what = match s.bisection {
        Bisection::Found { lo, hi, .. } => format!("at the limit {Z_T_REF} = {lo:.4} m (fails at {hi:.4} m)"),
        Bisection::LowerFails { lo, .. } => format!("lifts off already at the lowest target {lo:.4} m"),
        Bisection::UpperReached { hi, .. } => format!("reaches the highest target {hi:.4} m"),
    };
    let title = format!("{Z_T_SLIDING}: {} from x0{}, {}: {what}", c.controller.name(), c.x0.letter(), c.setting.name());
    plot::time_panels(path, &title, (0.0, t_end), &panels).map_err(CliError::from)
}
