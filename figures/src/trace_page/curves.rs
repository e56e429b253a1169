//! The page's plots: every curve kept in fixed memory as a min/max envelope
//! ([`rig::Envelope`]), so a run of any length gives a bounded page and no
//! sample's extreme (an impact's force, a hop's height) is lost, only thinned
//! to the lowest and highest of each bucket.

use rig::Envelope;
use serde_json::{Value, json};

use crate::plot::{
    colors,
    symbols::{F_N, TAU, Z_N, Z_T, Z_T_REF},
};

/// Buckets per curve: at most twice this many points, more than the plots'
/// pixel columns, so the min/max decimation is finer than a pixel.
pub const CURVE_BUCKETS: usize = 2048;

/// One sample of the plotted signals.
#[derive(Debug, Clone, Copy)]
pub struct CurveSample {
    /// Time, s.
    pub t: f64,
    /// Tip position `[z_t, z_n]`, m.
    pub z: [f64; 2],
    /// Contact force `[f_t, f_n]`, N.
    pub force: [f64; 2],
    /// Contact mode code (0 flight, 1 sliding, 2 sticking).
    pub mode: u8,
    /// Reference `z_t*`, m (NaN when there is none: open loop).
    pub z_t_ref: f64,
    /// Motor torques `[u1, u2]`, N m (NaN when there are none: open loop).
    pub u: [f64; 2],
}

/// The curves of the page's five panels (tip position, tip height, forces,
/// torques, contact mode), each a min/max envelope.
#[derive(Debug, Clone)]
pub struct Curves {
    /// `z_t`, `z_t*`, `z_n + H`, `f_n`, `f_t`, `u1`, `u2`, mode.
    env: [Envelope; 8],
    /// Height of the base above the belt `H`, m.
    h: f64,
    closed_loop: bool,
}

impl Curves {
    /// Empty curves for a run whose base is `h` (m) above the belt; a
    /// `closed_loop` run also plots `z_t*` and the torques.
    pub fn new(h: f64, closed_loop: bool) -> Self {
        Self { env: std::array::from_fn(|_| Envelope::with_capacity(CURVE_BUCKETS)), h, closed_loop }
    }

    /// Adds the next sample (in time order).
    pub fn push(&mut self, s: &CurveSample) {
        let ys = [s.z[0], s.z_t_ref, s.z[1] + self.h, s.force[1], s.force[0], s.u[0], s.u[1], f64::from(s.mode)];
        for (e, y) in self.env.iter_mut().zip(ys) {
            e.push(s.t, y);
        }
    }

    /// Samples per bucket of the thinned curves (1: every sample kept).
    pub fn samples_per_bucket(&self) -> u64 {
        self.env[0].samples_per_bucket()
    }

    /// The panels as the page's JSON: `[{label, series: [{name, color, dash,
    /// step, t: [s], y: [...]}], categories?}]`, values as `f32` (NaN as null).
    pub fn panels(&self) -> Value {
        let series = |i: usize, name: &str, color: plotters::style::RGBColor, dash: bool, step: bool| {
            let points = self.env[i].points();
            let t: Vec<f32> = points.iter().map(|p| p.0 as f32).collect();
            let y: Vec<f32> = points.iter().map(|p| p.1 as f32).collect();
            json!({ "name": name, "color": hex(color), "dash": dash, "step": step, "t": t, "y": y })
        };
        let mut tip = vec![series(0, Z_T, colors::BLUE, false, false)];
        if self.closed_loop {
            tip.push(series(1, Z_T_REF, colors::GREY, true, true));
        }
        let mut panels = vec![
            json!({ "label": format!("{Z_T} (m)"), "series": tip }),
            json!({ "label": format!("{Z_N} + H (m)"), "series": [series(2, &format!("tip height {Z_N} + H"), colors::BLUE, false, false)] }),
            // The impacts' normal impulses as stems (the page's events), on their own scale.
            json!({ "label": "force (N)", "impulses": true, "series": [
                series(3, F_N, colors::GREEN, false, false),
                series(4, "fₜ", colors::ORANGE, true, false),
            ] }),
        ];
        if self.closed_loop {
            panels.push(json!({ "label": "torque (N m)", "series": [
                series(5, TAU[0], colors::BLUE, false, true),
                series(6, TAU[1], colors::RED, true, true),
            ] }));
        }
        panels.push(json!({
            "label": "mode",
            "series": [series(7, "contact mode", colors::PURPLE, false, true)],
            "categories": crate::plot::MODE_NAMES,
        }));
        Value::Array(panels)
    }
}

/// `#rrggbb` of a colour.
pub fn hex(c: plotters::style::RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, f_n: f64) -> CurveSample {
        CurveSample { t, z: [0.1, -0.3], force: [0.0, f_n], mode: 1, z_t_ref: 0.1, u: [0.0, 0.0] }
    }

    /// A one-sample spike in a long run survives the thinning.
    #[test]
    fn a_spike_survives_the_thinning_and_the_points_are_bounded() {
        let mut c = Curves::new(0.3775, true);
        for k in 0..100_000 {
            c.push(&sample(k as f64 * 1e-3, if k == 54_321 { 500.0 } else { 10.0 }));
        }
        assert!(c.samples_per_bucket() > 1);
        let panels = c.panels();
        let f_n = &panels[2]["series"][0];
        let y = f_n["y"].as_array().unwrap();
        assert!(y.len() <= 2 * CURVE_BUCKETS, "{}", y.len());
        assert!(y.iter().any(|v| v.as_f64() == Some(500.0)), "the spike is kept");
        let h = panels[1]["series"][0]["y"][0].as_f64().unwrap();
        assert!((h - 0.0775).abs() < 1e-6, "height above the belt z_n + H: {h}");
        assert_eq!(panels.as_array().unwrap().len(), 5);
    }

    #[test]
    fn open_loop_has_no_torque_panel_nor_reference() {
        let mut c = Curves::new(0.3775, false);
        c.push(&CurveSample { z_t_ref: f64::NAN, u: [f64::NAN; 2], ..sample(0.0, 1.0) });
        let panels = c.panels();
        assert_eq!(panels.as_array().unwrap().len(), 4);
        assert_eq!(panels[0]["series"].as_array().unwrap().len(), 1);
    }
}
