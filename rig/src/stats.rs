//! Streaming statistics of a run: what `summary.json` reports, accumulated
//! period by period in fixed memory (a run of any length is summarised without
//! keeping its records). Counts, sums, the RMS tracking error and the lift-off
//! statistics are exact (the same numbers as over the whole list of records);
//! wall-clock timings go to an HDR histogram (3 significant digits), the
//! image's integer step counts to an exact distribution of distinct values.

use std::collections::BTreeMap;

use serde::Serialize;

use super::record::{LiftOffStats, LiftOffTracker, PeriodRecord};

/// The figures of `summary.json` every closed-loop run has, accumulated one
/// [`PeriodRecord`] at a time in fixed memory; each is exactly what the whole
/// list of records gives.
#[derive(Debug, Clone)]
pub struct RunStats {
    periods: usize,
    deadline_misses: usize,
    max_overruns: u32,
    /// Sum of `(z_t - z_t*)^2`, m^2, in record order (as `Iterator::sum`).
    sum_sq_tracking: f64,
    /// The last record's `t` (s) and `z_t` (m).
    last: Option<(f64, f64)>,
    lift_off: LiftOffTracker,
}

impl Default for RunStats {
    fn default() -> Self {
        // -0.0: the neutral element `Iterator::sum` starts from, so the sums agree to the bit.
        Self { periods: 0, deadline_misses: 0, max_overruns: 0, sum_sq_tracking: -0.0, last: None, lift_off: LiftOffTracker::default() }
    }
}

impl RunStats {
    /// The statistics of `records` (a whole run).
    pub fn of(records: &[PeriodRecord]) -> Self {
        let mut s = Self::default();
        records.iter().for_each(|r| s.push(r));
        s
    }

    /// Adds the next period's record.
    #[inline]
    pub fn push(&mut self, r: &PeriodRecord) {
        self.periods += 1;
        self.deadline_misses += usize::from(r.deadline_miss);
        self.max_overruns = self.max_overruns.max(r.overruns);
        self.sum_sq_tracking += (r.z_t - r.z_t_ref).powi(2);
        self.last = Some((r.t, r.z_t));
        self.lift_off.push(r.lift_off_true, r.lift_off_detected);
    }

    /// Periods recorded.
    pub fn periods(&self) -> usize {
        self.periods
    }

    /// Deadline misses seen by the plant.
    pub fn deadline_misses(&self) -> usize {
        self.deadline_misses
    }

    /// The firmware's overrun counter at its highest, i.e. at the end.
    pub fn max_overruns(&self) -> u32 {
        self.max_overruns
    }

    /// RMS of `z_t - z_t*`, m (0 when empty).
    pub fn rms_tracking_error(&self) -> f64 {
        if self.periods == 0 {
            return 0.0;
        }
        (self.sum_sq_tracking / self.periods as f64).sqrt()
    }

    /// The last record's sample time, s (`None` when empty).
    pub fn last_t(&self) -> Option<f64> {
        self.last.map(|l| l.0)
    }

    /// The last record's `z_t`, m (NaN when empty).
    pub fn final_z_t(&self) -> f64 {
        self.last.map_or(f64::NAN, |l| l.1)
    }

    /// The lift-off detection statistics.
    pub fn lift_off(&self) -> LiftOffStats {
        self.lift_off.stats()
    }
}

/// A wall-clock timing (round trip, jitter, step time) in fixed memory: an HDR
/// histogram of nanoseconds at 3 significant digits (`hdrhistogram`; about
/// 8 KB per factor of two of range, some 100 KB for 1 ns to an hour), plus
/// the exact maximum.
///
/// Resolution: a percentile is hdrhistogram's (the nearest rank `ceil(q n)`),
/// reported as the highest value equivalent to it, so at most 0.1 % (and below
/// 2.048 us at most 1 ns) above the sample's value; the maximum is exact.
#[derive(Debug, Clone)]
pub struct TimingHistogram {
    hist: hdrhistogram::Histogram<u64>,
    max_ns: u64,
}

impl Default for TimingHistogram {
    fn default() -> Self {
        Self::new()
    }
}

impl TimingHistogram {
    /// An empty histogram (auto-resizing from 1 ns up to whatever is recorded).
    pub fn new() -> Self {
        // 3 significant digits are always valid: `new` cannot fail here.
        let hist = hdrhistogram::Histogram::new(3).unwrap_or_else(|_| unreachable!("3 significant digits are valid"));
        Self { hist, max_ns: 0 }
    }

    /// Records one sample, ns.
    pub fn record_ns(&mut self, ns: u64) {
        // `record` grows the histogram to the value (`saturating_record` would clamp
        // it to the current range); it fails only past its largest trackable value.
        if self.hist.record(ns).is_err() {
            self.hist.saturating_record(ns);
        }
        self.max_ns = self.max_ns.max(ns);
    }

    /// Records one sample of `d`.
    pub fn record(&mut self, d: std::time::Duration) {
        self.record_ns(u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    }

    /// Samples recorded.
    pub fn len(&self) -> u64 {
        self.hist.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.hist.is_empty()
    }

    /// Adds every sample of `other`.
    pub fn merge(&mut self, other: &Self) {
        // Both auto-resize: adding cannot run out of range.
        let _ = self.hist.add(&other.hist);
        self.max_ns = self.max_ns.max(other.max_ns);
    }

    /// p50, p99, p999 and max, microseconds; zeros when empty.
    pub fn percentiles(&self) -> Percentiles {
        if self.hist.is_empty() {
            return Percentiles::default();
        }
        let us = |q: f64| self.hist.value_at_quantile(q) as f64 * 1e-3;
        Percentiles { p50: us(0.5), p99: us(0.99), p999: us(0.999), max: self.max_ns as f64 * 1e-3 }
    }
}

/// An exact distribution of integer counts (the image's instruction or cycle
/// counts per step): how many times each distinct value occurred. Memory is one
/// map entry per distinct value, bounded by the spread of the counts (a step's
/// path lengths), not by the number of samples.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CountDistribution {
    counts: BTreeMap<u32, u64>,
    n: u64,
}

impl CountDistribution {
    /// Records one sample.
    pub fn record(&mut self, value: u32) {
        *self.counts.entry(value).or_insert(0) += 1;
        self.n += 1;
    }

    /// Samples recorded.
    pub fn len(&self) -> u64 {
        self.n
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Distinct values recorded (the map's size).
    pub fn distinct(&self) -> usize {
        self.counts.len()
    }

    /// The smallest sample (`None` when empty).
    pub fn min(&self) -> Option<u32> {
        self.counts.keys().next().copied()
    }

    /// The largest sample (`None` when empty).
    pub fn max(&self) -> Option<u32> {
        self.counts.keys().next_back().copied()
    }

    /// The sample of rank `r` (0-based) in ascending order.
    fn at_rank(&self, r: u64) -> u32 {
        let mut seen = 0;
        for (&v, &c) in &self.counts {
            seen += c;
            if seen > r {
                return v;
            }
        }
        self.max().unwrap_or(0)
    }

    /// Median, 99th percentile and worst, scaled by `scale`: exactly
    /// [`Spread::of`] over the samples (rank `round(q (n - 1))`); zeros when empty.
    pub fn spread(&self, scale: f64) -> Spread {
        if self.n == 0 {
            return Spread::default();
        }
        let at = |q: f64| {
            let r = ((q * (self.n - 1) as f64).round() as u64).min(self.n - 1);
            self.at_rank(r) as f64 * scale
        };
        Spread { median: at(0.5), p99: at(0.99), worst: self.max().unwrap_or(0) as f64 * scale }
    }
}

/// Percentiles of a sample (p50, p99, p999, max; rank `round(q (n - 1))` of the
/// sorted sample), in the sample's unit; zeros when empty. Runs of any length use
/// [`crate::stats::TimingHistogram`] instead (fixed memory).
pub fn percentiles(samples: &[f32]) -> Percentiles {
    if samples.is_empty() {
        return Percentiles::default();
    }
    let mut v = samples.to_vec();
    v.sort_by(f32::total_cmp);
    let at = |q: f64| v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)] as f64;
    Percentiles { p50: at(0.5), p99: at(0.99), p999: at(0.999), max: v[v.len() - 1] as f64 }
}

/// Percentiles of a timing, microseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.9th percentile.
    pub p999: f64,
    /// Largest.
    pub max: f64,
}

/// Median, 99th percentile and worst of a sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub worst: f64,
}

impl Spread {
    /// The spread of `samples` scaled by `scale`; zeros when empty.
    pub fn of(samples: &[u32], scale: f64) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let mut v = samples.to_vec();
        v.sort_unstable();
        let at = |q: f64| v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)] as f64 * scale;
        Self { median: at(0.5), p99: at(0.99), worst: v[v.len() - 1] as f64 * scale }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn count_spread_equals_sorting(v in proptest::collection::vec(0u32..50, 1..500), scale in 0.1f64..10.0) {
            let mut d = CountDistribution::default();
            v.iter().for_each(|&x| d.record(x));
            prop_assert_eq!(d.spread(scale), Spread::of(&v, scale));
            prop_assert!(d.distinct() <= 50);
        }

        #[test]
        fn timing_percentiles_within_a_thousandth(v in proptest::collection::vec(1u64..50_000_000, 1..2000)) {
            let mut h = TimingHistogram::new();
            v.iter().for_each(|&ns| h.record_ns(ns));
            let got = h.percentiles();
            let mut sorted = v.clone();
            sorted.sort_unstable();
            let n = sorted.len();
            // hdrhistogram's rank: the smallest sample with at least ceil(q n) samples at or below it.
            let exact = |q: f64| sorted[((q * n as f64).ceil() as usize).clamp(1, n) - 1] as f64 * 1e-3;
            for (q, p) in [(0.5, got.p50), (0.99, got.p99), (0.999, got.p999)] {
                let e = exact(q);
                prop_assert!(p >= e && p <= e * 1.001 + 1e-3, "q {}: {} vs exact {}", q, p, e);
            }
            prop_assert_eq!(got.max, sorted[n - 1] as f64 * 1e-3);
        }
    }

    #[test]
    fn timing_percentiles_agree_with_the_sorted_ones_on_a_typical_spread() {
        // Round trips of ~10 us with a tail: the histogram's figures within 0.1 % of sorting's.
        let ns: Vec<u64> = (0..100_000u64).map(|k| 8_000 + (k * 7919) % 4_000 + if k % 500 == 0 { 50_000 } else { 0 }).collect();
        let mut h = TimingHistogram::new();
        ns.iter().for_each(|&x| h.record_ns(x));
        let us: Vec<f32> = ns.iter().map(|&x| x as f32 * 1e-3).collect();
        let (a, b) = (h.percentiles(), percentiles(&us));
        for (x, y) in [(a.p50, b.p50), (a.p99, b.p99), (a.p999, b.p999), (a.max, b.max)] {
            assert!((x - y).abs() <= 1e-3 * y + 2e-3, "{a:?} vs {b:?}");
        }
    }
}
