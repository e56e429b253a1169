//! What the devices of one board share in a period: the physical inputs the
//! simulated arm sets before the tick (the magnets' angles, the forces, the belt's
//! travel) and the faults acting on the bus, and the outputs the motor stage's
//! pins and PWM hold after it. The device models ([`crate::as5047p`],
//! [`crate::adc`], [`crate::counter`], [`crate::motor_stage`]) each hold a
//! handle to it: a shared `Arc<Mutex<_>>` is the bus and the wires (the twin
//! runs in one thread; the emulator's device classes must be `Send + Sync`).

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

/// A handle on the board's shared state.
pub type Shared = Arc<Mutex<Bench>>;

/// The bench behind `shared`, locked (a poisoned lock is taken as it is: the
/// bench is plain data, always consistent between two statements).
pub fn lock(shared: &Shared) -> MutexGuard<'_, Bench> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Faults on one AS5047P's bus or magnet, this period.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EncoderFaults {
    /// Every transfer fails (a broken wire, the SPI peripheral's error).
    pub spi_error: bool,
    /// MISO is corrupted: one data bit of every answer flips (odd parity).
    pub parity_error: bool,
    /// The magnet is gone: DIAAGC reads MAGL with AGC 255, the angle is noise.
    pub magnet_lost: bool,
    /// The chip's angle stays where it was (a seized shaft coupling, a frozen
    /// CORDIC): every answer is right, the angle does not move.
    pub stuck: bool,
    /// The encoder's chip select reads low after its release (GPIO IDR; theta1's
    /// PA4, the elbow's PB0): the acquisition's
    /// [`arm_app::AcquisitionFault::StuckChipSelect`], which makes both encoders'
    /// readings of the period invalid ([`crate::acquisition`]; on the emulated
    /// board, the image's own read-back of the pin).
    pub chip_select_stuck: bool,
}

/// The board's shared state.
#[derive(Debug, Clone, Default)]
pub struct Bench {
    /// Each encoder's magnet angle, chip counts (real-valued, any range:
    /// [`crate::as5047p`] quantises and wraps), `[theta1, elbow]`.
    pub magnet_counts: [f64; 2],
    /// Faults of each encoder, `[theta1, elbow]`.
    pub encoder_faults: [EncoderFaults; 2],
    /// The ADC's conversions of this period `[tangential, normal]`, counts in
    /// `0..=4095`, or `None`: the conversion is missing (no end of conversion).
    pub adc_counts: Option<[u16; 2]>,
    /// The belt's quadrature counter (TIM4's CNT), wrapping at 16 bits.
    pub belt_count: u16,
    /// The drivers hold nFAULT low (over-current, over-temperature).
    pub driver_fault: bool,
    /// The acquisition of the encoders fails this period
    /// ([`crate::acquisition`]): a DMA stream's error flag, a timeout, a
    /// stuck chip select.
    pub acquisition: Option<arm_app::AcquisitionFault>,
    /// The enable button is held (PC13 low).
    pub button_held: bool,
    /// What the motor stage's outputs are now.
    pub outputs: Outputs,
}

/// The motor stage's outputs as the MCU drives them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Outputs {
    /// The PWM duties `[u1, u2]`, timer counts.
    pub duty: [u16; 2],
    /// The direction pins `[u1, u2]` (high = positive torque).
    pub dir_high: [bool; 2],
    /// The shared enable pin (high = drivers on).
    pub enable: bool,
}
