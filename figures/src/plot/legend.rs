//! Legends drawn outside the data: in a column beside a chart or in rows above a
//! figure's panels, each entry a swatch and a label, sized with the figures' font
//! ([`super::font`]) so that no label is cut off or overlaps another.

use plotters::{coord::Shift, prelude::*};

use super::font::FAMILY;

/// How an entry's series is drawn, for its swatch.
#[derive(Debug, Clone, Copy)]
pub enum Swatch {
    /// A solid line of this colour.
    Line(RGBColor),
    /// A dashed line of this colour.
    Dashed(RGBColor),
    /// A filled round marker of this colour.
    Marker(RGBColor),
    /// A hollow round marker of this colour (a result with no value, at an axis's edge).
    Ring(RGBColor),
    /// A filled square of this colour (a map's cell).
    Box(RGBColor),
    /// A filled triangle of this colour pointing up (points above an axis, marked at its edge).
    Triangle(RGBColor),
    /// A filled triangle of this colour pointing down (points below an axis, marked at its edge).
    TriangleDown(RGBColor),
}

/// A legend: labelled swatches, in the order given.
#[derive(Debug, Clone, Default)]
pub struct Legend {
    /// The entries: label and swatch.
    pub entries: Vec<(String, Swatch)>,
}

/// Font size of legend labels, px (plotters' size, 1.24 times the SVG font-size).
pub const LABEL_PX: f64 = super::font::TEXT_PX;
/// Width of a swatch, px.
const SWATCH_W: i32 = 22;
/// Gap between a swatch and its label, and after a label in a row, px.
const GAP: i32 = 6;
/// Height of one legend line, px.
pub const LINE_H: i32 = 24;

/// Width and height of `text` at plotters' font size `px`, px, as plotters lays it
/// out (the registered font's advances; a generous guess if text measurement fails).
pub fn text_size(text: &str, px: f64) -> (u32, u32) {
    super::font::register();
    (FAMILY, px).into_font().box_size(text).unwrap_or(((text.chars().count() as f64 * px * 0.7) as u32, px as u32))
}

impl Legend {
    /// A legend of these entries.
    pub fn new(entries: Vec<(String, Swatch)>) -> Self {
        Self { entries }
    }

    /// Whether the legend has no entry.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    fn entry_width(label: &str) -> i32 {
        SWATCH_W + GAP + text_size(label, LABEL_PX).0 as i32
    }

    /// Width of the legend drawn as a column, px (0 when empty).
    pub fn column_width(&self) -> u32 {
        self.entries.iter().map(|(l, _)| Self::entry_width(l)).max().map_or(0, |w| (w + 2 * GAP) as u32)
    }

    /// The entries' positions `(x, y)` when packed in rows `width` px wide, from
    /// `(GAP, GAP)`, and the height they take, px.
    fn rows_layout(&self, width: u32) -> (Vec<(i32, i32)>, u32) {
        let (mut x, mut y) = (GAP, GAP);
        let mut at = Vec::with_capacity(self.entries.len());
        for (label, _) in &self.entries {
            let w = Self::entry_width(label) + 3 * GAP;
            if x > GAP && x + w > width as i32 - GAP {
                (x, y) = (GAP, y + LINE_H + 4);
            }
            at.push((x, y));
            x += w;
        }
        let h = if self.entries.is_empty() { 0 } else { (y + LINE_H + GAP) as u32 };
        (at, h)
    }

    /// Height of the legend packed in rows `width` px wide, px (0 when empty).
    pub fn rows_height(&self, width: u32) -> u32 {
        self.rows_layout(width).1
    }

    /// Draws the legend as a column on `area`, from its upper left corner.
    ///
    /// # Errors
    /// plotters' error, as text.
    pub fn draw_column<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        for (i, (label, swatch)) in self.entries.iter().enumerate() {
            draw_entry(area, (GAP, GAP + i as i32 * LINE_H), label, *swatch)?;
        }
        Ok(())
    }

    /// Draws the legend packed in rows across `area`'s width.
    ///
    /// # Errors
    /// plotters' error, as text.
    pub fn draw_rows<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let (at, _) = self.rows_layout(area.dim_in_pixel().0);
        for ((label, swatch), (x, y)) in self.entries.iter().zip(at) {
            draw_entry(area, (x, y), label, *swatch)?;
        }
        Ok(())
    }
}

/// Draws one entry with its line's top left corner at `(x, y)`.
fn draw_entry<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, (x, y): (i32, i32), label: &str, swatch: Swatch) -> Result<(), String> {
    let mid = y + LINE_H / 2;
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    match swatch {
        Swatch::Line(c) => area.draw(&PathElement::new(vec![(x, mid), (x + SWATCH_W, mid)], c.stroke_width(2))).map_err(e)?,
        Swatch::Dashed(c) => {
            for k in 0..3 {
                let x0 = x + k * 8;
                area.draw(&PathElement::new(vec![(x0, mid), (x0 + 5, mid)], c.stroke_width(2))).map_err(e)?;
            }
        }
        Swatch::Marker(c) => area.draw(&Circle::new((x + SWATCH_W / 2, mid), 4, c.filled())).map_err(e)?,
        Swatch::Ring(c) => area.draw(&Circle::new((x + SWATCH_W / 2, mid), 4, c.stroke_width(2))).map_err(e)?,
        Swatch::Box(c) => area.draw(&Rectangle::new([(x + 3, mid - 8), (x + 19, mid + 8)], c.filled())).map_err(e)?,
        Swatch::Triangle(c) => {
            let cx = x + SWATCH_W / 2;
            area.draw(&Polygon::new(vec![(cx - 5, mid + 4), (cx + 5, mid + 4), (cx, mid - 5)], c.filled())).map_err(e)?
        }
        Swatch::TriangleDown(c) => {
            let cx = x + SWATCH_W / 2;
            area.draw(&Polygon::new(vec![(cx - 5, mid - 4), (cx + 5, mid - 4), (cx, mid + 5)], c.filled())).map_err(e)?
        }
    }
    let style = TextStyle::from((FAMILY, LABEL_PX).into_font())
        .pos(plotters::style::text_anchor::Pos::new(plotters::style::text_anchor::HPos::Left, plotters::style::text_anchor::VPos::Center));
    area.draw_text(label, &style, (x + SWATCH_W + GAP, mid)).map_err(e)
}
