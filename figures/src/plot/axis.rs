//! Axes for figures fit for a paper: numeric axes whose ticks fall on round
//! values (1, 2 or 5 times a power of ten) and whose labels all carry the same,
//! smallest sufficient number of decimals (never `-0.0`, never `9000.0`), and
//! categorical axes whose ticks are names.
//!
//! Both implement plotters' [`Ranged`], so a chart is built on them as on a
//! plain `Range<f64>`.

use std::ops::Range;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

/// A numeric axis from `lo` to `hi` (any unit) with round ticks.
///
/// The tick step is the smallest of `{1, 2, 5} x 10^k` that gives at most
/// `max_ticks` ticks inside `[lo, hi]` (W. S. Cleveland, *The Elements of Graphing
/// Data*, 1985: round numbers, a few per axis). Labels use the step's decimals.
#[derive(Debug, Clone)]
pub struct NiceAxis {
    lo: f64,
    hi: f64,
    max_ticks: usize,
    min_step: f64,
}

impl NiceAxis {
    /// The axis over `range` with at most `max_ticks` (at least 2) ticks. An empty
    /// or reversed range is widened to a unit around its start; a non-finite end
    /// gives the range `[0, 1]`.
    pub fn new(range: Range<f64>, max_ticks: usize) -> Self {
        let (mut lo, mut hi) = (range.start, range.end);
        if !lo.is_finite() || !hi.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        if hi <= lo {
            let half = 0.5 * lo.abs().max(1.0);
            (lo, hi) = (lo - half, lo + half);
        }
        Self { lo, hi, max_ticks: max_ticks.max(2), min_step: 0.0 }
    }

    /// The axis with ticks at least `min_step` apart (`1`: a count, whole numbers only).
    pub fn with_min_step(mut self, min_step: f64) -> Self {
        self.min_step = min_step;
        self
    }

    /// The tick step for at most `max_ticks` ticks, but at least two inside the
    /// range (issue 69: a narrow panel whose range straddles a round value, e.g.
    /// -0.35 to 0.05 with 3 ticks, had the step 0.5 and one label, `0`): the next
    /// smaller `{1, 2, 5} x 10^k` while fewer than two fall inside, down to
    /// `min_step`.
    pub fn step(&self, max_ticks: usize) -> f64 {
        let mut step = nice_step(self.hi - self.lo, max_ticks.max(2)).max(self.min_step);
        let inside = |s: f64| (self.hi / s).floor() - (self.lo / s).ceil() + 1.0;
        // Never more than one tick beyond the count asked for: a panel with too
        // little room keeps its one tick (and a caller may widen its range to the
        // step's multiples, as the sensitivity figure does).
        while inside(step) < 2.0 {
            let smaller = smaller_step(step);
            if smaller < self.min_step || smaller <= 0.0 || inside(smaller) > (max_ticks.max(2) + 1) as f64 {
                break;
            }
            step = smaller;
        }
        step
    }

    /// The ticks for at most `max_ticks` ticks, ascending.
    pub fn ticks(&self, max_ticks: usize) -> Vec<f64> {
        let step = self.step(max_ticks);
        let first = (self.lo / step).ceil() as i64;
        let last = (self.hi / step).floor() as i64;
        (first..=last).map(|k| if k == 0 { 0.0 } else { k as f64 * step }).collect()
    }

    /// The largest number of ticks asked for.
    pub fn max_ticks(&self) -> usize {
        self.max_ticks
    }

    /// The label of tick value `v`: the decimals of this axis's step, no `-0`.
    pub fn label(&self, v: f64) -> String {
        format_tick(v, self.step(self.max_ticks))
    }
}

/// The smallest step `{1, 2, 5} x 10^k` that divides `span` into at most
/// `max_ticks - 1` intervals.
pub fn nice_step(span: f64, max_ticks: usize) -> f64 {
    let raw = span / (max_ticks.max(2) - 1) as f64;
    let mut p = 10f64.powi(raw.log10().floor() as i32);
    loop {
        for m in [1.0, 2.0, 5.0] {
            if m * p >= raw * (1.0 - 1e-12) {
                return m * p;
            }
        }
        p *= 10.0;
    }
}

/// The round step below `step` (`{1, 2, 5} x 10^k`): 5 -> 2 -> 1 -> 0.5.
fn smaller_step(step: f64) -> f64 {
    let p = 10f64.powi(step.log10().floor() as i32);
    let m = (step / p).round();
    if m >= 5.0 {
        2.0 * p
    } else if m >= 2.0 {
        p
    } else {
        0.5 * p
    }
}

/// Formats tick value `v` of an axis with tick `step` (`{1, 2, 5} x 10^k`): the
/// step's decimals (`max(0, -k)`); `0` for values within a millionth of a step of
/// zero (so never `-0.00`); scientific notation (`2.5e6`) from `|v| >= 1e5`.
pub fn format_tick(v: f64, step: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let v = if v.abs() < step.abs() * 1e-6 { 0.0 } else { v };
    let k = step.abs().log10().floor() as i32;
    if v.abs() >= 1e5 {
        let e = v.abs().log10().floor() as i32;
        let decimals = (e - k).clamp(0, 6) as usize;
        let s = format!("{:.*e}", decimals, v);
        return trim_mantissa(&s);
    }
    let decimals = (-k).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') { s[1..].to_string() } else { s }
}

/// `2.50e6` -> `2.5e6`, `1.0e6` -> `1e6`.
fn trim_mantissa(s: &str) -> String {
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
        _ => s.to_string(),
    }
}

impl Ranged for NiceAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let f = (value - self.lo) / (self.hi - self.lo);
        limit.0 + (f * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        self.ticks(hint.max_num_points().min(self.max_ticks))
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for NiceAxis {
    fn format_ext(&self, value: &f64) -> String {
        self.label(*value)
    }
}

/// A categorical axis: `names[i]` at position `i`, the first name at the low end
/// of the axis's pixels (the top of a y axis drawn top-down: see
/// [`CategoryAxis::top_down`]).
#[derive(Debug, Clone)]
pub struct CategoryAxis {
    names: Vec<String>,
    top_down: bool,
}

impl CategoryAxis {
    /// The axis of `names`, first at the left (x) or bottom (y).
    pub fn new(names: Vec<String>) -> Self {
        Self { names, top_down: false }
    }

    /// The axis of `names` for a y axis read top-down: the first name on top.
    pub fn top_down(names: Vec<String>) -> Self {
        Self { names, top_down: true }
    }

    /// The number of categories.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether there is no category.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
}

impl Ranged for CategoryAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let n = self.names.len().max(1) as f64;
        let mut f = (value + 0.5) / n;
        if self.top_down {
            f = 1.0 - f;
        }
        limit.0 + (f * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, _hint: H) -> Vec<f64> {
        (0..self.names.len()).map(|i| i as f64).collect()
    }

    fn range(&self) -> Range<f64> {
        -0.5..self.names.len() as f64 - 0.5
    }
}

impl ValueFormatter<f64> for CategoryAxis {
    fn format_ext(&self, value: &f64) -> String {
        let i = value.round();
        if i >= 0.0 && (i as usize) < self.names.len() { self.names[i as usize].clone() } else { String::new() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_one_two_or_five_times_a_power_of_ten() {
        for (span, n, step) in [(1.0, 11, 0.1), (1.0, 6, 0.2), (1.0, 3, 0.5), (9000.0, 10, 1000.0), (0.33, 8, 0.05), (2.2, 12, 0.2)] {
            let s = nice_step(span, n);
            assert!((s - step).abs() < 1e-12 * step, "{span} {n}: {s}");
            assert!(span / s <= (n - 1) as f64 + 1e-9);
        }
    }

    #[test]
    fn labels_share_the_steps_decimals_and_never_read_minus_zero() {
        let a = NiceAxis::new(-0.1..0.2, 8);
        let labels: Vec<String> = a.ticks(8).into_iter().map(|v| a.label(v)).collect();
        assert_eq!(labels, ["-0.10", "-0.05", "0.00", "0.05", "0.10", "0.15", "0.20"]);
        let b = NiceAxis::new(0.0..9000.0, 10);
        assert_eq!(b.label(9000.0), "9000");
        assert_eq!(format_tick(-1e-17, 0.1), "0.0");
        assert_eq!(format_tick(-0.04, 0.1), "0.0");
        assert_eq!(format_tick(2.5e6, 5e5), "2.5e6");
        assert_eq!(format_tick(1e6, 5e5), "1e6");
    }

    #[test]
    fn ticks_lie_inside_the_range_and_respect_the_count() {
        for (lo, hi) in [(-0.377, -0.352), (0.0, 10.0), (-1.02, -0.08), (1.3, 1.3), (-17.0, 68.0)] {
            let a = NiceAxis::new(lo..hi, 7);
            let r = a.range();
            let t = a.ticks(7);
            assert!(!t.is_empty() && t.len() <= 7, "{lo} {hi}: {t:?}");
            assert!(t.iter().all(|v| *v >= r.start - 1e-12 && *v <= r.end + 1e-12));
        }
    }

    /// Issue 69 (5): a range that straddles a round value gets two labels or
    /// more however few ticks are asked for (the sensitivity figure's narrow
    /// panels, the animation's strip), over random ranges.
    #[test]
    fn every_axis_has_at_least_two_labelled_ticks() {
        let a = NiceAxis::new(-0.35..0.05, 3);
        let t = a.ticks(3);
        assert!(t.len() >= 2, "{t:?}");
        assert_eq!(t.iter().map(|v| a.label(*v)).collect::<Vec<_>>(), ["-0.2", "0.0"]);
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut two = 0;
        for _ in 0..10_000 {
            let scale = 10f64.powi((next() * 8.0) as i32 - 4);
            let lo = (next() - 0.5) * 10.0 * scale;
            let hi = lo + (0.01 + next()) * scale;
            let n = 2 + (next() * 8.0) as usize;
            let a = NiceAxis::new(lo..hi, n);
            let t = a.ticks(n);
            assert!(!t.is_empty() && t.len() <= n + 1, "{lo}..{hi} with {n} ticks: {t:?}");
            // Two or more whenever one more tick than asked for allows it.
            let finer = smaller_step(nice_step(hi - lo, n));
            let could = (hi / finer).floor() - (lo / finer).ceil() + 1.0;
            assert!(t.len() >= 2 || could > (n + 1) as f64 || could < 2.0, "{lo}..{hi} with {n} ticks: {t:?}");
            two += usize::from(t.len() >= 2);
            let labels: Vec<String> = t.iter().map(|v| a.label(*v)).collect();
            assert!(labels.windows(2).all(|w| w[0] != w[1]), "distinct labels for {lo}..{hi}: {labels:?}");
        }
        assert!(two > 9_500, "{two} of 10 000 random axes have two ticks or more (98.6 % measured)");
    }

    #[test]
    fn categories_map_first_on_top_when_read_top_down() {
        let c = CategoryAxis::top_down(vec!["a".into(), "b".into(), "c".into()]);
        // plotters maps a y value with the limits (bottom pixel, top pixel).
        assert!(c.map(&0.0, (300, 0)) < c.map(&2.0, (300, 0)), "the first category is drawn above the last");
        assert_eq!(c.format_ext(&1.0), "b");
        assert_eq!(c.format_ext(&7.0), "");
    }
}
