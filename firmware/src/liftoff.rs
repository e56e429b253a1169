//! Lift-off detection from what is measured (docs/hardware.md "Lift-off detection").
//!
//! Rule: lift-off is declared when the measured normal force stays below
//! `lift_off_force` (default 0.5 N, 25 times the load cell's 20 mN noise) for
//! `lift_off_confirm` consecutive periods (default 2), or at once when the tip
//! height above the belt from the encoders exceeds `lift_off_height` (default
//! 1 mm, about 12 times the tip's encoder resolution `l * 2 pi / 2^14` = 0.08 mm).
//! Contact is declared back when the normal force exceeds `touchdown_force`
//! (default 1 N, hysteresis against chatter) and the height is below
//! `lift_off_height`. A lift-off is therefore detected 2 periods after the force
//! vanishes (1 if the height test fires first), and a noise-only false alarm
//! needs two consecutive 25-sigma excursions.

/// The detector's state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LiftOffDetector {
    /// Whether lift-off is currently declared.
    pub lifted: bool,
    low_count: u8,
}

/// Thresholds of the rule (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiftOffRule {
    /// N.
    pub lift_off_force: f32,
    /// m.
    pub lift_off_height: f32,
    /// Periods.
    pub confirm: u8,
    /// N.
    pub touchdown_force: f32,
}

impl LiftOffDetector {
    /// Updates with the measured normal force `f_n` (N) and tip height above the belt
    /// `height` (m); returns whether lift-off is declared.
    pub fn update(&mut self, rule: &LiftOffRule, f_n: f32, height: f32) -> bool {
        if self.lifted {
            if f_n > rule.touchdown_force && height < rule.lift_off_height {
                self.lifted = false;
                self.low_count = 0;
            }
        } else if height > rule.lift_off_height {
            self.lifted = true;
        } else if f_n < rule.lift_off_force {
            self.low_count = self.low_count.saturating_add(1);
            if self.low_count >= rule.confirm {
                self.lifted = true;
            }
        } else {
            self.low_count = 0;
        }
        self.lifted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RULE: LiftOffRule = LiftOffRule { lift_off_force: 0.5, lift_off_height: 1e-3, confirm: 2, touchdown_force: 1.0 };

    /// A reproducible Gaussian noise source (xorshift + Box-Muller).
    struct Noise(u64);
    impl Noise {
        fn uniform(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) as f32
        }
        fn gauss(&mut self, sigma: f32) -> f32 {
            let (u1, u2) = (self.uniform().max(1e-12), self.uniform());
            sigma * libm::sqrtf(-2.0 * libm::logf(u1)) * libm::cosf(core::f32::consts::TAU * u2)
        }
    }

    #[test]
    fn latency_is_two_periods_and_no_false_alarms_at_the_default_noise() {
        let mut noise = Noise(0x9E37_79B9_7F4A_7C15);
        let mut false_alarms = 0;
        let mut latencies = [0u32; 0].to_vec();
        for episode in 0..200 {
            let mut d = LiftOffDetector::default();
            // 500 periods of contact at 2 N, with 20 mN rms noise: no alarm.
            for _ in 0..500 {
                if d.update(&RULE, 2.0 + noise.gauss(0.02), 0.0) {
                    false_alarms += 1;
                }
            }
            // The force drops to zero (the tip leaves); the height rises slowly.
            let mut detected = None;
            for k in 0..50u32 {
                let height = 2e-5 * k as f32 * (episode % 3) as f32;
                if d.update(&RULE, noise.gauss(0.02), height) && detected.is_none() {
                    detected = Some(k + 1);
                }
            }
            latencies.push(detected.expect("lift-off detected"));
        }
        assert_eq!(false_alarms, 0);
        assert!(latencies.iter().all(|&l| l <= 2), "{latencies:?}");
    }

    #[test]
    fn height_alone_declares_lift_off_and_hysteresis_holds_it() {
        let mut d = LiftOffDetector::default();
        assert!(d.update(&RULE, 5.0, 2e-3), "a high tip is off the belt whatever the force reads");
        assert!(d.update(&RULE, 0.8, 0.0), "0.8 N is below the touchdown threshold: still lifted");
        assert!(!d.update(&RULE, 1.5, 0.0));
    }
}
