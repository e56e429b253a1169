//! The figure of `sil-host simulate`: the trace against time (`trace.svg`), drawn
//! from a decimated copy kept in fixed memory while the trace is streamed.

use super::summary::TraceRow;
use crate::{
    error::CliError,
    plot::{self, Panel, Series, colors},
};
use rig::envelope::Envelope;
use shared::Params;

/// The curves of `trace.svg` (`z_t`, `z_n`, `f_n`, the mode code) against time,
/// each an [`Envelope`]: every row up to [`Envelope::DEFAULT_CAPACITY`], then the
/// minimum and maximum of even buckets of rows (bounces stay visible).
#[derive(Debug, Clone, Default)]
pub(crate) struct TraceCurves {
    curves: [Envelope; 4],
    t_end: Option<f64>,
}

impl TraceCurves {
    /// Adds the next row (in time order).
    pub(crate) fn push(&mut self, r: &TraceRow) {
        for (curve, y) in self.curves.iter_mut().zip([r.z_t, r.z_n, r.f_n, plot::mode_code(r.mode)]) {
            curve.push(r.t, y);
        }
        self.t_end = Some(r.t);
    }
}

pub(crate) fn draw_trace(path: &std::path::Path, params: &Params<f64>, name: &str, trace: &TraceCurves) -> Result<(), CliError> {
    let t_end = trace.t_end.unwrap_or(1.0).max(1e-9);
    let [z_t, z_n, f_n, mode] = trace.curves.each_ref().map(Envelope::points);
    let belt = -params.h;
    let panels = [
        Panel::numeric("z_t (m)", vec![Series::line("z_t", z_t, colors::BLUE)]),
        Panel::numeric(
            "z_n (m)",
            vec![Series::line("z_n", z_n, colors::ORANGE), Series::reference("belt -H", vec![(0.0, belt), (t_end, belt)], colors::GREY)],
        ),
        Panel::numeric("f_n (N)", vec![Series::line("f_n", f_n, colors::GREEN)]),
        plot::mode_panel_of_points(mode),
    ];
    let title = format!("open loop from {name}: mu = {}, v_belt = {} m/s", params.mu, params.v_belt);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
