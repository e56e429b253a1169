//! A numeric axis with a gutter at one end for results that have no value: the
//! round-valued [`NiceAxis`] over all but `gutter_px` pixels of the axis, and NaN
//! (a result computed with no value: no critical `mu` on the grid, a
//! `Z_t,sliding` below the bisection's bracket) mapped to the gutter's middle, so
//! that such markers sit apart from the data and from the tick labels instead of
//! on the axis's edge.

use std::ops::Range;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

use super::{axis::NiceAxis, chart::TickLabels};

/// [`NiceAxis`] with a gutter of `gutter_px` pixels at its low end (`at_low_end`)
/// or its high end, where NaN maps.
#[derive(Debug, Clone)]
pub struct GutterAxis {
    axis: NiceAxis,
    gutter_px: i32,
    at_low_end: bool,
}

impl GutterAxis {
    /// `axis` with a gutter `gutter_px` pixels wide (0: none) at its low end when
    /// `at_low_end`, else at its high end.
    pub fn new(axis: NiceAxis, gutter_px: u32, at_low_end: bool) -> Self {
        Self { axis, gutter_px: gutter_px as i32, at_low_end }
    }

    /// The pixels of the data part of the axis and of the gutter, from the axis's
    /// pixel `limit` (as plotters passes it: low value's pixel first).
    fn split(&self, limit: (i32, i32)) -> ((i32, i32), (i32, i32)) {
        let dir = if limit.1 >= limit.0 { 1 } else { -1 };
        let g = self.gutter_px.min((limit.1 - limit.0).abs() / 2) * dir;
        if self.at_low_end { ((limit.0 + g, limit.1), (limit.0, limit.0 + g)) } else { ((limit.0, limit.1 - g), (limit.1 - g, limit.1)) }
    }

    /// The gutter's pixels (start, end) on an axis drawn over pixel `limit`.
    pub fn gutter(&self, limit: (i32, i32)) -> (i32, i32) {
        self.split(limit).1
    }
}

impl Ranged for GutterAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let (data, gutter) = self.split(limit);
        if value.is_nan() { (gutter.0 + gutter.1) / 2 } else { self.axis.map(value, data) }
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        self.axis.key_points(hint)
    }

    fn range(&self) -> Range<f64> {
        self.axis.range()
    }
}

impl ValueFormatter<f64> for GutterAxis {
    fn format_ext(&self, value: &f64) -> String {
        self.axis.format_ext(value)
    }
}

impl TickLabels for GutterAxis {
    fn tick_labels(&self) -> Vec<String> {
        self.axis.tick_labels()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_maps_into_the_gutter_and_values_beside_it() {
        let low = GutterAxis::new(NiceAxis::new(0.0..1.0, 5), 40, true);
        assert_eq!(low.map(&f64::NAN, (100, 300)), 120);
        assert_eq!(low.map(&0.0, (100, 300)), 140);
        assert_eq!(low.map(&1.0, (100, 300)), 300);
        let high = GutterAxis::new(NiceAxis::new(0.0..1.0, 5), 40, false);
        assert_eq!(high.map(&f64::NAN, (100, 300)), 280);
        assert_eq!(high.map(&1.0, (100, 300)), 260);
        assert_eq!(high.gutter((100, 300)), (260, 300));
        // No gutter wider than half the axis.
        assert_eq!(GutterAxis::new(NiceAxis::new(0.0..1.0, 5), 500, true).gutter((0, 100)), (0, 50));
    }
}
