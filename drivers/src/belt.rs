//! The belt drive's quadrature encoder on a timer in encoder mode (RM0090
//! "Encoder interface mode": the counter counts the A/B edges up or down with the
//! direction; docs/hardware.md "Reference board": speed = counts per period, 1 mm/s
//! resolution on the wire).
//!
//! embedded-hal 1.0 has no encoder-counter trait, so the board implements
//! [`QuadratureCounter`] on its timer.
//!
//! The belt sensor's one model on every link (docs/hardware.md "The belt
//! sensor's model"): the counter's value at a period's sample is [`count_at`]
//! the belt's travel since period 0, and the speed in the frame is
//! [`BeltEncoder::speed_mm_s`] of it. The board twin and the emulated board set
//! their counter with [`count_at`] and the `arm` application's [`BeltEncoder`]
//! reads it; the wire-level links' sensor model (`rig::sensors`) runs the same
//! pair as [`SampledBelt`].

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

/// The counter's value CNT after `travel_m` metres of belt (m, signed) from
/// where it read 0, at `counts_per_metre` (counts/m, negative when the encoder
/// counts against the belt's positive direction): the whole counts passed (an
/// encoder counts edges, so the count is the travel truncated toward minus
/// infinity), wrapped to the counter's 16 bits (RM0090 "Encoder interface mode",
/// auto-reload 0xFFFF). A non-finite product reads 0. The reference board has
/// 1e6 counts/m (docs/hardware.md "The belt sensor's model").
///
/// The one rule of the board twin's and the emulated board's TIM4 and of the
/// wire-level sensor model ([`SampledBelt`]).
pub fn count_at(travel_m: f64, counts_per_metre: f64) -> u16 {
    let counts = shared::rounding::floor(travel_m * counts_per_metre);
    if !counts.is_finite() {
        return 0;
    }
    // The Euclidean remainder of a whole number, exact: in [0, 65536). Below 2^52 in
    // magnitude the whole number is an `i64` (the same remainder, without libm's fmod).
    if counts.abs() < 4_503_599_627_370_496.0 {
        return (counts as i64).rem_euclid(65536) as u16;
    }
    let r = libm::fmod(counts, 65536.0);
    (if r < 0.0 { r + 65536.0 } else { r }) as u16
}

/// A [`QuadratureCounter`] whose value is set from outside: the wire-level
/// sensor model's counter ([`SampledBelt`]), a scripted counter in tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SetCounter(pub u16);

impl QuadratureCounter for SetCounter {
    fn count(&mut self) -> u16 {
        self.0
    }
}

/// The belt sensor sampled once per control period from the belt's travel: the
/// counter at [`count_at`] the travel, read by a [`BeltEncoder`] (its
/// differencing over the period, wrap and rounding). The counter reads 0 at
/// travel 0 when the model is made, so the first sample at travel 0 (period 0,
/// `t = 0`) reads 0 mm/s: there is no earlier count to difference; from then
/// on the speed carries the encoder's quantisation (one count of change over a
/// period, 1 mm/s at 1 kHz and 10 mm/s at 10 kHz on the reference board, and
/// the count's +-1 jitter from where each sample falls between two counts).
/// The wire-level links' belt reading (`rig::sensors::Sensors`), the same
/// numbers as the board links' timer and `arm` application make
/// (docs/hardware.md "The belt sensor's model").
#[derive(Debug, Clone)]
pub struct SampledBelt {
    counts_per_metre: f64,
    encoder: BeltEncoder<SetCounter>,
}

impl SampledBelt {
    /// The belt sensor of a board with `counts_per_metre` (counts/m, the
    /// board's truth: `board_description::BoardDescription::belt_counts_per_metre`)
    /// read by firmware calibrated to `metres_per_count` (m per count) at control
    /// period `period_s` (s). The reference board: 1e6 and 1e-6.
    ///
    /// # Errors
    /// [`BeltError::InvalidScale`] when `counts_per_metre` is NaN, infinite or
    /// zero, or [`scale`] refuses `metres_per_count` and `period_s`.
    pub fn new(counts_per_metre: f64, metres_per_count: f32, period_s: f32) -> Result<Self, BeltError> {
        if !(counts_per_metre.is_finite() && counts_per_metre != 0.0) {
            return Err(BeltError::InvalidScale);
        }
        Ok(Self { counts_per_metre, encoder: BeltEncoder::new(SetCounter(0), metres_per_count, period_s)? })
    }

    /// The speed (mm/s) the firmware reads at the sample where the belt has
    /// travelled `travel_m` (m) since period 0 (`v_belt t_k` for a belt at
    /// constant speed): [`BeltEncoder::speed_mm_s`] of the counter at
    /// [`count_at`] `travel_m`. Call once per period, in order.
    ///
    /// # Errors
    /// [`BeltError::OutOfRange`] beyond +-[`MAX_SPEED_MM_S`] (the frame then
    /// carries the belt as invalid, as [`crate::frame::assemble`] does on a board).
    pub fn speed_mm_s(&mut self, travel_m: f64) -> Result<i16, BeltError> {
        self.encoder.counter.0 = count_at(travel_m, self.counts_per_metre);
        self.encoder.speed_mm_s()
    }

    /// The counter's value at the last sample.
    pub fn last_count(&self) -> u16 {
        self.encoder.last_count()
    }
}

/// The travel a belt counter reads under a gain fault (issue 80's FMEA: a
/// slipping wheel, a wrong gear ratio, a channel reversed), m: the belt's
/// travel, except that while a gain acts each period's increment is scaled by
/// it, and after it the counter carries on from where the gain left it. The
/// one model of the twin's counter and the SIL rig's sensor model, so both read
/// the same counts ([`count_at`] of [`GainedTravel::read`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GainedTravel {
    read_m: f64,
    last_m: f64,
    offset_m: f64,
}

impl GainedTravel {
    /// The travel the counter reads at a sample where the belt has travelled
    /// `travel_m` (m) since period 0, a gain `gain` acting over the period
    /// since the last sample (`None`: none). Call once per period, in order.
    pub fn read(&mut self, travel_m: f64, gain: Option<f64>) -> f64 {
        let read = match gain {
            Some(g) => {
                let read = self.read_m + g * (travel_m - self.last_m);
                self.offset_m = read - travel_m;
                read
            }
            None if self.offset_m != 0.0 => travel_m + self.offset_m,
            None => travel_m,
        };
        self.read_m = read;
        self.last_m = travel_m;
        read
    }
}

/// The belt's speed from a quadrature counter read once per control period.
#[derive(Debug, Clone)]
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

    /// The counter truncates the travel toward minus infinity and wraps at 16
    /// bits both ways; a reversed encoder counts down.
    #[test]
    fn the_count_is_the_whole_counts_passed_wrapped_to_16_bits() {
        assert_eq!(count_at(0.0, 1e6), 0);
        assert_eq!(count_at(0.999_999e-6, 1e6), 0);
        assert_eq!(count_at(1e-6, 1e6), 1);
        // Just below 0 is the count below 0: 0xFFFF.
        assert_eq!(count_at(-1e-12, 1e6), 0xFFFF);
        assert_eq!(count_at(-1.5e-6, 1e6), 0xFFFE);
        assert_eq!(count_at(0.065_536, 1e6), 0);
        assert_eq!(count_at(0.065_537, 1e6), 1);
        assert_eq!(count_at(-0.065_536, 1e6), 0);
        assert_eq!(count_at(2.5e-6, -1e6), 0xFFFD);
        assert_eq!(count_at(f64::NAN, 1e6), 0);
        assert_eq!(count_at(1.0, f64::INFINITY), 0);
        // Far beyond 2^63 counts the wrap is still exact (the f64's own value mod 2^16).
        assert_eq!(count_at(1e30, 1.0), (1e30f64.rem_euclid(65536.0)) as u16);
    }

    /// The count below 2^52 counts (the integer remainder) is libm's `fmod` form's,
    /// over travels from a micrometre to beyond 2^52 counts, both signs and both
    /// directions of counting, and at the edges of 2^52.
    #[test]
    fn the_integer_remainder_is_the_fmod_form() {
        let fmod_form = |travel_m: f64, cpm: f64| -> u16 {
            let counts = libm::floor(travel_m * cpm);
            if !counts.is_finite() {
                return 0;
            }
            let r = libm::fmod(counts, 65536.0);
            (if r < 0.0 { r + 65536.0 } else { r }) as u16
        };
        let mut travel = 1e-6;
        while travel < 1e12 {
            for t in [travel, -travel, travel * 1.000_123_7, -travel * 0.999_71] {
                for cpm in [1e6, -1e6, 4096.0, 1.0] {
                    assert_eq!(count_at(t, cpm), fmod_form(t, cpm), "travel {t:e} m at {cpm} counts/m");
                }
            }
            travel *= 1.618;
        }
        let whole = 4_503_599_627_370_496.0f64;
        for c in [whole, whole.next_down(), whole.next_up(), -whole, -whole.next_down(), -whole.next_up(), whole + 65536.0] {
            assert_eq!(count_at(c, 1.0), fmod_form(c, 1.0), "{c:e} counts");
        }
    }

    /// The sampled belt: 0 at the first sample (travel 0), then the counts of
    /// each period at the firmware's scale, the sign the belt's, +-1 count where
    /// the samples fall between counts, right across the counter's wrap.
    #[test]
    fn the_sampled_belt_starts_at_0_and_quantises_at_the_rates_scale() {
        // 1 kHz, the reference board: 1 mm/s per count.
        let mut b = SampledBelt::new(1e6, 1e-6, 1e-3).unwrap();
        assert_eq!(b.speed_mm_s(0.0), Ok(0));
        assert_eq!(b.speed_mm_s(-0.4e-3), Ok(-400));
        assert_eq!(b.speed_mm_s(-0.8e-3), Ok(-400));
        assert_eq!(b.last_count(), 0u16.wrapping_sub(800));
        // A travel that falls a hair below a count boundary: one count short, then one over.
        assert_eq!(b.speed_mm_s(-1.2e-3 - 1e-12), Ok(-401));
        assert_eq!(b.speed_mm_s(-1.6e-3), Ok(-399));
        // 10 kHz: 10 mm/s per count; 0.403 m/s reads 400 or 410, averaging 403.
        let mut b = SampledBelt::new(1e6, 1e-6, 1e-4).unwrap();
        assert_eq!(b.speed_mm_s(0.0), Ok(0));
        let speeds: Vec<i16> = (1..=1000).map(|k| b.speed_mm_s(0.403 * f64::from(k) * 1e-4).unwrap()).collect();
        assert!(speeds.iter().all(|&v| v == 400 || v == 410), "{speeds:?}");
        // The counts telescope: the mean is the travel's, to one count over the whole run.
        let sum: i32 = speeds.iter().map(|&v| i32::from(v)).sum();
        assert!((403_000 - 10..=403_000).contains(&sum), "{sum}");
        // The first sample is 0 whatever the speed: no earlier count.
        let mut b = SampledBelt::new(1e6, 1e-6, 1e-3).unwrap();
        assert_eq!(b.speed_mm_s(0.0), Ok(0));
        assert_eq!(b.speed_mm_s(1e-3), Ok(1000));
        // Across the 16-bit wrap, both ways: 1000 counts a period (2^20 counts per
        // metre, travels of whole counts, exact in binary) pass 65 536 counts in 66.
        for sign in [1.0, -1.0] {
            let mut b = SampledBelt::new(1_048_576.0, 1e-6, 1e-3).unwrap();
            for k in 0..=80u32 {
                let want = if k == 0 { 0 } else { 1000 * sign as i16 };
                assert_eq!(b.speed_mm_s(sign * f64::from(1000 * k) / 1_048_576.0), Ok(want), "period {k}");
            }
            assert_eq!(b.last_count(), (sign * 80_000.0f64).rem_euclid(65536.0) as u16);
        }
        // A reversed encoder (negative counts per metre) with a calibration that knows it.
        let mut b = SampledBelt::new(-1e6, -1e-6, 1e-3).unwrap();
        assert_eq!((b.speed_mm_s(0.0), b.speed_mm_s(-0.25e-3)), (Ok(0), Ok(-250)));
        // Beyond 5 m/s: out of range, the counter consumed.
        let mut b = SampledBelt::new(1e6, 1e-6, 1e-3).unwrap();
        assert_eq!(b.speed_mm_s(0.0), Ok(0));
        assert_eq!(b.speed_mm_s(6e-3), Err(BeltError::OutOfRange { delta_counts: 6000 }));
        assert_eq!(b.speed_mm_s(7e-3), Ok(1000));
        for bad in [0.0, f64::NAN, f64::INFINITY] {
            assert_eq!(SampledBelt::new(bad, 1e-6, 1e-3).map(|_| ()), Err(BeltError::InvalidScale));
        }
        assert_eq!(SampledBelt::new(1e6, 1e-6, 0.0).map(|_| ()), Err(BeltError::InvalidScale));
    }

    proptest! {
        /// The counter's wrap by `fmod` is the Euclidean remainder (the rule
        /// the twin used: `rem_euclid`), bit for bit.
        #[test]
        fn the_count_is_the_euclidean_remainder(travel in -1e3f64..1e3, cpm in prop_oneof![-1e9f64..-1.0, 1.0f64..1e9]) {
            let counts = (travel * cpm).floor();
            prop_assert_eq!(count_at(travel, cpm), counts.rem_euclid(65536.0) as u16);
        }

        #[test]
        fn any_delta_within_range_round_trips(start in any::<u16>(), delta in -5000i16..=5000, hz in 250u32..=10_000) {
            let period = 1.0 / hz as f32;
            let mut b = BeltEncoder::new(Script(vec![start, start.wrapping_add_signed(delta)]), 1e-3 * period, period).unwrap();
            prop_assert_eq!(b.speed_mm_s(), Ok(delta));
        }
    }
}
