//! The animation's frames: the samples of a run of any length, thinned to a
//! frame every [`FRAME_STEP_S`] of simulated time (100 Hz) and at most
//! [`MAX_FRAMES`] frames (the step doubled whenever they would be more), in
//! memory that does not grow with the run.

/// The frame spacing a short run gets, s of simulated time (100 frames per simulated second).
pub const FRAME_STEP_S: f64 = 0.01;

/// The most frames a page holds: a run longer than `MAX_FRAMES * FRAME_STEP_S`
/// (50 s) gets a frame every 20 ms, 40 ms, ... of simulated time.
pub const MAX_FRAMES: usize = 5_000;

/// One frame of the animation: the state the arm view draws at time `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Time, s.
    pub t: f64,
    /// Joint angles `[theta1, theta2]`, rad (from the downward vertical).
    pub theta: [f64; 2],
    /// Contact force `[f_t, f_n]` on the tip, N.
    pub force: [f64; 2],
    /// Contact mode code (0 flight, 1 sliding, 2 sticking; [`crate::plot::mode_code`]).
    pub mode: u8,
    /// The reference `z_t*`, m (closed-loop runs; NaN otherwise).
    pub z_t_ref: f64,
    /// Motor torques `[u1, u2]`, N m (closed-loop runs; NaN otherwise).
    pub u: [f64; 2],
}

/// The frames kept so far, evenly spaced by `step` (s) from the first sample's time.
#[derive(Debug, Clone)]
pub struct Frames {
    step: f64,
    t0: Option<f64>,
    /// The index (in steps from `t0`) the next kept frame must reach.
    next: u64,
    kept: Vec<Frame>,
    /// The latest sample, so that the run's last instant is a frame too.
    last: Option<Frame>,
    samples: u64,
}

impl Default for Frames {
    fn default() -> Self {
        Self { step: FRAME_STEP_S, t0: None, next: 0, kept: Vec::new(), last: None, samples: 0 }
    }
}

impl Frames {
    /// Adds the next sample (in time order); kept when it is the first at or
    /// after the next multiple of the step. Samples with a non-finite time are ignored.
    pub fn push(&mut self, f: Frame) {
        if !f.t.is_finite() {
            return;
        }
        self.samples += 1;
        let t0 = *self.t0.get_or_insert(f.t);
        let index = self.index(f.t, t0);
        if self.kept.is_empty() || index >= self.next {
            self.kept.push(f);
            self.next = index + 1;
            if self.kept.len() > MAX_FRAMES {
                self.thin(t0);
            }
        }
        self.last = Some(f);
    }

    /// The step index of time `t` (s) from `t0` (a millionth of a step of slack
    /// for times such as `k * 1e-3` that land just below a multiple).
    fn index(&self, t: f64, t0: f64) -> u64 {
        ((t - t0) / self.step + 1e-6).floor().max(0.0) as u64
    }

    /// Keeps every other frame and doubles the step.
    fn thin(&mut self, t0: f64) {
        let mut i = 0;
        self.kept.retain(|_| {
            i += 1;
            i % 2 == 1
        });
        self.step *= 2.0;
        self.next = self.kept.last().map_or(0, |f| self.index(f.t, t0) + 1);
    }

    /// The frames, the run's last sample included, and their nominal spacing (s).
    pub fn finish(mut self) -> (Vec<Frame>, f64) {
        if let Some(last) = self.last
            && self.kept.last().is_none_or(|f| f.t < last.t)
        {
            self.kept.push(last);
        }
        (self.kept, self.step)
    }

    /// Samples pushed so far (finite times).
    pub fn samples(&self) -> u64 {
        self.samples
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f64) -> Frame {
        Frame { t, theta: [t, -t], force: [0.0; 2], mode: 1, z_t_ref: f64::NAN, u: [f64::NAN; 2] }
    }

    #[test]
    fn a_short_run_at_1_khz_gives_a_frame_every_10_ms_and_its_last_sample() {
        let mut f = Frames::default();
        for k in 0..=1234 {
            f.push(at(k as f64 * 1e-3));
        }
        assert_eq!(f.samples(), 1235);
        let (frames, step) = f.finish();
        assert_eq!(step, 0.01);
        assert_eq!(frames.len(), 124 + 1, "0, 0.01, ..., 1.23 and the last sample 1.234");
        for (k, fr) in frames.iter().take(124).enumerate() {
            assert!((fr.t - k as f64 * 0.01).abs() < 1e-9, "frame {k} at {}", fr.t);
        }
        assert!((frames.last().unwrap().t - 1.234).abs() < 1e-12);
    }

    #[test]
    fn a_long_run_is_thinned_under_the_cap_with_even_spacing() {
        let mut f = Frames::default();
        for k in 0..=300_000 {
            f.push(at(k as f64 * 1e-3));
        }
        let (frames, step) = f.finish();
        assert!(frames.len() <= MAX_FRAMES + 1, "{}", frames.len());
        assert!(frames.len() > MAX_FRAMES / 2, "{}", frames.len());
        assert!((step - 0.08).abs() < 1e-12, "300 s in at most 5000 frames: 80 ms, got {step}");
        for w in frames.windows(2).take(frames.len() - 2) {
            assert!((w[1].t - w[0].t - step).abs() < 1e-6, "{} -> {}", w[0].t, w[1].t);
        }
        assert_eq!(frames.last().unwrap().t, 300.0);
    }

    #[test]
    fn coarse_samples_are_all_kept_and_bad_times_ignored() {
        let mut f = Frames::default();
        f.push(at(f64::NAN));
        for k in 0..10 {
            f.push(at(k as f64 * 0.05));
        }
        let (frames, _) = f.finish();
        assert_eq!(frames.len(), 10);
    }
}
