//! The figure of `sil-host simulate`: the trace against time (`trace.svg`), drawn
//! from a decimated copy kept in fixed memory while the trace is streamed.

use super::summary::{EventRow, TraceRow};
use crate::error::CliError;
use figures::plot::symbols::{BELT_SPEED, F_N, MU, Z_N, Z_T, axis};
use figures::plot::{self, Panel, Series, colors};
use rig::envelope::Envelope;
use shared::Params;

/// The curves of `trace.svg` (`z_t`, `z_n`, `f_n`, the mode code) against time,
/// each an [`Envelope`]: every row up to [`Envelope::DEFAULT_CAPACITY`], then the
/// minimum and maximum of even buckets of rows (bounces stay visible).
#[derive(Debug, Clone, Default)]
pub(crate) struct TraceCurves {
    curves: [Envelope; 4],
    t_end: Option<f64>,
    impacts: Impacts,
}

/// The times of the impacts (touchdowns and impacts without collision), in fixed
/// memory: every impact up to [`Impacts::CAP`], then every second one kept, then
/// every fourth, ... (an even thinning, so that the markers still show where the
/// arm bounces), with the count of all.
#[derive(Debug, Clone, Default)]
struct Impacts {
    /// Kept times, s.
    times: Vec<f64>,
    /// Impacts seen.
    count: u64,
    /// One in `stride` impacts is kept.
    stride: u64,
}

impl Impacts {
    /// Times kept at most.
    const CAP: usize = 2000;

    fn push(&mut self, t: f64) {
        let stride = self.stride.max(1);
        if self.count.is_multiple_of(stride) {
            if self.times.len() == Self::CAP {
                // Keep every second one (those at multiples of the doubled stride).
                let mut i = 0;
                self.times.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride = stride * 2;
            }
            if self.count.is_multiple_of(self.stride.max(1)) {
                self.times.push(t);
            }
        }
        self.count += 1;
    }
}

impl TraceCurves {
    /// Adds the next row (in time order).
    pub(crate) fn push(&mut self, r: &TraceRow) {
        for (curve, y) in self.curves.iter_mut().zip([r.z_t, r.z_n, r.f_n, plot::mode_code(r.mode)]) {
            curve.push(r.t, y);
        }
        self.t_end = Some(r.t);
    }

    /// Notes the impacts among `events` (in time order), which happen between the
    /// samples and so show in no sampled curve.
    pub(crate) fn push_events(&mut self, events: &[EventRow]) {
        for e in events.iter().filter(|e| matches!(e.kind, "touchdown" | "impact_without_collision")) {
            self.impacts.push(e.t);
        }
    }
}

pub(crate) fn draw_trace(path: &std::path::Path, params: &Params<f64>, name: &str, trace: &TraceCurves) -> Result<(), CliError> {
    let t_end = trace.t_end.unwrap_or(1.0).max(1e-9);
    let [z_t, z_n, f_n, mode] = trace.curves.each_ref().map(Envelope::points);
    let belt = -params.h;
    let impacts = &trace.impacts;
    let mut z_n_series =
        vec![Series::line(Z_N, z_n, colors::ORANGE), Series::reference("belt, −H", vec![(0.0, belt), (t_end, belt)], colors::GREY)];
    let impact_label = match impacts.stride {
        0 | 1 => "impact".to_string(),
        k => format!("impact (1 in {k})"),
    };
    if impacts.count > 0 {
        z_n_series.push(Series::markers(&impact_label, impacts.times.iter().map(|&t| (t, belt)).collect(), colors::RED));
    }
    let mut mode_panel = plot::mode_panel_of_points(mode);
    if impacts.count > 0 {
        let s = if impacts.count == 1 { "" } else { "s" };
        mode_panel.between_samples = Some(format!("{} impact{s} between the samples, marked on {Z_N}", impacts.count));
    }
    let panels = [
        Panel::numeric(axis(Z_T, "m"), vec![Series::line(Z_T, z_t, colors::BLUE)]),
        Panel::numeric(axis(Z_N, "m"), z_n_series),
        Panel::numeric(axis(F_N, "N"), vec![Series::line(F_N, f_n, colors::GREEN)]),
        mode_panel,
    ];
    let title = format!("Open loop from {name}: {MU} = {}, {BELT_SPEED} {} m/s", params.mu, params.v_belt);
    plot::time_panels(path, &title, (0.0, t_end), &panels).map_err(CliError::from)
}
