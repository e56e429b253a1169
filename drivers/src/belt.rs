//! The belt drive's quadrature encoder on a timer in encoder mode (RM0090
//! "Encoder interface mode": the counter counts the A/B edges up or down with the
//! direction; docs/hardware.md "Reference board": speed = counts per period, 1 mm/s
//! resolution on the wire).
//!
//! embedded-hal 1.0 has no encoder-counter trait, so the board implements
//! [`QuadratureCounter`] on its timer.

use core::fmt;

/// Largest belt speed the frame may carry, mm/s (the firmware rejects a frame
/// beyond 5 m/s).
pub const MAX_SPEED_MM_S: i16 = 5000;

/// A timer in encoder mode, implemented by the board.
pub trait QuadratureCounter {
    /// The timer's 16-bit counter CNT (RM0090 TIMx_CNT), counting up in the belt's
    /// positive direction and wrapping at 0xFFFF <-> 0 (auto-reload 0xFFFF).
    fn count(&mut self) -> u16;
}

/// Errors of the belt encoder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BeltError {
    /// `metres_per_count` or `period_s` is NaN, infinite, zero (or, for the
    /// period, negative), or their ratio is outside `MIN_MM_S_PER_COUNT` to
    /// `MAX_MM_S_PER_COUNT` mm/s per count ([`scale`]).
    InvalidScale,
    /// The speed is beyond +-[`MAX_SPEED_MM_S`]: `delta_counts` counts in one period.
    OutOfRange {
        /// The counter's change over the period.
        delta_counts: i16,
    },
}

impl fmt::Display for BeltError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BeltError::InvalidScale => write!(f, "belt encoder: invalid scale or period"),
            BeltError::OutOfRange { delta_counts } => {
                write!(f, "belt encoder: {delta_counts} counts in one period is beyond +-{MAX_SPEED_MM_S} mm/s")
            }
        }
    }
}

/// The finest belt scale, mm/s per count of change over one period: the
/// counter's 16-bit change in one period must hold the frame's largest speed,
/// [`MAX_SPEED_MM_S`] (5000 / 32767 = 0.153 mm/s per count), or the count would
/// wrap within a period and a fast belt read as a slow one.
pub const MIN_MM_S_PER_COUNT: f32 = MAX_SPEED_MM_S as f32 / 32767.0;

/// The coarsest belt scale, mm/s per count of change over one period: 100 mm/s
/// (the paper's belt speeds, 0.1 to 1 m/s, read to one count in 1 to 10). The
/// reference board's encoder, 1 um per count, gives 1 mm/s per count at 1 kHz
/// and 10 at 10 kHz (docs/hardware.md "Full scales and signs").
pub const MAX_MM_S_PER_COUNT: f32 = 100.0;

/// mm/s per count of change over one period of `period_s`, at `metres_per_count`
/// (negative flips the direction). The one rule of the firmware, the bring-up's
/// `Restore` and the flash record, the backup files and the scenario files'
/// `[calibration]`.
///
/// # Errors
/// [`BeltError::InvalidScale`] when either is NaN, infinite or zero (the period
/// negative), or the scale's magnitude is outside [`MIN_MM_S_PER_COUNT`] to
/// [`MAX_MM_S_PER_COUNT`] mm/s per count: no speed is ever inf or NaN, and a
/// 16-bit count a period holds every speed the frame carries.
pub fn scale(metres_per_count: f32, period_s: f32) -> Result<f32, BeltError> {
    let mm_s_per_count = metres_per_count * 1000.0 / period_s;
    let valid = period_s > 0.0 && period_s.is_finite() && metres_per_count.is_finite();
    if valid && (MIN_MM_S_PER_COUNT..=MAX_MM_S_PER_COUNT).contains(&mm_s_per_count.abs()) {
        Ok(mm_s_per_count)
    } else {
        Err(BeltError::InvalidScale)
    }
}

/// The belt's speed from a quadrature counter read once per control period.
#[derive(Debug)]
pub struct BeltEncoder<C> {
    counter: C,
    last: u16,
    /// mm/s per count of change over one period.
    mm_s_per_count: f32,
}

impl<C: QuadratureCounter> BeltEncoder<C> {
    /// A belt encoder on `counter`: `metres_per_count` of belt travel per counter
    /// step (m, negative to flip the direction), read every `period_s` (s, the
    /// control period). Reads the counter once, so the first
    /// [`BeltEncoder::speed_mm_s`] gives the speed over one period. On the
    /// reference board `metres_per_count = 1e-3 * period_s` (one count per period
    /// is 1 mm/s).
    ///
    /// # Errors
    /// [`BeltError::InvalidScale`].
    pub fn new(mut counter: C, metres_per_count: f32, period_s: f32) -> Result<Self, BeltError> {
        let mm_s_per_count = scale(metres_per_count, period_s)?;
        let last = counter.count();
        Ok(Self { counter, last, mm_s_per_count })
    }

    /// Gives the counter back.
    pub fn release(self) -> C {
        self.counter
    }

    /// The counter's value at the last read (bring-up: raw readings).
    pub fn last_count(&self) -> u16 {
        self.last
    }

    /// Replaces the scale (bring-up), as [`BeltEncoder::new`] checks it.
    ///
    /// # Errors
    /// [`BeltError::InvalidScale`]; the old scale stays.
    pub fn set_scale(&mut self, metres_per_count: f32, period_s: f32) -> Result<(), BeltError> {
        self.mm_s_per_count = scale(metres_per_count, period_s)?;
        Ok(())
    }

    /// The belt speed over the period since the previous call (or [`BeltEncoder::new`]),
    /// mm/s rounded to the nearest (half away from zero), in
    /// `[-MAX_SPEED_MM_S, MAX_SPEED_MM_S]`. Call once per period. The counter may
    /// wrap; it must not move more than 32767 counts in one period.
    ///
    /// # Errors
    /// [`BeltError::OutOfRange`] beyond +-5000 mm/s (the counter is consumed
    /// anyway, so the next call measures the next period).
    pub fn speed_mm_s(&mut self) -> Result<i16, BeltError> {
        let now = self.counter.count();
        // Two's complement difference: right across the 0xFFFF <-> 0 wrap.
        let delta_counts = now.wrapping_sub(self.last) as i16;
        self.last = now;
        let speed = libm::roundf(delta_counts as f32 * self.mm_s_per_count);
        if speed.abs() <= MAX_SPEED_MM_S as f32 { Ok(speed as i16) } else { Err(BeltError::OutOfRange { delta_counts }) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A counter that replays scripted values (the last one repeats).
    struct Script(Vec<u16>);

    impl QuadratureCounter for Script {
        fn count(&mut self) -> u16 {
            if self.0.len() > 1 { self.0.remove(0) } else { self.0.first().copied().unwrap_or(0) }
        }
    }

    const TS: f32 = 1e-3;

    fn belt(counts: &[u16], metres_per_count: f32) -> BeltEncoder<Script> {
        BeltEncoder::new(Script(counts.to_vec()), metres_per_count, TS).unwrap()
    }

    #[test]
    fn wraps_across_zero_both_ways() {
        // One count per period is 1 mm/s.
        let mut b = belt(&[0xFFF0, 0x0010, 0xFFF0, 0xFFF0], 1e-6);
        assert_eq!(b.speed_mm_s(), Ok(32));
        assert_eq!(b.speed_mm_s(), Ok(-32));
        assert_eq!(b.speed_mm_s(), Ok(0));
        let mut b = belt(&[0x0000, 0xFFFF, 0x0000], 1e-6);
        assert_eq!(b.speed_mm_s(), Ok(-1));
        assert_eq!(b.speed_mm_s(), Ok(1));
    }

    #[test]
    fn rounds_to_the_nearest_mm_s() {
        // 0.25 mm/s per count: 2 counts = 0.5 -> 1 (half away from zero), 5 -> 1.25 -> 1.
        let mut b = belt(&[100, 102, 107, 101, 95], 0.25e-6);
        assert_eq!(b.speed_mm_s(), Ok(1));
        assert_eq!(b.speed_mm_s(), Ok(1));
        assert_eq!(b.speed_mm_s(), Ok(-2)); // -6 counts = -1.5 -> -2
        assert_eq!(b.speed_mm_s(), Ok(-2)); // -6 again
        // A reversed encoder (negative scale) flips the sign.
        let mut b = belt(&[0, 40], -1e-6);
        assert_eq!(b.speed_mm_s(), Ok(-40));
    }

    #[test]
    fn beyond_5_m_s_is_out_of_range_and_consumes_the_counter() {
        let mut b = belt(&[0, 5000, 10001, 10001 - 5000, 10001 - 10001], 1e-6);
        assert_eq!(b.speed_mm_s(), Ok(5000));
        assert_eq!(b.speed_mm_s(), Err(BeltError::OutOfRange { delta_counts: 5001 }));
        assert_eq!(b.speed_mm_s(), Ok(-5000));
        assert_eq!(b.speed_mm_s(), Err(BeltError::OutOfRange { delta_counts: -5001 }));
        let mut b = belt(&[0, 0x8000], 1e-6);
        assert_eq!(b.speed_mm_s(), Err(BeltError::OutOfRange { delta_counts: i16::MIN }));
    }

    #[test]
    fn bad_scales_are_rejected() {
        let new = |m: f32, p: f32| BeltEncoder::new(Script(vec![0]), m, p).map(|_| ());
        assert_eq!(new(1e-6, 1e-3), Ok(()));
        assert_eq!(new(0.0, 1e-3), Err(BeltError::InvalidScale));
        assert_eq!(new(1e-6, 0.0), Err(BeltError::InvalidScale));
        assert_eq!(new(1e-6, -1e-3), Err(BeltError::InvalidScale));
        assert_eq!(new(f32::NAN, 1e-3), Err(BeltError::InvalidScale));
        assert_eq!(new(1e-6, f32::NAN), Err(BeltError::InvalidScale));
        assert_eq!(new(1e-6, f32::INFINITY), Err(BeltError::InvalidScale));
        assert_eq!(new(f32::INFINITY, 1e-3), Err(BeltError::InvalidScale));
        assert_eq!(new(1e30, 1e-9), Err(BeltError::InvalidScale));
        assert_eq!(new(1e-45, 1e30), Err(BeltError::InvalidScale)); // underflows to 0 mm/s per count
        // Too fine a scale (5 m/s wraps the counter within a period), too coarse a one.
        assert_eq!(new(1e-8, 1e-3), Err(BeltError::InvalidScale));
        assert_eq!(new(-1e-6, 1e-3), Ok(()));
        assert_eq!(new(1.01e-4, 1e-3), Err(BeltError::InvalidScale));
        assert_eq!(new(0.99e-4, 1e-3), Ok(()));
    }

    proptest! {
        #[test]
        fn any_delta_within_range_round_trips(start in any::<u16>(), delta in -5000i16..=5000, hz in 250u32..=10_000) {
            let period = 1.0 / hz as f32;
            let mut b = BeltEncoder::new(Script(vec![start, start.wrapping_add_signed(delta)]), 1e-3 * period, period).unwrap();
            prop_assert_eq!(b.speed_mm_s(), Ok(delta));
        }
    }
}
