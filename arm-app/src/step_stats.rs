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

/// The running window.
#[derive(Debug, Clone)]
pub struct StepStats {
    bins: [u16; BINS],
    steps: u32,
    worst: u32,
}

impl Default for StepStats {
    fn default() -> Self {
        Self { bins: [0; BINS], steps: 0, worst: 0 }
    }
}

impl StepStats {
    /// Records one step of `ticks`; returns the window's summary when it closes.
    pub fn record(&mut self, ticks: u32) -> Option<WindowSummary> {
        let bin = ((ticks / BIN_TICKS) as usize).min(BINS - 1);
        if let Some(b) = self.bins.get_mut(bin) {
            *b = b.saturating_add(1);
        }
        self.steps += 1;
        self.worst = self.worst.max(ticks);
        (self.steps >= WINDOW).then(|| {
            let s = self.summary();
            *self = Self::default();
            s
        })
    }

    /// The summary of the window so far (zeros when empty).
    pub fn summary(&self) -> WindowSummary {
        let half = self.steps.div_ceil(2);
        let mut seen = 0u32;
        let mut median = 0;
        for (i, &n) in self.bins.iter().enumerate() {
            seen += u32::from(n);
            if n > 0 && seen >= half {
                median = (i as u32 * BIN_TICKS + BIN_TICKS / 2).min(self.worst);
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

    #[test]
    fn a_constant_step_has_its_own_median_and_worst() {
        let mut s = StepStats::default();
        for _ in 0..10 {
            s.record(7);
        }
        assert_eq!(s.summary(), WindowSummary { steps: 10, worst: 7, median: 7 });
    }
}
