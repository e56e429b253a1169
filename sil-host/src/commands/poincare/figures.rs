//! The figures of `sil-host poincare`: the bifurcation diagram (`bifurcation.svg`) and the Lyapunov exponents (`lyapunov.svg`).

use crate::{
    error::CliError,
    plot::{self, colors, plot_err},
};
use analyses::poincare::{PoincareConfig, PointResult, classify::Class};
use plotters::prelude::*;
use std::path::Path;

/// Colour and legend label of a result's class.
pub(crate) fn class_style(r: &PointResult) -> (RGBColor, &'static str) {
    match (r.class, r.period) {
        (Class::Periodic, Some(1)) => (colors::BLUE, "period 1"),
        (Class::Periodic, Some(2)) => (colors::GREEN, "period 2"),
        (Class::Periodic, Some(3 | 4)) => (colors::ORANGE, "period 3-4"),
        (Class::Periodic, _) => (colors::PURPLE, "period >= 5"),
        (Class::Chaotic, _) => (colors::RED, "chaotic"),
        (Class::Aperiodic, _) => (colors::GREY, "aperiodic"),
        (Class::Settling, _) => (RGBColor(190, 190, 190), "settling"),
        (Class::Equilibrium, _) => (BLACK, "equilibrium (final theta1)"),
        (Class::Failed, _) => (RGBColor(255, 0, 255), "failed"),
        (Class::Invalid, _) => (RGBColor(0, 160, 160), "invalid (violates the model)"),
    }
}

pub(crate) fn draw_bifurcation(path: &Path, cfg: &PoincareConfig, x0_name: &str, results: &[PointResult]) -> Result<(), CliError> {
    let err = plot_err(path);
    let v_lo = results.first().map_or(-1.0, |r| r.v_belt);
    let v_hi = results.last().map_or(0.0, |r| r.v_belt);
    let pad = ((v_hi - v_lo) * 0.02).max(1e-3);
    // (v_belt, theta1 in degrees, style) for every section point, and the final
    // theta1 of the belt speeds without crossings.
    let mut pts: Vec<(f64, f64, RGBColor, &'static str)> = Vec::new();
    for r in results {
        let (c, label) = class_style(r);
        if r.class == Class::Equilibrium {
            if r.final_theta1.is_finite() {
                pts.push((r.v_belt, r.final_theta1.to_degrees(), c, label));
            }
        } else {
            pts.extend(r.crossings.iter().map(|x| (r.v_belt, x.x[0].to_degrees(), c, label)));
        }
    }
    let (mut lo, mut hi) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if !lo.is_finite() {
        (lo, hi) = (-1.0, 1.0);
    }
    // One marker per pixel row and belt speed (the figure is 750 px high): a
    // periodic orbit repeats its points hundreds of times.
    let resolution = (hi - lo).max(1e-9) / 1500.0;
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup_by(|b, a| a.0 == b.0 && (b.1 - a.1).abs() < resolution);
    let ypad = ((hi - lo) * 0.05).max(0.5);
    let root = SVGBackend::new(path, (1200, 750)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let title = format!("Poincare section theta1_dot = 0 (upward), open loop, mu = {}, from {x0_name}", cfg.mu);
    let axes = plot::Axes {
        caption: Some((title, 22)),
        x: (v_lo - pad)..(v_hi + pad),
        y: (lo - ypad)..(hi + ypad),
        x_desc: "v_belt (m/s)",
        y_desc: "theta1 at the section (deg)",
        x_label_area: 45,
        y_label_area: 70,
        margin: 12,
    };
    let mut chart = plot::xy_chart(&root, &axes).map_err(|e| err(&e))?;
    let mut labels: Vec<&'static str> = pts.iter().map(|p| p.3).collect();
    labels.sort_unstable();
    labels.dedup();
    for label in labels {
        let color = pts.iter().find(|p| p.3 == label).map_or(BLACK, |p| p.2);
        let series = pts.iter().filter(|p| p.3 == label).map(|p| Circle::new((p.0, p.1), 1, color.filled()));
        chart.draw_series(series).map_err(|e| err(&e))?.label(label).legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    plot::legend_upper_right(&mut chart).map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

pub(crate) fn draw_lyapunov(path: &Path, cfg: &PoincareConfig, results: &[PointResult]) -> Result<(), CliError> {
    let err = plot_err(path);
    let pts: Vec<(f64, f64, RGBColor, &'static str)> = results
        .iter()
        .filter_map(|r| {
            let (c, label) = class_style(r);
            r.lyapunov.filter(|l| l.per_iteration.is_finite()).map(|l| (r.v_belt, l.per_iteration, c, label))
        })
        .collect();
    let v_lo = results.first().map_or(-1.0, |r| r.v_belt);
    let v_hi = results.last().map_or(0.0, |r| r.v_belt);
    let pad = ((v_hi - v_lo) * 0.02).max(1e-3);
    let (mut lo, mut hi) = pts.iter().fold((0.0f64, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if hi - lo < 1e-3 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let ypad = (hi - lo) * 0.05;
    let root = SVGBackend::new(path, (1200, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let title = format!("largest Lyapunov exponent of the section map, mu = {} (chaotic above {})", cfg.mu, cfg.classify.chaos_threshold);
    let axes = plot::Axes {
        caption: Some((title, 20)),
        x: (v_lo - pad)..(v_hi + pad),
        y: (lo - ypad)..(hi + ypad),
        x_desc: "v_belt (m/s)",
        y_desc: "lambda per crossing",
        x_label_area: 45,
        y_label_area: 70,
        margin: 12,
    };
    let mut chart = plot::xy_chart(&root, &axes).map_err(|e| err(&e))?;
    chart.draw_series(LineSeries::new([(v_lo - pad, 0.0), (v_hi + pad, 0.0)], BLACK.mix(0.5).stroke_width(1))).map_err(|e| err(&e))?;
    let mut labels: Vec<&'static str> = pts.iter().map(|p| p.3).collect();
    labels.sort_unstable();
    labels.dedup();
    for label in labels {
        let color = pts.iter().find(|p| p.3 == label).map_or(BLACK, |p| p.2);
        chart
            .draw_series(pts.iter().filter(|p| p.3 == label).map(|p| Circle::new((p.0, p.1), 2, color.filled())))
            .map_err(|e| err(&e))?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
