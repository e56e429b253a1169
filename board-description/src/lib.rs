//! The board's physical truth: how each device is mounted, wired and scaled on
//! *this* board (a scenario's `[board]` table). It is kept apart from the
//! firmware's calibration (`arm_app::ArmCalibration`), which is what the
//! firmware *believes*: the two agree on a calibrated board, and a mismatch
//! (an encoder mounted reversed, a load cell of the other sign, a motor wired
//! the other way) is simulated by changing this description alone.
//!
//! The defaults are the reference board as docs/hardware.md "Full scales and
//! signs" states it, and equal the firmware's default calibration
//! (`boards/stm32f405/src/calibration.rs`).

use serde::{Deserialize, Serialize};

/// AS5047P counts per revolution (datasheet: 14 bit).
pub const ENCODER_COUNTS: f64 = 16384.0;

/// How an AS5047P sees its joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EncoderMounting {
    /// The chip's count at the joint's zero angle, in `[0, 16384)` (fractional: a
    /// magnet is glued where it is).
    pub zero_count: f64,
    /// The chip counts against the joint's positive direction.
    pub reversed: bool,
}

impl Default for EncoderMounting {
    fn default() -> Self {
        Self { zero_count: 0.0, reversed: false }
    }
}

/// The load cell with its two instrumentation amplifiers into ADC1 (12 bit).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoadCellFrontEnd {
    /// ADC count at zero force `[tangential, normal]` (the amplifiers' offset).
    pub zero_counts: [f64; 2],
    /// Gain `[tangential, normal]`, ADC counts per newton (negative: the cell is
    /// mounted the other way round on that axis).
    pub counts_per_newton: [f64; 2],
}

impl Default for LoadCellFrontEnd {
    /// Mid-scale zero, +-25 N over +-2048 counts (one count is one wire code).
    fn default() -> Self {
        Self { zero_counts: [2048.0; 2], counts_per_newton: [2048.0 / 25.0; 2] }
    }
}

/// One joint's motor and current-mode driver.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MotorWiring {
    /// Joint torque at full duty, N m (docs/hardware.md: 5 N m; the wire's code
    /// 2048 is full duty).
    pub full_scale_nm: f64,
    /// The motor is wired the other way: direction pin high turns the joint in
    /// its negative direction.
    pub reversed: bool,
}

impl Default for MotorWiring {
    fn default() -> Self {
        Self { full_scale_nm: 5.0, reversed: false }
    }
}

/// The reference board's physical truth (docs/hardware.md "Reference board").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoardDescription {
    /// The base joint's encoder (`theta1`).
    pub theta1_encoder: EncoderMounting,
    /// The elbow's encoder (it turns with link 1 and sees `theta2 - theta1`).
    pub elbow_encoder: EncoderMounting,
    /// The load cell's front end.
    pub load_cell: LoadCellFrontEnd,
    /// The belt's quadrature counts per metre of travel (negative: the encoder
    /// counts against the belt's positive direction). 1e6: one count per micrometre,
    /// so one count per 1 ms period is 1 mm/s.
    pub belt_counts_per_metre: f64,
    /// The joint-1 motor (`u1`).
    pub motor1: MotorWiring,
    /// The joint-2 motor (`u2`).
    pub motor2: MotorWiring,
    /// The PWM's full-scale duty, timer counts (TIM3 at 84 MHz for 20 kHz: 4200).
    pub pwm_max_duty: u16,
    /// The two encoders' chip selects are swapped (a wiring fault): the base's
    /// chip answers on the elbow's select and the elbow's on the base's.
    pub encoders_swapped: bool,
}

impl Default for BoardDescription {
    fn default() -> Self {
        Self {
            theta1_encoder: EncoderMounting::default(),
            elbow_encoder: EncoderMounting::default(),
            load_cell: LoadCellFrontEnd::default(),
            belt_counts_per_metre: 1e6,
            motor1: MotorWiring::default(),
            motor2: MotorWiring::default(),
            pwm_max_duty: 4200,
            encoders_swapped: false,
        }
    }
}

impl BoardDescription {
    /// Checks every field; returns what is wrong, naming the field.
    ///
    /// # Errors
    /// A message for the first bad field.
    pub fn check(&self) -> Result<(), String> {
        for (name, e) in [("theta1_encoder", &self.theta1_encoder), ("elbow_encoder", &self.elbow_encoder)] {
            if !(e.zero_count.is_finite() && (0.0..ENCODER_COUNTS).contains(&e.zero_count)) {
                return Err(format!("board.{name}.zero_count = {}: a count in [0, 16384)", e.zero_count));
            }
        }
        for axis in 0..2 {
            let (z, g) = (self.load_cell.zero_counts[axis], self.load_cell.counts_per_newton[axis]);
            if !(z.is_finite() && (0.0..=4095.0).contains(&z)) {
                return Err(format!("board.load_cell.zero_counts[{axis}] = {z}: a count in [0, 4095]"));
            }
            if !(g.is_finite() && g != 0.0 && g.abs() <= 1e4) {
                return Err(format!("board.load_cell.counts_per_newton[{axis}] = {g}: non-zero, |gain| <= 1e4 counts/N"));
            }
        }
        let b = self.belt_counts_per_metre;
        if !(b.is_finite() && b != 0.0 && b.abs() <= 1e9) {
            return Err(format!("board.belt_counts_per_metre = {b}: non-zero, |value| <= 1e9"));
        }
        for (name, m) in [("motor1", &self.motor1), ("motor2", &self.motor2)] {
            if !(m.full_scale_nm.is_finite() && m.full_scale_nm > 0.0 && m.full_scale_nm <= 100.0) {
                return Err(format!("board.{name}.full_scale_nm = {}: in (0, 100] N m", m.full_scale_nm));
            }
        }
        if self.pwm_max_duty < 2 {
            return Err(format!("board.pwm_max_duty = {}: at least 2 counts", self.pwm_max_duty));
        }
        Ok(())
    }
}
