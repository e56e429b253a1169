//! The three timers of the arm image (RM0090 18): TIM2's update interrupt is
//! the control tick (and its TRGO starts the load cell's conversions), TIM3
//! makes the motors' 20 kHz PWM, TIM4 counts the belt encoder's quadrature edges.

use embedded_hal::pwm::{ErrorType, SetDutyCycle};
use stm32f4::stm32f405 as pac;

use super::gpio;
use crate::{pins, timing::TickTimer};

/// PWM frequency of the motor drivers, Hz (docs/hardware.md).
pub const PWM_HZ: u32 = 20_000;

fn tim2() -> &'static pac::tim2::RegisterBlock {
    // SAFETY: TIM2 is set up at start-up; afterwards only its interrupt clears UIF.
    unsafe { &*pac::TIM2::ptr() }
}
fn tim3() -> &'static pac::tim3::RegisterBlock {
    // SAFETY: TIM3's compare registers are written by the control interrupt only.
    unsafe { &*pac::TIM3::ptr() }
}
fn tim4() -> &'static pac::tim3::RegisterBlock {
    // SAFETY: TIM4 (same layout as TIM3) is read by the control interrupt only.
    unsafe { &*pac::TIM4::ptr() }
}

/// Starts TIM2 at `tick` from a timer clock of `timer_hz`: update interrupt
/// enabled, update event on TRGO, and compare 1 (frozen output, no pin) at
/// `deadline_us` after each update with its interrupt: the acquisition's
/// deadline (`super::acquisition::DEADLINE_US`), clamped into the period.
// Out of line: the start-up and a change of rate (`retime`) share one copy.
#[inline(never)]
pub fn start_tick(tick: TickTimer, timer_hz: u32, deadline_us: u32) {
    let t = tim2();
    let counts_per_us = (timer_hz / 1_000_000) / (u32::from(tick.psc) + 1);
    let ccr = (deadline_us * counts_per_us.max(1)).min(u32::from(tick.arr));
    t.psc().write(|w| w.psc().set(tick.psc));
    t.arr().write(|w| w.arr().set(u32::from(tick.arr)));
    t.ccr(0).write(|w| w.ccr().set(ccr));
    t.cr2().write(|w| w.mms().update());
    t.egr().write(|w| w.ug().set_bit()); // load PSC now
    t.sr().write(|w| w.uif().clear_bit().cc1if().clear_bit());
    t.dier().write(|w| w.uie().set_bit().cc1ie().set_bit());
    t.cr1().write(|w| w.cen().set_bit());
}

/// Restarts the control tick at `period` (a `Configure` or `Restore` of another
/// rate, served between two ticks in the idle loop's critical section:
/// `arm_app::ArmApp::retime`): TIM2 stopped, then started as [`start_tick`]
/// does with the new prescaler, reload and deadline (the update that loads
/// them is cleared before the interrupts are unmasked: its pended interrupt
/// finds no flag and does nothing), so the next tick comes one new period
/// later; the watchdog's timeout to five new periods; the log's stamp rebased.
/// Returns the period TIM2 now runs, `None` (TIM2 untouched) for one the
/// clock cannot make exactly (never within `arm_app::rate`'s range, which the
/// application checks before: `timing`'s tests).
pub fn retime(period: shared::Period, timer_hz: u32, deadline_us: u32) -> Option<shared::Period> {
    let tick = TickTimer::for_period(timer_hz, period).ok()?;
    tim2().cr1().write(|w| w.cen().clear_bit());
    start_tick(tick, timer_hz, deadline_us);
    let us = period.as_us() as u32;
    super::iwdg::retime(5 * us);
    super::log_time::retime(us);
    Some(period)
}

/// TIM2's events in its interrupt, cleared: `(update, compare 1)`.
pub fn take_tick_events() -> (bool, bool) {
    let sr = tim2().sr().read();
    let (update, deadline) = (sr.uif().bit_is_set(), sr.cc1if().bit_is_set());
    // rc_w0: writing 1 leaves a flag, 0 clears it; only the two taken are
    // cleared, the reserved bits written as their reset value 0 (RM0090 18.4.5).
    const FLAGS: u32 = 0x1E5F;
    // SAFETY (bits): the register's own flags only.
    tim2().sr().write(|w| unsafe { w.bits(FLAGS & !(u32::from(update) | (u32::from(deadline) << 1))) });
    (update, deadline)
}

/// TIM3 channels 1 and 2 in PWM mode 1 at [`PWM_HZ`] from `timer_hz`, duty 0.
pub fn start_pwm(timer_hz: u32) {
    gpio::configure(&pins::PWM_U1);
    gpio::configure(&pins::PWM_U2);
    let t = tim3();
    let arr = (timer_hz / PWM_HZ).saturating_sub(1);
    t.psc().write(|w| w.psc().set(0));
    t.arr().write(|w| w.arr().set(arr as u16));
    t.ccr(0).write(|w| w.ccr().set(0));
    t.ccr(1).write(|w| w.ccr().set(0));
    t.ccmr1_output().write(|w| w.oc1m().pwm_mode1().oc1pe().set_bit().oc2m().pwm_mode1().oc2pe().set_bit());
    t.ccer().write(|w| w.cc1e().set_bit().cc2e().set_bit());
    t.egr().write(|w| w.ug().set_bit());
    t.cr1().write(|w| w.arpe().set_bit().cen().set_bit());
}

/// One PWM channel of TIM3 (`0` or `1`) as an embedded-hal duty cycle.
#[derive(Debug, Clone, Copy)]
pub struct PwmChannel(pub usize);

impl ErrorType for PwmChannel {
    type Error = core::convert::Infallible;
}

impl SetDutyCycle for PwmChannel {
    fn max_duty_cycle(&self) -> u16 {
        tim3().arr().read().arr().bits().saturating_add(1)
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        tim3().ccr(self.0).write(|w| w.ccr().set(duty));
        Ok(())
    }
}

/// TIM4 in encoder mode 3 (both channels, both edges: 4 counts per line), 16-bit.
pub fn start_belt_encoder() {
    gpio::configure(&pins::BELT_A);
    gpio::configure(&pins::BELT_B);
    let t = tim4();
    t.ccmr1_input().write(|w| w.cc1s().ti1().cc2s().ti2().ic1f().set(0b0011).ic2f().set(0b0011));
    t.ccer().write(|w| w.cc1p().clear_bit().cc2p().clear_bit());
    t.smcr().write(|w| w.sms().encoder_mode_3());
    t.arr().write(|w| w.arr().set(0xFFFF));
    t.cr1().write(|w| w.cen().set_bit());
}

/// TIM4's counter as the belt's quadrature counter.
#[derive(Debug, Clone, Copy)]
pub struct BeltCounter;

impl drivers::belt::QuadratureCounter for BeltCounter {
    fn count(&mut self) -> u16 {
        tim4().cnt().read().cnt().bits()
    }
}
