//! A fixed-memory, decimated copy of a time series for figures: the points of a
//! run as they come, kept whole up to a capacity and then as the minimum and
//! maximum of consecutive buckets of samples (a min/max envelope), so a run of
//! any length draws from bounded memory and short spikes (impacts, bounces,
//! lift-offs) stay visible.

/// One bucket: the lowest and highest sample of `n` consecutive samples.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bucket {
    /// The lowest sample `(t, y)` (the earliest of equal ones; NaN only if all are NaN).
    lo: (f64, f64),
    /// The highest sample (the earliest of equal ones; NaN only if all are NaN).
    hi: (f64, f64),
    /// Samples in the bucket.
    n: u64,
}

impl Bucket {
    fn one(p: (f64, f64)) -> Self {
        Self { lo: p, hi: p, n: 1 }
    }

    /// `self` followed by the later `b`.
    fn merge(self, b: Self) -> Self {
        // NaN is "no value": any number replaces it; ties keep the earlier sample.
        let lo = if (self.lo.1.is_nan() && !b.lo.1.is_nan()) || b.lo.1 < self.lo.1 { b.lo } else { self.lo };
        let hi = if (self.hi.1.is_nan() && !b.hi.1.is_nan()) || b.hi.1 > self.hi.1 { b.hi } else { self.hi };
        Self { lo, hi, n: self.n + b.n }
    }
}

/// A decimating buffer of `(t, y)` samples pushed in time order, in at most
/// `capacity` buckets (40 bytes each) whatever the number of samples.
///
/// Up to `capacity` samples it keeps every one ([`Envelope::points`] gives them
/// back unchanged); past that, whenever the buckets are full, neighbouring
/// buckets are merged in pairs, so each holds `2^j` consecutive samples
/// represented by their lowest and highest (in time order). Between
/// `capacity / 2` and `capacity` buckets are kept, each of the same number of
/// samples (the last one possibly partial): for samples evenly spaced in time,
/// an envelope of even time buckets. NaN samples are kept only in buckets that
/// have nothing else.
#[derive(Debug, Clone)]
pub struct Envelope {
    capacity: usize,
    /// Samples per complete bucket (a power of two).
    per: u64,
    buckets: Vec<Bucket>,
    /// The bucket being filled (fewer than `per` samples).
    open: Option<Bucket>,
}

impl Envelope {
    /// The default capacity, buckets: 16 384 (655 KB per series), more than the
    /// 10 001 samples of a 10 s run at 1 kHz, which thus keep every sample.
    pub const DEFAULT_CAPACITY: usize = 1 << 14;

    /// An empty envelope of [`Envelope::DEFAULT_CAPACITY`] buckets.
    pub fn new() -> Self {
        Self::with_capacity(Self::DEFAULT_CAPACITY)
    }

    /// An empty envelope of `capacity` buckets (at least 2; rounded up to an even number).
    pub fn with_capacity(capacity: usize) -> Self {
        let capacity = capacity.max(2).next_multiple_of(2);
        Self { capacity, per: 1, buckets: Vec::new(), open: None }
    }

    /// Samples pushed so far.
    pub fn len(&self) -> u64 {
        self.buckets.len() as u64 * self.per + self.open.map_or(0, |b| b.n)
    }

    /// Whether nothing was pushed.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Samples each complete bucket stands for (1 while every sample is kept).
    pub fn samples_per_bucket(&self) -> u64 {
        self.per
    }

    /// Appends sample `(t, y)` (`t` not before the previous sample's).
    #[inline]
    pub fn push(&mut self, t: f64, y: f64) {
        // Every sample kept so far and room for this one: the common case of a
        // run up to the capacity, a few instructions per sample.
        if self.per == 1 && self.buckets.len() < self.capacity {
            self.buckets.push(Bucket::one((t, y)));
            return;
        }
        self.push_into_buckets(t, y);
    }

    /// [`Envelope::push`] once buckets hold more than one sample (or are about to).
    #[cold]
    fn push_into_buckets(&mut self, t: f64, y: f64) {
        let p = Bucket::one((t, y));
        let b = match self.open.take() {
            Some(open) => open.merge(p),
            None => p,
        };
        if b.n < self.per {
            self.open = Some(b);
            return;
        }
        if self.buckets.len() == self.capacity {
            // Full: halve the resolution (pairs of neighbours become one bucket).
            self.buckets = self.buckets.chunks_exact(2).map(|c| c[0].merge(c[1])).collect();
            self.per *= 2;
            // `b` (of the old size) now opens a bucket of the new one.
            self.open = Some(b);
            return;
        }
        self.buckets.push(b);
    }

    /// The kept points in time order: every sample while no more than the
    /// capacity were pushed, else each bucket's lowest and highest sample (one
    /// point when they are the same sample).
    pub fn points(&self) -> Vec<(f64, f64)> {
        let mut out = Vec::with_capacity(2 * (self.buckets.len() + 1));
        for b in self.buckets.iter().chain(&self.open) {
            let (first, second) = if b.lo.0 <= b.hi.0 { (b.lo, b.hi) } else { (b.hi, b.lo) };
            out.push(first);
            let same = first.0.to_bits() == second.0.to_bits() && first.1.to_bits() == second.1.to_bits();
            if !same {
                out.push(second);
            }
        }
        out
    }
}

impl Default for Envelope {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn keeps_every_sample_up_to_the_capacity() {
        let mut e = Envelope::with_capacity(8);
        let pts: Vec<(f64, f64)> = (0..8).map(|k| (k as f64, (k * k) as f64)).collect();
        for &(t, y) in &pts {
            e.push(t, y);
        }
        assert_eq!(e.points(), pts);
        assert_eq!(e.samples_per_bucket(), 1);
    }

    #[test]
    fn a_spike_survives_a_million_samples() {
        let mut e = Envelope::with_capacity(64);
        for k in 0..1_000_000u32 {
            let y = if k == 765_432 {
                5.0
            } else if k == 123_457 {
                -3.0
            } else {
                0.0
            };
            e.push(k as f64 * 1e-3, y);
        }
        assert_eq!(e.len(), 1_000_000);
        let pts = e.points();
        assert!(pts.len() <= 2 * 64 + 2, "{} points", pts.len());
        let at = |y: f64| pts.iter().find(|p| p.1 == y).map(|p| p.0);
        assert_eq!(at(5.0), Some(765_432.0 * 1e-3), "the spike, at its own time");
        assert_eq!(at(-3.0), Some(123_457.0 * 1e-3), "the dip, at its own time");
        assert!(pts.windows(2).all(|w| w[0].0 < w[1].0), "time order");
    }

    #[test]
    fn nan_is_kept_only_where_there_is_nothing_else() {
        let mut e = Envelope::with_capacity(2);
        for (k, y) in [f64::NAN, f64::NAN, f64::NAN, 1.0, f64::NAN, f64::NAN, f64::NAN, f64::NAN].into_iter().enumerate() {
            e.push(k as f64, y);
        }
        // Two buckets of four: [NaN NaN NaN 1] and [NaN NaN NaN NaN].
        let pts = e.points();
        assert_eq!(pts[0], (3.0, 1.0));
        assert!(pts.len() == 2 && pts[1].0 == 4.0 && pts[1].1.is_nan(), "{pts:?}");
    }

    proptest! {
        /// The envelope's points bound every sample's bucket: the global
        /// minimum and maximum are always among them, memory stays within the
        /// capacity, and the points are samples, in time order.
        #[test]
        fn bounds_hold_for_any_series(ys in proptest::collection::vec(-1e3f64..1e3, 1..3000), cap in 2usize..40) {
            let mut e = Envelope::with_capacity(cap);
            for (k, &y) in ys.iter().enumerate() {
                e.push(k as f64, y);
            }
            prop_assert_eq!(e.len(), ys.len() as u64);
            prop_assert!(e.buckets.len() <= e.capacity);
            let pts = e.points();
            prop_assert!(pts.len() <= 2 * (e.capacity + 1));
            prop_assert!(pts.windows(2).all(|w| w[0].0 < w[1].0));
            for &(t, y) in &pts {
                prop_assert_eq!(ys[t as usize], y);
            }
            let min = ys.iter().copied().fold(f64::INFINITY, f64::min);
            let max = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(pts.iter().any(|p| p.1 == min) && pts.iter().any(|p| p.1 == max));
            // Every bucket of `per` samples has its extremes in the output.
            let per = e.samples_per_bucket() as usize;
            for chunk in ys.chunks(per) {
                let lo = chunk.iter().copied().fold(f64::INFINITY, f64::min);
                prop_assert!(pts.iter().any(|p| p.1 == lo));
            }
            if ys.len() <= e.capacity {
                prop_assert_eq!(pts.len(), ys.len());
            }
        }
    }
}
