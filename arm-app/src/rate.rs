//! The control rates the `arm` image runs, and how a board follows a new one
//! (issue 56): TIM2's reload comes from the configuration in force (the
//! settings record's at reset, or one `Configure` or `Restore` put in force
//! since), not from a rebuild. The one statement of the range, for the image
//! (`board_stm32f405::timing`), the host (`sil-host board configure`, the
//! backup files, the emulator link) and the board twin alike.
//!
//! The range is docs/hardware.md "Timing"'s (the spec's 250 Hz to 10 kHz,
//! configurable): every whole number of microseconds from [`MIN_PERIOD_US`]
//! (10 kHz) to [`MAX_PERIOD_US`] (250 Hz). Each is exact on the board's timer
//! clock (84 MHz: 84 counts a microsecond) and QEMU's (1 GHz), with a 16-bit
//! prescaler and reload (`board_stm32f405::timing::TickTimer`, tested for
//! every period of the range). `firmware::Config::validate` holds the same
//! range (tested below).

use firmware::ControlLaw;
use shared::time::Period;

use crate::{app::ArmApp, io::ArmIo};

/// The shortest control period the image runs, us (10 kHz: the acquisition's
/// deadline, 40 us, and the control handler must fit in it).
pub const MIN_PERIOD_US: u64 = 100;
/// The longest, us (250 Hz).
pub const MAX_PERIOD_US: u64 = 4_000;
/// The range in words, for error messages.
pub const RANGE_WORDS: &str = "100 to 4000 us (10 kHz to 250 Hz)";

/// Whether the image runs control period `period`: [`MIN_PERIOD_US`] to
/// [`MAX_PERIOD_US`], both taken.
pub fn supported(period: Period) -> bool {
    (MIN_PERIOD_US..=MAX_PERIOD_US).contains(&period.as_us())
}

impl<H: ArmIo, L: ControlLaw> ArmApp<H, L> {
    /// The control period the board's tick runs, as the board last said
    /// ([`ArmApp::retime`]; at start-up the configuration's, which the board
    /// programs its timer from): what `Status` reports.
    pub fn tick_period_us(&self) -> u64 {
        self.hw.period_us
    }

    /// Follows a configuration whose control period differs from the tick's
    /// (`Configure` or `Restore` of another rate): calls `set` with the
    /// configuration's period, which reprograms the board's tick (TIM2's
    /// prescaler and reload, the watchdog's timeout) and returns the period the
    /// tick now runs, or `None` when the board could not. The frames' time
    /// goes on from where it was (no jump back or forward at the change).
    /// Nothing is called when the periods agree. A board calls it after every
    /// served request, between two ticks.
    ///
    /// Returns the new tick period when it changed. A tick that does not run
    /// the configuration's period after this locks the drivers out
    /// (`Refusal::Rate` to an enable).
    pub fn retime(&mut self, set: impl FnOnce(Period) -> Option<Period>) -> Option<Period> {
        let hw = &mut self.hw;
        let want = hw.config.period;
        if want.as_us() == hw.period_us {
            return None;
        }
        let now = set(want)?;
        // seq x period + offset: the time of the period under way stays put.
        let seq = u64::from(hw.seq);
        let t = seq.wrapping_mul(hw.period_us).wrapping_add(hw.time_offset_us);
        hw.time_offset_us = t.wrapping_sub(seq.wrapping_mul(now.as_us()));
        hw.period_us = now.as_us();
        hw.button_press_periods = crate::hardware::button_periods(hw.period_us);
        Some(now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_firmware_s_own_check_holds_the_same_range() {
        for us in [1, 50, 99, 100, 101, 1000, 3999, 4000, 4001, 5000, 1_000_000] {
            let period = Period::from_us(us).unwrap();
            let config = firmware::Config { period, ..firmware::Config::default() };
            // The observer's bandwidth is bounded per period: scaled into its range.
            let config = firmware::Config { observer_bandwidth: config.observer_bandwidth.min(2.0 / period.as_secs_f32()), ..config };
            let firmware_takes = config.validate().is_ok();
            assert_eq!(supported(period), firmware_takes, "{us} us");
            assert_eq!(supported(period), (100..=4000).contains(&us), "{us} us");
        }
    }

    #[test]
    fn the_enable_button_is_held_its_time_at_every_rate_the_image_runs() {
        // n periods of Ts hold BUTTON_PRESS_S: n Ts >= 20 ms (never a shorter
        // press than at 1 kHz: a contact's bounce is not a press; to the
        // thousandth of a period `periods_of` rounds off) and (n - 1) Ts < 20 ms,
        // for every whole microsecond of the range.
        for us in 100..=4000u64 {
            let n = u64::from(crate::hardware::button_periods(us));
            assert!(1000 * n * us + us >= 20_000_000 && (n - 1) * us < 20_000, "{us} us: {n} periods");
        }
        assert_eq!([100, 1000, 4000].map(crate::hardware::button_periods), [200, 20, 5]);
    }
}
