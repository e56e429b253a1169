//! The two current-mode motor drivers (docs/hardware.md "Reference board",
//! "Actuators"): per joint a 20 kHz PWM whose duty is the torque magnitude and a
//! direction pin; one enable pin shared by both; one active-low fault input
//! (nFAULT) shared by both. Disabled is the safe state: zero duty, enable low.
//!
//! Errors carry the embedded-hal [`digital::ErrorKind`] or [`pwm::ErrorKind`]
//! (via `Error::kind()`) rather than the HAL's own error types, so [`Error`] is
//! one concrete type whatever the board's pins and timers are.

use core::fmt;

use embedded_hal::digital::{self, InputPin, OutputPin};
use embedded_hal::pwm::{self, SetDutyCycle};

/// Torque codes per full scale (the wire: `5/2048 N m` per code).
const CODES_FULL_SCALE: u32 = 2048;

/// Errors of the motor stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// A direction, enable or fault pin failed.
    Pin(digital::ErrorKind),
    /// A PWM channel refused a duty cycle.
    Pwm(pwm::ErrorKind),
    /// The fault line (nFAULT) is asserted: the stage will not enable.
    Fault,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Pin(k) => write!(f, "motor stage: pin error {k:?}"),
            Error::Pwm(k) => write!(f, "motor stage: PWM error {k:?}"),
            Error::Fault => write!(f, "motor stage: driver fault asserted"),
        }
    }
}

fn pin_error<E: digital::Error>(e: E) -> Error {
    Error::Pin(e.kind())
}

fn pwm_error<E: pwm::Error>(e: E) -> Error {
    Error::Pwm(e.kind())
}

/// The first error of several steps that were all attempted.
fn first_error(results: &[Result<(), Error>]) -> Result<(), Error> {
    results.iter().copied().find(Result::is_err).unwrap_or(Ok(()))
}

/// The PWM duty for torque `code` (codes of 5/2048 N m): `|code| * max_duty /
/// 2048`, rounded half up, at most `max_duty` (so -2048 is full duty and so is
/// anything beyond the wire's range).
pub fn duty_for(code: i16, max_duty: u16) -> u16 {
    let magnitude = u32::from(code.unsigned_abs());
    let duty = (magnitude * u32::from(max_duty) + CODES_FULL_SCALE / 2) / CODES_FULL_SCALE;
    // <= max_duty after min, so the conversion cannot fail.
    u16::try_from(duty.min(u32::from(max_duty))).unwrap_or(max_duty)
}

/// One joint's driver inputs: the PWM channel (its duty is the torque
/// magnitude) and the direction pin (high = positive torque).
#[derive(Debug)]
pub struct Motor<PWM, DIR> {
    pwm: PWM,
    dir: DIR,
    max_duty: u16,
}

impl<PWM: SetDutyCycle, DIR: OutputPin> Motor<PWM, DIR> {
    /// A motor on `pwm` (already at 20 kHz: its full-scale duty is read here,
    /// once) and `dir`. Writes nothing; [`MotorStage::new`] sets the safe state.
    pub fn new(pwm: PWM, dir: DIR) -> Self {
        let max_duty = pwm.max_duty_cycle();
        Self { pwm, dir, max_duty }
    }

    /// The PWM's full-scale duty, timer counts.
    pub fn max_duty(&self) -> u16 {
        self.max_duty
    }

    /// Gives the PWM channel and direction pin back.
    pub fn release(self) -> (PWM, DIR) {
        (self.pwm, self.dir)
    }

    fn zero(&mut self) -> Result<(), Error> {
        self.pwm.set_duty_cycle(0).map_err(pwm_error)
    }

    /// Direction first, then the magnitude.
    fn set(&mut self, code: i16) -> Result<(), Error> {
        if code > 0 { self.dir.set_high() } else { self.dir.set_low() }.map_err(pin_error)?;
        self.pwm.set_duty_cycle(duty_for(code, self.max_duty)).map_err(pwm_error)
    }
}

/// Both joints' drivers with their shared enable and fault lines.
///
/// Every operation that writes several outputs attempts all of them and returns
/// the first error, so one failed write never keeps the others from happening.
#[derive(Debug)]
pub struct MotorStage<PWM1, DIR1, PWM2, DIR2, EN, FAULT> {
    m1: Motor<PWM1, DIR1>,
    m2: Motor<PWM2, DIR2>,
    enable: EN,
    fault: FAULT,
    enabled: bool,
}

impl<PWM1, DIR1, PWM2, DIR2, EN, FAULT> MotorStage<PWM1, DIR1, PWM2, DIR2, EN, FAULT>
where
    PWM1: SetDutyCycle,
    DIR1: OutputPin,
    PWM2: SetDutyCycle,
    DIR2: OutputPin,
    EN: OutputPin,
    FAULT: InputPin,
{
    /// The stage for joint 1 (`m1`, torque `u1`) and joint 2 (`m2`, `u2`), the
    /// shared `enable` (high = drivers on) and `fault` (nFAULT, low = fault)
    /// pins. Starts disabled, as after a reset: enable low, then both duties 0.
    ///
    /// # Errors
    /// [`Error::Pin`], [`Error::Pwm`] (all three writes are attempted; on an
    /// error the parts are dropped as they are).
    pub fn new(m1: Motor<PWM1, DIR1>, m2: Motor<PWM2, DIR2>, enable: EN, fault: FAULT) -> Result<Self, Error> {
        let mut stage = Self { m1, m2, enable, fault, enabled: false };
        // Drivers off first: whatever the duties are, no torque.
        let off = stage.enable.set_low().map_err(pin_error);
        let (z1, z2) = (stage.m1.zero(), stage.m2.zero());
        first_error(&[off, z1, z2])?;
        Ok(stage)
    }

    /// Whether the drivers are enabled (the last [`MotorStage::enable`] succeeded
    /// and no [`MotorStage::disable`] came since).
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Whether a driver asserts its fault line (nFAULT low).
    ///
    /// # Errors
    /// [`Error::Pin`] when the line cannot be read (treat as a fault).
    pub fn fault_asserted(&mut self) -> Result<bool, Error> {
        self.fault.is_low().map_err(pin_error)
    }

    /// Turns the drivers on with zero torque: both duties 0, then enable high.
    /// Refuses while the fault line is asserted (or unreadable): then the stage
    /// is put in the safe state ([`MotorStage::disable`]) and stays disabled.
    ///
    /// # Errors
    /// [`Error::Fault`], [`Error::Pin`], [`Error::Pwm`] (the stage stays disabled).
    pub fn enable(&mut self) -> Result<(), Error> {
        let healthy = match self.fault_asserted() {
            Ok(false) => Ok(()),
            Ok(true) => Err(Error::Fault),
            Err(e) => Err(e),
        };
        if let Err(e) = healthy {
            // The safe-state writes' own errors matter less than why we refused.
            let _ = self.disable();
            return Err(e);
        }
        let (z1, z2) = (self.m1.zero(), self.m2.zero());
        first_error(&[z1, z2])?;
        self.enable.set_high().map_err(pin_error)?;
        self.enabled = true;
        Ok(())
    }

    /// The safe state (docs/hardware.md: zero torque, drivers off): both duties 0,
    /// then enable low. Every write is attempted; the stage counts as disabled
    /// afterwards whatever happens.
    ///
    /// # Errors
    /// [`Error::Pin`], [`Error::Pwm`]: the first write that failed.
    pub fn disable(&mut self) -> Result<(), Error> {
        self.enabled = false;
        let (z1, z2) = (self.m1.zero(), self.m2.zero());
        let off = self.enable.set_low().map_err(pin_error);
        first_error(&[z1, z2, off])
    }

    /// Applies torque codes `[u1_code, u2_code]` (codes of 5/2048 N m, as in
    /// `shared::wire::ActuatorCommand`): per joint the direction pin (high for a
    /// positive code), then duty [`duty_for`]. While disabled it writes zero duty
    /// to both and leaves enable low. Both joints are attempted; on an error call
    /// [`MotorStage::disable`].
    ///
    /// # Errors
    /// [`Error::Pin`], [`Error::Pwm`]: the first write that failed.
    pub fn apply(&mut self, codes: [i16; 2]) -> Result<(), Error> {
        let [u1, u2] = codes;
        let (r1, r2) = if self.enabled { (self.m1.set(u1), self.m2.set(u2)) } else { (self.m1.zero(), self.m2.zero()) };
        first_error(&[r1, r2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal_mock::eh1::MockError;
    use embedded_hal_mock::eh1::digital::{Mock as Pin, State, Transaction as PinT};
    use embedded_hal_mock::eh1::pwm::{Mock as Pwm, Transaction as PwmT};
    use proptest::prelude::*;
    use std::io::ErrorKind as Io;

    const MAX: u16 = 4200; // 84 MHz / 20 kHz

    type Stage = MotorStage<Pwm, Pin, Pwm, Pin, Pin, Pin>;

    /// The mocks, kept to check them after the stage consumed its clones.
    struct Rig {
        pwm: [Pwm; 2],
        dir: [Pin; 2],
        en: Pin,
        fault: Pin,
    }

    impl Rig {
        fn done(mut self) {
            for m in &mut self.pwm {
                m.done();
            }
            for m in &mut self.dir {
                m.done();
            }
            self.en.done();
            self.fault.done();
        }
    }

    /// A stage through `new` (max duty read, enable low, duties 0), then the
    /// expectations `after` for each part.
    fn rig(pwm: [&[PwmT]; 2], dir: [&[PinT]; 2], en: &[PinT], fault: &[PinT]) -> (Stage, Rig) {
        let init = [PwmT::max_duty_cycle(MAX), PwmT::set_duty_cycle(0)];
        let pwm = pwm.map(|after| Pwm::new(init.iter().chain(after)));
        let dir = dir.map(Pin::new);
        let en = Pin::new([PinT::set(State::Low)].iter().chain(en));
        let fault = Pin::new(fault);
        let [p1, p2] = pwm.clone();
        let [d1, d2] = dir.clone();
        let stage = MotorStage::new(Motor::new(p1, d1), Motor::new(p2, d2), en.clone(), fault.clone()).unwrap();
        (stage, Rig { pwm, dir, en, fault })
    }

    fn io_error() -> MockError {
        MockError::Io(Io::NotConnected)
    }

    #[test]
    fn starts_disabled_and_apply_writes_zero_while_disabled() {
        let zero = [PwmT::set_duty_cycle(0)];
        let (mut s, rig) = rig([&zero, &zero], [&[], &[]], &[], &[]);
        assert!(!s.is_enabled());
        assert_eq!(s.apply([1000, -1000]), Ok(()));
        rig.done();
    }

    #[test]
    fn enable_apply_disable() {
        let p1 = [PwmT::set_duty_cycle(0), PwmT::set_duty_cycle(2100), PwmT::set_duty_cycle(0)];
        let p2 = [PwmT::set_duty_cycle(0), PwmT::set_duty_cycle(MAX), PwmT::set_duty_cycle(0)];
        let (mut s, rig) = rig(
            [&p1, &p2],
            [&[PinT::set(State::High)], &[PinT::set(State::Low)]],
            &[PinT::set(State::High), PinT::set(State::Low)],
            &[PinT::get(State::High)],
        );
        assert_eq!(s.enable(), Ok(()));
        assert!(s.is_enabled());
        // 1024 codes = half scale; -2048 = full scale, negative.
        assert_eq!(s.apply([1024, -2048]), Ok(()));
        assert_eq!(s.disable(), Ok(()));
        assert!(!s.is_enabled());
        rig.done();
    }

    #[test]
    fn enable_refuses_on_fault_and_stays_safe() {
        let zero = [PwmT::set_duty_cycle(0)];
        let (mut s, rig) = rig([&zero, &zero], [&[], &[]], &[PinT::set(State::Low)], &[PinT::get(State::Low)]);
        assert_eq!(s.enable(), Err(Error::Fault));
        assert!(!s.is_enabled());
        rig.done();
    }

    #[test]
    fn fault_line_reads_active_low_and_its_errors_propagate() {
        let zero = [PwmT::set_duty_cycle(0)];
        let fault = [PinT::get(State::High), PinT::get(State::Low), PinT::get(State::High).with_error(io_error())];
        let (mut s, rig) = rig([&zero, &zero], [&[], &[]], &[PinT::set(State::Low)], &fault);
        assert_eq!(s.fault_asserted(), Ok(false));
        assert_eq!(s.fault_asserted(), Ok(true));
        // An unreadable fault line refuses to enable too.
        assert_eq!(s.enable(), Err(Error::Pin(digital::ErrorKind::Other)));
        rig.done();
    }

    #[test]
    fn disable_attempts_every_write_and_reports_the_first_error() {
        let p1 = [PwmT::set_duty_cycle(0).with_error(io_error())];
        let p2 = [PwmT::set_duty_cycle(0)];
        let (mut s, rig) = rig([&p1, &p2], [&[], &[]], &[PinT::set(State::Low).with_error(io_error())], &[]);
        assert_eq!(s.disable(), Err(Error::Pwm(pwm::ErrorKind::Other)));
        assert!(!s.is_enabled());
        rig.done();
    }

    #[test]
    fn apply_errors_propagate_and_both_joints_are_attempted() {
        let p1 = [PwmT::set_duty_cycle(0), PwmT::set_duty_cycle(2)];
        let p2 = [PwmT::set_duty_cycle(0), PwmT::set_duty_cycle(0), PwmT::set_duty_cycle(0)];
        let (mut s, rig) = rig(
            [&p1, &p2],
            [&[PinT::set(State::High).with_error(io_error()), PinT::set(State::High)], &[PinT::set(State::Low), PinT::set(State::Low)]],
            &[PinT::set(State::High)],
            &[PinT::get(State::High)],
        );
        s.enable().unwrap();
        assert_eq!(s.apply([1, 0]), Err(Error::Pin(digital::ErrorKind::Other)));
        assert_eq!(s.apply([1, 0]), Ok(()));
        rig.done();
    }

    #[test]
    fn enable_fails_without_enabling_when_a_duty_write_fails() {
        let p1 = [PwmT::set_duty_cycle(0).with_error(io_error())];
        let p2 = [PwmT::set_duty_cycle(0)];
        let (mut s, rig) = rig([&p1, &p2], [&[], &[]], &[], &[PinT::get(State::High)]);
        assert_eq!(s.enable(), Err(Error::Pwm(pwm::ErrorKind::Other)));
        assert!(!s.is_enabled());
        rig.done();
    }

    #[test]
    fn new_reports_a_failed_safe_state_write() {
        let mut pwm = [
            Pwm::new(&[PwmT::max_duty_cycle(MAX), PwmT::set_duty_cycle(0)]),
            Pwm::new(&[PwmT::max_duty_cycle(MAX), PwmT::set_duty_cycle(0)]),
        ];
        let mut dir = [Pin::new(&[]), Pin::new(&[])];
        let mut en = Pin::new(&[PinT::set(State::Low).with_error(io_error())]);
        let mut fault = Pin::new(&[]);
        let [p1, p2] = pwm.clone();
        let [d1, d2] = dir.clone();
        let r = MotorStage::new(Motor::new(p1, d1), Motor::new(p2, d2), en.clone(), fault.clone());
        assert_eq!(r.err(), Some(Error::Pin(digital::ErrorKind::Other)));
        pwm.iter_mut().for_each(Pwm::done);
        dir.iter_mut().for_each(Pin::done);
        en.done();
        fault.done();
    }

    #[test]
    fn duty_rounds_and_saturates() {
        assert_eq!(duty_for(0, MAX), 0);
        assert_eq!(duty_for(1, 1000), 0); // 0.49 -> 0
        assert_eq!(duty_for(3, 1000), 1); // 1.46 -> 1
        assert_eq!(duty_for(2047, MAX), 4198); // 4197.95
        assert_eq!(duty_for(-2048, MAX), MAX);
        assert_eq!(duty_for(i16::MIN, MAX), MAX);
        assert_eq!(duty_for(i16::MAX, u16::MAX), u16::MAX);
        assert_eq!(duty_for(i16::MAX, 0), 0);
    }

    proptest! {
        #[test]
        fn duty_is_monotone_and_bounded(code in any::<i16>(), max in any::<u16>()) {
            let d = duty_for(code, max);
            prop_assert!(d <= max);
            if code != i16::MIN {
                prop_assert_eq!(d, duty_for(-code, max));
            }
            if code.unsigned_abs() < 2048 {
                prop_assert!(d <= duty_for(code.saturating_add(code.signum()), max));
            }
        }
    }
}
