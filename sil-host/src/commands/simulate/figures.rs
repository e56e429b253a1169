//! The figure of `sil-host simulate`: the trace against time (`trace.svg`).

use super::summary::TraceRow;
use crate::{
    error::CliError,
    plot::{self, Panel, Series, colors},
};
use shared::Params;

pub(crate) fn draw_trace(path: &std::path::Path, params: &Params<f64>, name: &str, trace: &[TraceRow]) -> Result<(), CliError> {
    let t_end = trace.last().map_or(1.0, |r| r.t).max(1e-9);
    let col = |f: fn(&TraceRow) -> f64| trace.iter().map(|r| (r.t, f(r))).collect::<Vec<_>>();
    let belt = -params.h;
    let panels = [
        Panel {
            y_label: "z_t (m)",
            series: vec![Series { label: "z_t", points: col(|r| r.z_t), color: colors::BLUE, step: false }],
            y_range: None,
        },
        Panel {
            y_label: "z_n (m)",
            series: vec![
                Series { label: "z_n", points: col(|r| r.z_n), color: colors::ORANGE, step: false },
                Series { label: "belt -H", points: vec![(0.0, belt), (t_end, belt)], color: colors::GREY, step: false },
            ],
            y_range: None,
        },
        Panel {
            y_label: "f_n (N)",
            series: vec![Series { label: "f_n", points: col(|r| r.f_n), color: colors::GREEN, step: false }],
            y_range: None,
        },
        plot::mode_panel(trace.iter().map(|r| (r.t, r.mode))),
    ];
    let title = format!("open loop from {name}: mu = {}, v_belt = {} m/s", params.mu, params.v_belt);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
