//! The step's execution time over a window of periods: the worst exactly, the
//! median from a histogram (fixed size, no heap; resolution [`BIN_TICKS`]).
//! A window closes every [`WINDOW`] steps and a new one starts (tumbling
//! windows: each report covers the last `WINDOW` periods).
//!
//! Two histograms in turn: a window's close only switches to the other
//! ([`StepStats::record`], in the control interrupt); its summary and clearing
//! ([`StepStats::finish`]) are left for between two ticks (the image's idle
//! loop; issue 56: the close had cost the control interrupt 500 to 900 cycles
//! more than any other period, 2 200 before the used range).

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
pub struct Histogram {
    bins: [u16; BINS],
    steps: u32,
    worst: u32,
    /// The lowest and highest bins used in the window (`[BINS, 0]` when empty).
    used: [usize; 2],
}

impl Default for Histogram {
    fn default() -> Self {
        Self { bins: [0; BINS], steps: 0, worst: 0, used: [BINS, 0] }
    }
}

/// The running window and the last one closed, in two histograms.
#[derive(Debug, Clone, Default)]
pub struct StepStats {
    windows: [Histogram; 2],
    /// The running window's histogram (0 or 1).
    running: usize,
    /// The other histogram holds a closed window not yet finished.
    closed: bool,
}

impl StepStats {
    /// Records one step of `ticks`; returns whether this closed the window
    /// (its summary then comes from [`StepStats::finish`]). Cheap at a close
    /// too: the next window runs in the other histogram. A window closed
    /// while the last one was not finished (nothing ran between two ticks for
    /// a whole window) drops the last one's summary, cleared here.
    pub fn record(&mut self, ticks: u32) -> bool {
        let r = self.running & 1;
        if !self.windows[r].record(ticks) {
            return false;
        }
        if self.closed {
            let _ = self.finish();
        }
        self.running = r ^ 1;
        self.closed = true;
        true
    }

    /// The summary of the window closed last, and its histogram cleared for
    /// the window after the running one; `None` when there is none to finish.
    pub fn finish(&mut self) -> Option<WindowSummary> {
        if !core::mem::take(&mut self.closed) {
            return None;
        }
        let h = &mut self.windows[(self.running & 1) ^ 1];
        let s = h.summary();
        h.clear();
        Some(s)
    }

    /// The summary of the running window so far (zeros when empty).
    pub fn summary(&self) -> WindowSummary {
        self.windows[self.running & 1].summary()
    }
}

impl Histogram {
    /// Records one step of `ticks`; returns whether the window is full.
    fn record(&mut self, ticks: u32) -> bool {
        let bin = ((ticks / BIN_TICKS) as usize).min(BINS - 1);
        if let Some(b) = self.bins.get_mut(bin) {
            *b = b.saturating_add(1);
        }
        self.used = [self.used[0].min(bin), self.used[1].max(bin)];
        self.steps += 1;
        self.worst = self.worst.max(ticks);
        self.steps >= WINDOW
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
    fn summary(&self) -> WindowSummary {
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
        // 1000 steps: 5000 + (i mod 100) ticks, one outlier of 40 000.
        for i in 0..WINDOW {
            let ticks = if i == 500 { 40_000 } else { 5_000 + i % 100 };
            assert_eq!(s.record(ticks), i + 1 == WINDOW);
            if i + 1 < WINDOW {
                assert_eq!(s.finish(), None, "nothing closed yet");
            }
        }
        // The next window starts empty, the closed one is finished once.
        assert_eq!(s.summary(), WindowSummary::default());
        let w = s.finish().unwrap();
        assert_eq!(s.finish(), None);
        assert_eq!((w.steps, w.worst), (WINDOW, 40_000));
        // True median: 5049 or 5050.
        assert!(w.median.abs_diff(5050) <= BIN_TICKS / 2 + 1, "{w:?}");
    }

    /// The summary of a full scan of every bin, as before the used range.
    fn full_scan(h: &Histogram) -> WindowSummary {
        let half = h.steps.div_ceil(2);
        let mut seen = 0u32;
        for (i, &n) in h.bins.iter().enumerate() {
            seen += u32::from(n);
            if n > 0 && seen >= half {
                return WindowSummary { steps: h.steps, worst: h.worst, median: (i as u32 * BIN_TICKS + BIN_TICKS / 2).min(h.worst) };
            }
        }
        WindowSummary { steps: h.steps, worst: h.worst, median: 0 }
    }

    #[test]
    fn each_window_is_summed_up_as_a_scan_of_its_whole_histogram_and_every_bin_is_clear_for_the_window_after() {
        // Windows of random steps (a steady step with outliers, spread ones, ones
        // past the last bin): the running summary at every record, and each
        // closed window's, against a scan of the whole histogram (kept aside);
        // finished between two ticks, or not at all before the next close (then
        // at that close: the window is not lost). After a finish its histogram
        // is all zeros.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut s = StepStats::default();
        let mut shadow = Histogram::default();
        let mut expected = Vec::new();
        let mut got = Vec::new();
        for window in 0..9 {
            for _ in 0..WINDOW {
                let r = next();
                let ticks = match window % 3 {
                    0 => 5_000 + (r % 200) as u32 + if r % 97 == 0 { 40_000 } else { 0 },
                    1 => (r % 20_000) as u32,
                    _ => (r % (2 * BINS as u64 * u64::from(BIN_TICKS))) as u32,
                };
                let closed = s.record(ticks);
                shadow.bins[((ticks / BIN_TICKS) as usize).min(BINS - 1)] += 1;
                shadow.steps += 1;
                shadow.worst = shadow.worst.max(ticks);
                if closed {
                    expected.push(full_scan(&shadow));
                    shadow = Histogram::default();
                    assert_eq!(s.summary(), WindowSummary::default(), "window {window}: the next starts empty");
                    // Every other window is finished at once; the rest wait for the next close.
                    if window % 2 == 0 {
                        got.push(s.finish().expect("a closed window"));
                        let done = &s.windows[(s.running & 1) ^ 1];
                        assert!(done.bins.iter().all(|&b| b == 0) && done.steps == 0 && done.used == [BINS, 0], "window {window}");
                    }
                } else {
                    assert_eq!(s.summary(), full_scan(&shadow), "window {window}");
                }
            }
        }
        // Windows left unfinished at a close were finished there (lost, if
        // `record` had not): their summaries are not returned, but the ones
        // finished are each their window's.
        for g in &got {
            assert!(expected.contains(g), "{g:?}");
        }
        assert_eq!(got.len(), 5);
        assert_eq!(got[0], expected[0]);
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
