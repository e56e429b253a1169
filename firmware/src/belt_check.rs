//! The belt speed's plausibility (issue 80): a reading that jumps between two
//! periods by more than any belt can change speed in one is a sensor fault.
//!
//! The belt is driven (docs/hardware.md "Sensors": the belt drive's quadrature
//! encoder, speed = counts per period); its speed changes through the drive's
//! ramp and the belt's inertia, at a few m/s^2 at most. A reading whose change
//! from the last period's exceeds [`JUMP_MPS`] is therefore not the belt: the
//! encoder's sign or scale changed (a reversed or re-geared sensor read from
//! mid-run), or its count stuck (the speed reads 0 from one period to the next).
//! The friction the law compensates follows the belt's reading: the hybrid
//! arm read the belt reversed from mid-run was dragged 30 to 231 mm before the
//! friction-sign check (which waits for the slip's sign) stopped it, in 9 of
//! 200 runs of the FMEA (docs/hardware.md "FMEA").
//!
//! **The bound.** [`JUMP_MPS`], 0.04 m/s, against two sources of healthy change:
//! the count's quantisation (one count per period each side: 2 counts of 1 um
//! at 10 kHz, 20 mm/s, the largest the envelope's rates make) and the belt's own
//! acceleration (at 1 kHz, 0.04 m/s in a period is 40 m/s^2, beyond any belt
//! drive; at 250 Hz 10 m/s^2). The envelope's belt runs at 0.1 to 1 m/s, so a
//! reversal jumps at least 0.2 m/s, a stuck count 0.1 m/s and a halved scale
//! 0.05 m/s: each is seen at the period it starts. A scale or sign wrong from
//! the first period makes no jump, and stays the friction-sign check's.
//!
//! **The first readings.** The speed is counts per period: the run's first
//! frame has no period before it and reads 0, and the second's change from it
//! is the belt's start, not a jump; the second may read part of a period too (a
//! counter read as the belt's edges arrive: the emulated board's TIM4 reads
//! half the first period's counts at 8.7 kHz, then the full count). The step
//! folds in every reading, and counts a jump from the run's fourth period on
//! ([`FIRST_PERIOD`]).

/// The largest change of the belt's speed reading between two periods, m/s (module docs).
pub const JUMP_MPS: f32 = 0.04;

/// The run's first period (counted from 0) whose jump counts (module docs: the
/// first reads 0, the second may read part of a period).
pub const FIRST_PERIOD: u32 = 3;

/// The check's state across periods: the last reading (NaN before the first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeltMonitor {
    /// The last reading, m/s; NaN before the first.
    last: f32,
}

impl Default for BeltMonitor {
    /// No reading yet: the first is compared with nothing.
    fn default() -> Self {
        Self { last: f32::NAN }
    }
}

impl BeltMonitor {
    /// Folds in the belt speed reading `v_belt` (m/s, decoded from the
    /// frame's count); returns whether it jumped from the last reading by more
    /// than [`JUMP_MPS`] (never for the first reading; a non-finite reading
    /// never jumps, and the frame's decoding makes none). The step folds in
    /// every trusted frame's reading and ignores the answer before the run's
    /// [`FIRST_PERIOD`] (module docs).
    #[inline(always)]
    pub fn update(&mut self, v_belt: f32) -> bool {
        // One comparison, false against the first reading's NaN.
        let jumped = (v_belt - self.last).abs() > JUMP_MPS;
        self.last = v_belt;
        jumped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A steady belt read with the count's quantisation (one count of 1 um per
    /// period either way, at every rate of the envelope) never trips; the
    /// first reading's 0 never trips; a reversal, a stuck count or a halved
    /// scale of any belt of the envelope trips at the period it starts.
    #[test]
    fn a_quantised_belt_passes_and_a_reversed_stuck_or_halved_reading_trips_at_once() {
        for rate in [250.0f32, 1000.0, 4000.0, 10_000.0] {
            let count = 1e-6 * rate; // one count per period, m/s
            for v in [-1.0f32, -0.5, -0.1, 0.1, 1.0] {
                // The run's first reading (0) is not folded in; the second is the first.
                let mut b = BeltMonitor::default();
                for k in 1..200usize {
                    let jitter = [0.0, count, -count, 0.0][k % 4];
                    assert!(!b.update(v + jitter), "rate {rate}, v {v}, period {k}");
                }
                for (what, read) in [("reversed", -v), ("stuck", 0.0), ("halved", 0.5 * v)] {
                    let mut c = b;
                    assert!(c.update(read), "rate {rate}, v {v}: {what}");
                }
            }
        }
    }

    /// The first reading never jumps, whatever it is; a NaN is not a reading
    /// to compare with (the decoding makes none).
    #[test]
    fn the_first_reading_is_compared_with_nothing() {
        for v in [-1.0f32, 0.0, 0.7] {
            assert!(!BeltMonitor::default().update(v));
        }
        let mut b = BeltMonitor::default();
        b.update(-0.5);
        assert!(!b.update(f32::NAN));
    }
}
