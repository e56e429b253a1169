//! The step's execution time over a window of periods: the worst exactly, the
//! median from a histogram (fixed size, no heap; resolution [`BIN_TICKS`]).
//! A window closes every [`WINDOW`] steps and a new one starts (tumbling
//! windows: each report covers the last `WINDOW` periods).

/// Steps per window (1 s at the default 1 kHz).
pub const WINDOW: u32 = 1000;
/// Width of a histogram bin, ticks (cycles on silicon: 0.19 us at 168 MHz).
pub const BIN_TICKS: u32 = 32;
/// Bins; a step beyond `BINS * BIN_TICKS` ticks (97 us at 168 MHz) lands in the last.
pub const BINS: usize = 512;

/// What one window measured, ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct WindowSummary {
    /// Steps in the window.
    pub steps: u32,
    /// The longest step, ticks (exact).
    pub worst: u32,
    /// The median step, ticks: the middle of its bin (within `BIN_TICKS / 2`),
    /// or the worst if that is smaller.
    pub median: u32,
}

/// The running window. The bins a window used lie between its lowest and
/// highest (`used`): the median's scan and the next window's clearing cover
/// those only, a few bins for a steady step, not all [`BINS`] (issue 56: the
/// window's close had cost the control interrupt 2 200 cycles, the whole
/// histogram scanned and cleared).
#[derive(Debug, Clone)]
pub struct StepStats {
    bins: [u16; BINS],
    steps: u32,
    worst: u32,
    /// The lowest and highest bins used in the window (`[BINS, 0]` when empty).
    used: [usize; 2],
}

impl Default for StepStats {
    fn default() -> Self {
        Self { bins: [0; BINS], steps: 0, worst: 0, used: [BINS, 0] }
    }
}

impl StepStats {
    /// Records one step of `ticks`; returns the window's summary when it closes.
    pub fn record(&mut self, ticks: u32) -> Option<WindowSummary> {
        let bin = ((ticks / BIN_TICKS) as usize).min(BINS - 1);
        if let Some(b) = self.bins.get_mut(bin) {
            *b = b.saturating_add(1);
        }
        self.used = [self.used[0].min(bin), self.used[1].max(bin)];
        self.steps += 1;
        self.worst = self.worst.max(ticks);
        (self.steps >= WINDOW).then(|| {
            let s = self.summary();
            self.clear();
            s
        })
    }

    /// Starts the next window: the bins used set to zero, the counts reset.
    fn clear(&mut self) {
        let [lo, hi] = self.used;
        if let Some(used) = self.bins.get_mut(lo..=hi) {
            used.fill(0);
        }
        self.steps = 0;
        self.worst = 0;
        self.used = [BINS, 0];
    }

    /// The summary of the window so far (zeros when empty).
    pub fn summary(&self) -> WindowSummary {
        let half = self.steps.div_ceil(2);
        let mut seen = 0u32;
        let mut median = 0;
        let [lo, hi] = self.used;
        for (i, &n) in self.bins.get(lo..=hi).unwrap_or(&[]).iter().enumerate() {
            seen += u32::from(n);
            if n > 0 && seen >= half {
                median = ((lo + i) as u32 * BIN_TICKS + BIN_TICKS / 2).min(self.worst);
                break;
            }
        }
        WindowSummary { steps: self.steps, worst: self.worst, median }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_reports_the_exact_worst_and_the_median_within_half_a_bin() {
        let mut s = StepStats::default();
        let mut out = None;
        // 1000 steps: 5000 + (i mod 100) ticks, one outlier of 40 000.
        for i in 0..WINDOW {
            let ticks = if i == 500 { 40_000 } else { 5_000 + i % 100 };
            out = s.record(ticks);
            if i + 1 < WINDOW {
                assert!(out.is_none());
            }
        }
        let w = out.unwrap();
        assert_eq!((w.steps, w.worst), (WINDOW, 40_000));
        // True median: 5049 or 5050.
        assert!(w.median.abs_diff(5050) <= BIN_TICKS / 2 + 1, "{w:?}");
        // The next window starts empty.
        assert_eq!(s.summary(), WindowSummary::default());
    }

    /// The summary of a full scan of every bin, as before the used range.
    fn full_scan(s: &StepStats) -> WindowSummary {
        let half = s.steps.div_ceil(2);
        let mut seen = 0u32;
        for (i, &n) in s.bins.iter().enumerate() {
            seen += u32::from(n);
            if n > 0 && seen >= half {
                return WindowSummary { steps: s.steps, worst: s.worst, median: (i as u32 * BIN_TICKS + BIN_TICKS / 2).min(s.worst) };
            }
        }
        WindowSummary { steps: s.steps, worst: s.worst, median: 0 }
    }

    #[test]
    fn the_used_range_gives_the_full_scans_summary_and_leaves_every_bin_clear_for_the_next_window() {
        // Windows of random steps (a steady step with outliers, spread ones, ones
        // past the last bin), the summary at every record against a scan of the
        // whole histogram, and after each window's close every bin zero.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut s = StepStats::default();
        for window in 0..6 {
            for i in 0..WINDOW {
                let r = next();
                let ticks = match window % 3 {
                    0 => 5_000 + (r % 200) as u32 + if r % 97 == 0 { 40_000 } else { 0 },
                    1 => (r % 20_000) as u32,
                    _ => (r % (2 * BINS as u64 * u64::from(BIN_TICKS))) as u32,
                };
                let before = s.clone();
                let out = s.record(ticks);
                if i + 1 < WINDOW {
                    assert!(out.is_none());
                    assert_eq!(s.summary(), full_scan(&s), "window {window}, step {i}");
                } else {
                    let mut whole = before;
                    whole.bins[((ticks / BIN_TICKS) as usize).min(BINS - 1)] += 1;
                    whole.steps += 1;
                    whole.worst = whole.worst.max(ticks);
                    assert_eq!(out, Some(full_scan(&whole)), "window {window}");
                    assert!(s.bins.iter().all(|&b| b == 0) && s.steps == 0 && s.worst == 0, "window {window}: not cleared");
                }
            }
        }
    }

    #[test]
    fn a_constant_step_has_its_own_median_and_worst() {
        let mut s = StepStats::default();
        for _ in 0..10 {
            s.record(7);
        }
        assert_eq!(s.summary(), WindowSummary { steps: 10, worst: 7, median: 7 });
    }
}
