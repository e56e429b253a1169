//! Closed-loop time histories for figures (`run`, `pil`, `zmax`): the samples, a
//! fixed-memory envelope of a run of any length, and their four panels.

use rig::envelope::Envelope;

use super::{
    colors,
    symbols::{F_N, TAU, Z_T, Z_T_REF, axis},
    time_panels::{Panel, Series},
};

/// One sample of a closed-loop time history, for [`history_panels`].
#[derive(Debug, Clone, Copy)]
pub struct HistorySample {
    /// Time, s.
    pub t: f64,
    /// Tip position `z_t`, m.
    pub z_t: f64,
    /// Its reference `z_t*`, m.
    pub z_t_ref: f64,
    /// Normal force `f_n`, N.
    pub f_n: f64,
    /// Motor torques `[u1, u2]`, N m.
    pub u: [f64; 2],
    /// Contact mode name (`sliding`, `flight`, `sticking`).
    pub mode: &'static str,
}

/// The four panels of a closed-loop figure (`run`, `pil`, `zmax`): tip position
/// against its reference, normal force, torques (drawn as steps when `step_torques`,
/// a zero-order hold) and contact mode, against time.
pub fn history_panels(samples: &[HistorySample], step_torques: bool) -> [Panel<'static>; 4] {
    let col = |f: fn(&HistorySample) -> f64| samples.iter().map(|r| (r.t, f(r))).collect::<Vec<_>>();
    let columns = [col(|r| r.z_t), col(|r| r.z_t_ref), col(|r| r.f_n), col(|r| r.u[0]), col(|r| r.u[1]), col(|r| mode_code(r.mode))];
    panels_of_columns(columns, step_torques)
}

/// [`history_panels`] from the columns `z_t`, `z_t*`, `f_n`, `u1`, `u2` and the
/// mode code ([`mode_code`]), each as `(t, value)` points.
fn panels_of_columns(columns: [Vec<(f64, f64)>; 6], step_torques: bool) -> [Panel<'static>; 4] {
    let [z_t, z_t_ref, f_n, u1, u2, mode] = columns;
    [
        Panel::numeric(axis(Z_T, "m"), vec![Series::line(Z_T, z_t, colors::BLUE), Series::reference(Z_T_REF, z_t_ref, colors::GREY)]),
        Panel::numeric(axis(F_N, "N"), vec![Series::line(F_N, f_n, colors::GREEN)]),
        Panel::numeric(
            "torque (N m)",
            vec![
                Series { step: step_torques, ..Series::line(TAU[0], u1, colors::BLUE) },
                Series { step: step_torques, ..Series::line(TAU[1], u2, colors::RED) },
            ],
        ),
        mode_panel_of_points(mode),
    ]
}

/// A closed-loop time history kept for its figure in fixed memory while a run
/// of any length goes: one [`Envelope`] per curve (every sample up to
/// [`Envelope::DEFAULT_CAPACITY`], then the minimum and maximum of even
/// buckets of samples, so impacts and hops stay visible).
#[derive(Debug, Clone, Default)]
pub struct HistoryEnvelope {
    /// `z_t`, `z_t*`, `f_n`, `u1`, `u2` and the mode code, against time.
    curves: [Envelope; 6],
}

impl HistoryEnvelope {
    /// Adds the next sample (in time order).
    #[inline]
    pub fn push(&mut self, s: &HistorySample) {
        let values = [s.z_t, s.z_t_ref, s.f_n, s.u[0], s.u[1], mode_code(s.mode)];
        for (curve, y) in self.curves.iter_mut().zip(values) {
            curve.push(s.t, y);
        }
    }

    /// The four panels of [`history_panels`], from the kept points.
    pub fn panels(&self, step_torques: bool) -> [Panel<'static>; 4] {
        panels_of_columns(self.curves.each_ref().map(Envelope::points), step_torques)
    }
}

/// The contact mode's code in figures: 0 flight, 1 sliding, 2 sticking.
pub fn mode_code(mode: &str) -> f64 {
    match mode {
        "sliding" => 1.0,
        "sticking" => 2.0,
        _ => 0.0,
    }
}

/// The contact-mode panel: a step curve of 0 flight, 1 sliding, 2 sticking
/// against time, from `(t, mode name)` samples.
pub fn mode_panel<'s>(samples: impl Iterator<Item = (f64, &'s str)>) -> Panel<'static> {
    mode_panel_of_points(samples.map(|(t, mode)| (t, mode_code(mode))).collect())
}

/// The names of the contact modes by code ([`mode_code`]).
pub const MODE_NAMES: [&str; 3] = ["flight", "sliding", "sticking"];

/// The contact-mode panel from `(t, mode code)` points ([`mode_code`]): a step
/// curve on a categorical axis (flight, sliding, sticking).
pub fn mode_panel_of_points(points: Vec<(f64, f64)>) -> Panel<'static> {
    Panel {
        y_label: "contact mode".into(),
        series: vec![Series { step: true, ..Series::line("mode", points, colors::PURPLE) }],
        y_range: None,
        categories: Some(&MODE_NAMES),
        between_samples: None,
    }
}
