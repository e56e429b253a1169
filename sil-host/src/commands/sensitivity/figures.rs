//! The study's figures: one per headline result, a panel per open choice that
//! enters it, the result against the choice's values (the default marked).

use std::path::Path;

use analyses::sensitivity::{ChoiceResult, Dimension, Study};
use analyses::zmax::Combination;
use plotters::prelude::*;

use crate::error::CliError;
use crate::plot::{Axes, legend_upper_right, plot_err, xy_chart};

/// A series of a figure: its label, its value under a choice (given the series'
/// index), and that index.
pub type SeriesOf = (String, fn(&ChoiceResult, usize) -> Option<f64>, usize);

/// One figure: its file, title, y label, and its series (name and value under a choice).
pub struct Figure {
    /// File name.
    pub file: &'static str,
    /// Title.
    pub title: &'static str,
    /// Y-axis label with units.
    pub y_desc: &'static str,
    /// The series: a label and the value under a choice (`None`: not computed, or no value).
    pub series: fn() -> Vec<SeriesOf>,
}

fn open<T>(r: &ChoiceResult, f: impl Fn(&analyses::sensitivity::OpenLoop) -> T) -> Option<T> {
    r.open_loop.as_ref().map(f)
}

/// The figures, one per headline result.
pub const FIGURES: [Figure; 5] = [
    Figure {
        file: "critical_mu.svg",
        title: "critical mu (open loop)",
        y_desc: "critical mu",
        series: || {
            vec![
                ("x0a".into(), |r, _| open(r, |o| o.critical_mu_x0a).flatten().or(r.open_loop.as_ref().map(|_| f64::NAN)), 0),
                ("x0d".into(), |r, _| open(r, |o| o.critical_mu_x0d).flatten().or(r.open_loop.as_ref().map(|_| f64::NAN)), 0),
            ]
        },
    },
    Figure {
        file: "band_mu06_x0a.svg",
        title: "persistent bouncing at mu = 0.6 from x0a: main interval (open loop)",
        y_desc: "v_belt (m/s)",
        series: || {
            vec![
                ("from".into(), |r, _| open(r, |o| o.band_x0a_mu06.map(|b| b[0])).flatten(), 0),
                ("to".into(), |r, _| open(r, |o| o.band_x0a_mu06.map(|b| b[1])).flatten(), 0),
            ]
        },
    },
    Figure {
        file: "x0d_bounces.svg",
        title: "does x0d ever bounce? (open loop; 1 = yes)",
        y_desc: "bounces (0/1)",
        series: || vec![("x0d".into(), |r, _| open(r, |o| if o.x0d_bounces { 1.0 } else { 0.0 }), 0)],
    },
    Figure {
        file: "zt_sliding.svg",
        title: "Z_t,sliding of the four paper cases, ideal and sampled",
        y_desc: "Z_t,sliding (m)",
        series: || {
            Combination::all()
                .into_iter()
                .enumerate()
                .map(|(i, k)| {
                    let f: fn(&ChoiceResult, usize) -> Option<f64> =
                        |r, i| r.zmax.iter().find(|z| z.combination == Combination::all()[i]).and_then(|z| z.z_t_sliding);
                    (format!("{} x0{} {}", k.controller, k.x0, k.setting), f, i)
                })
                .collect()
        },
    },
    Figure {
        file: "hybrid_closed_loop.svg",
        title: "hybrid closed loop from x0d at mu = 0.6: how the belt speeds' runs ended",
        y_desc: "belt speeds",
        series: || {
            vec![
                ("lift-off".into(), |r, _| r.closed_loop.as_ref().map(|c| c.lift_off_points as f64), 0),
                ("safe state".into(), |r, _| r.closed_loop.as_ref().map(|c| c.safe_state_points as f64), 0),
                ("target not reached".into(), |r, _| r.closed_loop.as_ref().map(|c| c.target_not_reached_points as f64), 0),
            ]
        },
    },
];

/// Draws `fig` of `study` at `path`: a panel per dimension with at least one value.
///
/// # Errors
/// [`CliError::Plot`].
pub fn draw(path: &Path, study: &Study, fig: &Figure) -> Result<(), CliError> {
    let err = plot_err(path);
    let series = (fig.series)();
    let dims: Vec<Dimension> = Dimension::ALL
        .into_iter()
        .filter(|d| study.results.iter().filter(|r| r.choice.dimension == *d).any(|r| series.iter().any(|(_, f, i)| f(r, *i).is_some())))
        .collect();
    let cols = 3usize;
    let rows = dims.len().div_ceil(cols).max(1);
    let root = SVGBackend::new(path, (1500, 60 + 330 * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (title, body) = root.split_vertically(50);
    title.titled(fig.title, ("sans-serif", 24)).map_err(|e| err(&e))?;
    let panels = body.split_evenly((rows, cols));
    let colors = [RED, BLUE, GREEN, MAGENTA, CYAN, RGBColor(200, 120, 0), RGBColor(90, 90, 90), BLACK];
    for (dim, area) in dims.iter().zip(panels.iter()) {
        let of: Vec<&ChoiceResult> = study.results.iter().filter(|r| r.choice.dimension == *dim).collect();
        let values: Vec<f64> = of.iter().flat_map(|r| series.iter().filter_map(|(_, f, i)| f(r, *i))).filter(|v| v.is_finite()).collect();
        let (lo, hi) = values.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
        let (lo, hi) = if values.is_empty() {
            (0.0, 1.0)
        } else if hi - lo < 1e-9 {
            (lo - 0.5 * lo.abs().max(0.1), hi + 0.5 * hi.abs().max(0.1))
        } else {
            (lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo))
        };
        let n = of.len() as f64;
        let axes = Axes {
            caption: Some((dim.label().to_string(), 16)),
            x: -0.5..n - 0.5,
            y: lo..hi,
            x_desc: "",
            y_desc: fig.y_desc,
            x_label_area: 60,
            y_label_area: 60,
            margin: 8,
        };
        let mut chart = xy_chart(area, &axes).map_err(|e| err(&e))?;
        // The values' names under the axis, the default starred.
        for (k, r) in of.iter().enumerate() {
            let label = format!("{}{}", r.choice.value, if r.choice.is_default { "*" } else { "" });
            chart
                .draw_series(std::iter::once(Text::new(label, (k as f64 - 0.3, lo), ("sans-serif", 11).into_font())))
                .map_err(|e| err(&e))?;
        }
        for (s, (name, f, i)) in series.iter().enumerate() {
            let color = colors[s % colors.len()];
            let pts: Vec<(f64, f64)> =
                of.iter().enumerate().filter_map(|(k, r)| f(r, *i).filter(|v| v.is_finite()).map(|v| (k as f64, v))).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(1)))
                .map_err(|e| err(&e))?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2)));
            chart.draw_series(pts.iter().map(|p| Circle::new(*p, 3, color.filled()))).map_err(|e| err(&e))?;
        }
        if series.len() > 1 && dims.first() == Some(dim) {
            legend_upper_right(&mut chart).map_err(|e| err(&e))?;
        }
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
