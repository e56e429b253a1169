//! The control tick's timer settings (RM0090 18.3.1: the update event comes
//! every `(psc + 1) (arr + 1)` timer clocks) and the independent watchdog's
//! (RM0090 21.3: LSI / `4 * 2^pr` counted down from `rl`).

/// TIM2's clock on the board: APB1 at 42 MHz, doubled for its timers because
/// APB1's prescaler is not 1 (RM0090 6.2, figure 21).
pub const TIM2_CLOCK_HZ: u32 = 2 * crate::clock_tree::PCLK1_HZ;

/// QEMU's clock for TIM2 to TIM5 in `netduinoplus2`, Hz: the emulator models no
/// RCC and clocks its timers at a fixed 1 GHz (QEMU 7.2's `stm32f405_soc`; a
/// proposed patch moves it to 48 MHz). Measured: docs/board.md "Under QEMU".
pub const QEMU_TIMER_HZ: u32 = 1_000_000_000;

use shared::Period;

/// The shortest and longest control periods the `arm` image runs, us (10 kHz
/// and 250 Hz, docs/hardware.md "Timing"'s range): `arm_app::rate`'s, the one
/// statement the image and the host share. Every whole microsecond between is
/// exact on both timer clocks (tested below).
pub use arm_app::rate::{MAX_PERIOD_US, MIN_PERIOD_US};

/// The LSI that clocks the watchdog, Hz (nominal; 17 to 47 kHz over parts and
/// temperature, DS8626 table 41: the timeout is chosen with that margin).
pub const LSI_HZ: u32 = 32_000;

/// Prescaler and reload of a timer that overflows once per control period.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickTimer {
    /// PSC.
    pub psc: u16,
    /// ARR (TIM2 is 32-bit; kept within 16 bits so TIM3 to TIM5 fit too).
    pub arr: u16,
}

/// Why a rate cannot be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum TimingError {
    /// No integer prescaler and reload give exactly `period_us` from `clock_hz`:
    /// the firmware's period would disagree with the tick's.
    Inexact {
        /// The timer clock, Hz.
        clock_hz: u32,
        /// The period asked for, us.
        period_us: u32,
    },
}

impl TickTimer {
    /// The settings for exactly `period` (whole microseconds, `shared::time`)
    /// from a timer clock of `clock_hz`, with the smallest prescaler (the finest
    /// counter).
    ///
    /// # Errors
    /// [`TimingError::Inexact`] when `clock_hz` is not a whole number of MHz (no
    /// whole count of ticks per microsecond) or the count does not fit 16 x 16 bits.
    // Out of line: the image's start-up and its change of rate share one copy.
    #[inline(never)]
    pub fn for_period(clock_hz: u32, period: Period) -> Result<Self, TimingError> {
        let period_us = period.as_us() as u32;
        let err = TimingError::Inexact { clock_hz, period_us };
        if !clock_hz.is_multiple_of(1_000_000) {
            return Err(err);
        }
        let Some(ticks) = (clock_hz / 1_000_000).checked_mul(period_us) else { return Err(err) };
        for psc in 1..=65_536u32 {
            if ticks.is_multiple_of(psc) && ticks / psc <= 65_536 {
                return Ok(Self { psc: (psc - 1) as u16, arr: (ticks / psc - 1) as u16 });
            }
        }
        Err(err)
    }

    /// The tick's rate from `clock_hz`, Hz.
    pub fn rate_hz(&self, clock_hz: u32) -> f64 {
        f64::from(clock_hz) / ((f64::from(self.psc) + 1.0) * (f64::from(self.arr) + 1.0))
    }
}

/// The watchdog's prescaler code `pr` (divider `4 * 2^pr`) and reload `rl`
/// (12 bits) for a timeout of at least `timeout_us` at the fastest LSI
/// (47 kHz), so a slow part never resets a healthy loop; the slowest (17 kHz)
/// stretches it by less than 3x.
pub fn watchdog(timeout_us: u32) -> (u8, u16) {
    const LSI_MAX_HZ: u64 = 47_000;
    for pr in 0..=6u8 {
        let div = 4u64 << pr;
        let counts = (u64::from(timeout_us) * LSI_MAX_HZ).div_ceil(div * 1_000_000);
        if counts <= 0x0FFF {
            return (pr, counts.max(1) as u16);
        }
    }
    (6, 0x0FFF)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_supported_period_is_exact_on_the_board_and_in_qemu() {
        // docs/hardware.md: 250 Hz to 10 kHz, each rounded once to whole microseconds
        // (shared::time): the tick then runs at exactly the firmware's period.
        for rate in [250.0, 500.0, 1_000.0, 2_000.0, 3_000.0, 4_000.0, 5_000.0, 6_000.0, 7_000.0, 9_000.0, 10_000.0] {
            let period = Period::from_rate_hz(rate).unwrap();
            for clock in [TIM2_CLOCK_HZ, QEMU_TIMER_HZ] {
                let t = TickTimer::for_period(clock, period).unwrap();
                let ticks = u64::from(u32::from(t.psc) + 1) * u64::from(u32::from(t.arr) + 1);
                assert_eq!(ticks, u64::from(clock / 1_000_000) * period.as_us(), "{rate} Hz at {clock} Hz");
                assert!((t.rate_hz(clock) - period.rate_hz()).abs() < 1e-9);
            }
        }
        let ms = Period::from_us(1000).unwrap();
        assert_eq!(TickTimer::for_period(84_000_000, ms), Ok(TickTimer { psc: 1, arr: 41_999 }));
        // A clock with no whole number of ticks per microsecond is refused rather than drifting.
        assert!(TickTimer::for_period(84_000_001, ms).is_err());
    }

    #[test]
    fn every_period_the_image_runs_is_exact_on_both_clocks() {
        // All 3 901 of them: a `Configure` can ask for any (arm_app::rate).
        for us in MIN_PERIOD_US..=MAX_PERIOD_US {
            let period = Period::from_us(u32::try_from(us).unwrap()).unwrap();
            for clock in [TIM2_CLOCK_HZ, QEMU_TIMER_HZ] {
                let t = TickTimer::for_period(clock, period).unwrap_or_else(|e| panic!("{us} us at {clock} Hz: {e:?}"));
                let ticks = u64::from(u32::from(t.psc) + 1) * u64::from(u32::from(t.arr) + 1);
                assert_eq!(ticks, u64::from(clock / 1_000_000) * us, "{us} us at {clock} Hz");
            }
        }
    }

    #[test]
    fn the_watchdog_is_never_shorter_than_asked() {
        for timeout_us in [500u32, 1_000, 4_000, 5_000, 20_000, 1_000_000, 30_000_000] {
            let (pr, rl) = watchdog(timeout_us);
            let fastest_us = f64::from(rl) * f64::from(4u32 << pr) / 47_000.0 * 1e6;
            assert!(fastest_us >= f64::from(timeout_us) || rl == 0x0FFF, "{timeout_us}: {fastest_us}");
            assert!(rl <= 0x0FFF && pr <= 6);
        }
        // 5 ms: divider 4, 59 counts.
        assert_eq!(watchdog(5_000), (0, 59));
    }
}
