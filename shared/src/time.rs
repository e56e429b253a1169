//! Time as integers: the control period and the sample instants that both sides
//! of the wire compute the same way.
//!
//! One unit, the microsecond (the wire's `t_us`): an [`Instant`] is microseconds
//! since the start of the run (simulated time in SIL and PIL, the tick timer's
//! count on a board), a [`Period`] a whole number of microseconds. Period `k`
//! samples at `t_k = k * period` exactly, on the plant's side and the firmware's;
//! floating-point seconds are derived from these integers once where a law needs
//! them (`Period::as_secs_f32` for the firmware's `dt`).
//!
//! A control rate whose period is not a whole number of microseconds (6 kHz:
//! 166.67 us) is rounded once, here ([`Period::from_rate_hz`]), to the nearest
//! microsecond (167 us, so the loop runs at 5988 Hz); every other part of the
//! system uses that period, so no two parts disagree about a deadline and no
//! stamp drifts from plant time.

/// A point in time: microseconds since the start of the run ([`Instant::from_us`],
/// [`Instant::as_us`]). `Instant + Duration` and `Instant - Instant` saturate (a
/// clock that far reads as late, never wraps round to early; an earlier minus a
/// later instant is 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Instant(u64);

/// A span of time in microseconds ([`Duration::from_us`], [`Duration::as_us`]);
/// `Duration + Duration` saturates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Duration(u64);

/// The control period: a whole, non-zero number of microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Period(u32);

/// Why a rate or period has no [`Period`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TimeError {
    /// The rate is not finite and positive, or its period rounds to 0 us or
    /// beyond `u32::MAX` us.
    #[error("control rate {0} Hz has no period of 1 us to 4294 s")]
    Rate(f64),
    /// A period of 0 us.
    #[error("a control period of 0 us")]
    Zero,
}

impl Period {
    /// 1 ms (1 kHz, the default control rate).
    pub const MILLISECOND: Period = Period(1000);

    /// A period of `us` microseconds.
    ///
    /// # Errors
    /// [`TimeError::Zero`] for 0.
    pub const fn from_us(us: u32) -> Result<Self, TimeError> {
        if us == 0 { Err(TimeError::Zero) } else { Ok(Self(us)) }
    }

    /// The period of `rate_hz` (Hz), rounded once to the nearest microsecond
    /// (`round(1e6 / rate_hz)`; exact for rates that divide 1 MHz).
    ///
    /// # Errors
    /// [`TimeError::Rate`] for a rate that is not finite and positive or whose
    /// period rounds to 0 us or past `u32::MAX` us.
    pub fn from_rate_hz(rate_hz: f64) -> Result<Self, TimeError> {
        let us = libm::round(1e6 / rate_hz);
        if rate_hz.is_finite() && rate_hz > 0.0 && us >= 1.0 && us <= u32::MAX as f64 {
            Ok(Self(us as u32))
        } else {
            Err(TimeError::Rate(rate_hz))
        }
    }

    /// Microseconds.
    pub const fn as_us(self) -> u64 {
        self.0 as u64
    }

    /// As a [`Duration`].
    pub const fn duration(self) -> Duration {
        Duration(self.0 as u64)
    }

    /// Seconds, `f64` (`us / 1e6`, correctly rounded: `0.001` exactly as written at 1 kHz).
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 / 1e6
    }

    /// Seconds, `f32` (`us / 1e6` in `f32`, correctly rounded): the firmware's `dt`.
    pub fn as_secs_f32(self) -> f32 {
        self.0 as f32 / 1e6
    }

    /// The rate this period runs at, Hz (`1e6 / us`).
    pub fn rate_hz(self) -> f64 {
        1e6 / self.0 as f64
    }

    /// The instant of sample `k`: `k * period`, exactly (saturating at `u64::MAX` us).
    pub const fn sample(self, k: u64) -> Instant {
        Instant(k.saturating_mul(self.0 as u64))
    }
}

impl Instant {
    /// The instant `us` microseconds after the start of the run.
    #[inline]
    pub const fn from_us(us: u64) -> Self {
        Self(us)
    }

    /// Microseconds since the start of the run.
    pub const fn as_us(self) -> u64 {
        self.0
    }

    /// Seconds since the start, `f64` (`us / 1e6`).
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 / 1e6
    }

    /// `self - earlier`, 0 when `earlier` is later.
    pub const fn saturating_since(self, earlier: Instant) -> Duration {
        Duration(self.0.saturating_sub(earlier.0))
    }

    /// `self + d`, saturating at `u64::MAX` us (a clock that far reads as late,
    /// never wraps round to early).
    pub const fn saturating_add(self, d: Duration) -> Instant {
        Instant(self.0.saturating_add(d.0))
    }
}

impl Duration {
    /// A span of `us` microseconds.
    #[inline]
    pub const fn from_us(us: u64) -> Self {
        Self(us)
    }

    /// Microseconds.
    pub const fn as_us(self) -> u64 {
        self.0
    }

    /// `self + other`, saturating at `u64::MAX` us.
    pub const fn saturating_add(self, other: Duration) -> Duration {
        Duration(self.0.saturating_add(other.0))
    }
}

impl core::ops::Add<Duration> for Instant {
    type Output = Instant;
    /// [`Instant::saturating_add`].
    #[inline]
    fn add(self, d: Duration) -> Instant {
        self.saturating_add(d)
    }
}

impl core::ops::Sub for Instant {
    type Output = Duration;
    /// [`Instant::saturating_since`]: 0 when `earlier` is later.
    #[inline]
    fn sub(self, earlier: Instant) -> Duration {
        self.saturating_since(earlier)
    }
}

impl core::ops::Add for Duration {
    type Output = Duration;
    /// [`Duration::saturating_add`].
    #[inline]
    fn add(self, other: Duration) -> Duration {
        self.saturating_add(other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instants_and_durations_add_and_subtract_saturating() {
        let (t, d) = (Instant::from_us(1_000), Duration::from_us(250));
        assert_eq!((t + d).as_us(), 1_250);
        assert_eq!((t + d) - t, d);
        assert_eq!(t - (t + d), Duration::from_us(0), "an earlier minus a later instant is 0");
        assert_eq!((Instant::from_us(u64::MAX) + d).as_us(), u64::MAX, "a late clock never wraps to early");
        assert_eq!((d + Duration::from_us(u64::MAX)).as_us(), u64::MAX);
        assert_eq!(
            Period::MILLISECOND.sample(3) - Period::MILLISECOND.sample(1),
            Period::MILLISECOND.duration().saturating_add(Period::MILLISECOND.duration())
        );
    }

    #[test]
    fn rates_that_divide_a_megahertz_are_exact() {
        for (rate, us) in [(250.0, 4000), (1000.0, 1000), (4000.0, 250), (10_000.0, 100)] {
            let p = Period::from_rate_hz(rate).unwrap();
            assert_eq!(p.as_us(), us);
            assert_eq!(p.rate_hz(), rate);
        }
        assert_eq!(Period::from_rate_hz(1000.0).unwrap().as_secs_f64(), 1.0 / 1000.0);
        assert_eq!(Period::from_rate_hz(1000.0).unwrap().as_secs_f32(), (1.0f64 / 1000.0) as f32);
    }

    #[test]
    fn other_rates_round_once_to_the_nearest_microsecond() {
        assert_eq!(Period::from_rate_hz(6000.0).unwrap().as_us(), 167);
        assert_eq!(Period::from_rate_hz(7000.0).unwrap().as_us(), 143);
        assert_eq!(Period::from_rate_hz(3000.0).unwrap().as_us(), 333);
    }

    #[test]
    fn samples_are_whole_multiples_with_no_drift() {
        let p = Period::from_rate_hz(6000.0).unwrap();
        for k in [0u64, 1, 6000, 1_000_000] {
            assert_eq!(p.sample(k).as_us(), 167 * k);
        }
        assert_eq!(p.sample(u64::MAX).as_us(), u64::MAX);
    }

    #[test]
    fn bad_rates_are_errors() {
        for r in [0.0, -1.0, f64::NAN, f64::INFINITY, 3e6, 1e-7] {
            assert!(Period::from_rate_hz(r).is_err(), "{r}");
        }
        assert_eq!(Period::from_us(0), Err(TimeError::Zero));
    }
}
