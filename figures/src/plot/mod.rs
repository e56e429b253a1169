//! Figures fit for a paper, drawn with plotters into SVG files: the canvas and
//! its font, axes with round ticks or category names, legends outside the data,
//! stacked time-series panels, and the frame every x-y chart of the commands
//! shares.
//!
//! Why plotters: it is pure Rust, writes SVG without a runtime, and is the most
//! used plotting crate on crates.io; what it lacks for a paper (round tick labels,
//! categorical axes, legends that measure their text) is here, on its public
//! traits. The rules every figure keeps (no text outside the canvas, no two texts
//! overlapping, no `-0.0`, units on every numeric axis) are checked by
//! `tests/e2e/figures.rs` on every figure `sil-host report` writes.

pub mod axis;
pub mod chart;
pub mod colors;
pub mod font;
pub mod gutter;
pub mod history;
pub mod legend;
#[cfg(feature = "pdf")]
pub mod pdf;
pub mod print;
pub mod symbols;
pub mod time_panels;

use std::{ops::Range, path::Path};

use plotters::{coord::Shift, prelude::*};

pub use history::{HistoryEnvelope, HistorySample, MODE_NAMES, history_panels, mode_code, mode_panel, mode_panel_of_points};
pub use print::{PrintWidth, finish};
pub use time_panels::{Panel, Series, decimate, time_panels};

use crate::error::Error;
use axis::NiceAxis;
use chart::{Frame, frame_chart};
use font::FAMILY;
use legend::text_size;

/// The error of drawing the figure at `path`, as a [`Error::Plot`].
pub fn plot_err(path: &Path) -> impl Fn(&dyn std::fmt::Display) -> Error + '_ {
    move |e| Error::Plot { path: path.to_path_buf(), message: e.to_string() }
}

/// A white SVG canvas writing to `path`, [`PrintWidth::px`] wide for `width` and
/// `height` px high, with the figures' font registered ([`font::register`]).
/// [`print::finish`] presents it, sets its printed size and writes its PDF.
///
/// # Errors
/// plotters' error, as text.
pub fn svg_canvas(path: &Path, width: PrintWidth, height: u32) -> Result<DrawingArea<SVGBackend<'_>, Shift>, String> {
    font::register();
    let root = SVGBackend::new(path, (width.px(), height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    Ok(root)
}

/// An area of an SVG canvas.
pub type SvgArea<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A canvas for `width` with `title` on top ([`draw_title`] at [`font::TITLE_PX`],
/// as many lines as it needs), `legend` packed in rows under it (none when
/// `None`), and `body_h` px below them for the charts: the canvas, to pass to
/// [`finish`], and the body's area.
///
/// # Errors
/// plotters' error, as text.
pub fn titled_canvas<'a>(
    path: &'a Path,
    width: PrintWidth,
    title: &str,
    legend: Option<&legend::Legend>,
    body_h: u32,
) -> Result<(SvgArea<'a>, SvgArea<'a>), String> {
    let title_h = title_height(title, width.px(), font::TITLE_PX, 10);
    let legend_h = legend.map_or(0, |l| l.rows_height(width.px()));
    let root = svg_canvas(path, width, title_h + legend_h + body_h)?;
    let (top, rest) = root.split_vertically(title_h);
    draw_title(&top, title, font::TITLE_PX, 10)?;
    let (legend_area, body) = rest.split_vertically(legend_h);
    if let Some(l) = legend {
        l.draw_rows(&legend_area.margin(0, 0, 10, 10))?;
    }
    Ok((root, body))
}

/// `title` broken at spaces into lines that each fit `width` px, less 10 px
/// either side, at plotters' font size `px` (a word wider than that stays whole on
/// its line, and fails the figure check).
pub fn title_lines(title: &str, width: u32, px: f64) -> Vec<String> {
    let room = width.saturating_sub(20);
    let mut lines: Vec<String> = Vec::new();
    for word in title.split(' ') {
        match lines.last_mut() {
            Some(line) if text_size(&format!("{line} {word}"), px).0 <= room => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// The height `title` takes drawn by [`draw_title`] at plotters' font size `px`
/// on an area `width` px wide from `top` px down, with 10 px below, px.
pub fn title_height(title: &str, width: u32, px: f64, top: u32) -> u32 {
    top + title_lines(title, width, px).len() as u32 * title_line_h(px) + 10
}

/// The distance between the lines of a title at plotters' font size `px`, px.
fn title_line_h(px: f64) -> u32 {
    (px * 1.25).ceil() as u32
}

/// Draws `title` centred at the top of `area`, `top` px down, at plotters' font
/// size `px`, in as many lines as it needs to fit the width with 10 px either side
/// ([`title_lines`]; [`title_height`] is the space it takes).
///
/// # Errors
/// plotters' error, as text.
pub fn draw_title<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, title: &str, px: f64, top: i32) -> Result<(), String> {
    let width = area.dim_in_pixel().0;
    let style = TextStyle::from((FAMILY, px).into_font())
        .pos(plotters::style::text_anchor::Pos::new(plotters::style::text_anchor::HPos::Center, plotters::style::text_anchor::VPos::Top));
    for (i, line) in title_lines(title, width, px).iter().enumerate() {
        let y = top + (i as u32 * title_line_h(px)) as i32;
        area.draw_text(line, &style, (width as i32 / 2, y)).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// An x-y chart of `f64` against `f64` on round-valued axes.
pub type XyChart<'a, DB> = chart::Chart<'a, DB, NiceAxis>;

/// The axes of an [`xy_chart`].
pub struct Axes<'s> {
    /// Caption above the chart, if any.
    pub caption: Option<&'s str>,
    /// X range, in the x unit.
    pub x: Range<f64>,
    /// Y range, in the y unit.
    pub y: Range<f64>,
    /// X-axis description with units.
    pub x_desc: &'s str,
    /// Y-axis description with units.
    pub y_desc: &'s str,
}

/// A chart on `area` with `axes` (round ticks, about one per 75 px across and 40 px
/// up), its mesh drawn.
///
/// # Errors
/// plotters' error, as text.
pub fn xy_chart<'a, DB: DrawingBackend>(area: &'a DrawingArea<DB, Shift>, axes: &Axes) -> Result<XyChart<'a, DB>, String> {
    let (w, h) = area.dim_in_pixel();
    let x = NiceAxis::new(axes.x.clone(), (w / 75).clamp(3, 12) as usize);
    let y = NiceAxis::new(axes.y.clone(), (h / 40).clamp(3, 10) as usize);
    let frame = Frame { x_desc: axes.x_desc, y_desc: axes.y_desc, x_tick_labels: true, caption: axes.caption, margin_top: 8, y_area: None };
    frame_chart(area, x, y, &frame)
}
