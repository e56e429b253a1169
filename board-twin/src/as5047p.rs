//! The AS5047P as its SPI peer sees it (ams AS5047P datasheet v1-06, "SPI
//! Interface", "Register Description"): 16-bit frames, one per chip-select
//! assertion, even parity in bit 15; a read command is answered in the *next*
//! frame (the one-frame pipeline); an answer carries EF (bit 14) while an error
//! is latched in ERRFL, which a read of ERRFL clears. Modelled registers: NOP
//! (0x0000), ERRFL (0x0001), DIAAGC (0x3FFC), ANGLECOM (0x3FFF); any other read
//! address, and any write (the firmware never writes), latch INVCOMM. A command
//! of odd parity latches PARERR and is not executed.
//!
//! The angle is quantised to 14 bits (round to nearest, wrapped) from the
//! magnet's angle the arm sets on the bench; DIAAGC reads LF = 1 and AGC 128
//! (a magnet at its nominal distance), or, with the magnet lost, MAGL and AGC
//! 255 while the angle freezes. Bus faults ([`EncoderFaults`]) act on the
//! transfer: a failed transfer, or a flipped data bit on MISO.

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

use crate::bench::{EncoderFaults, Shared};

// The frame's bits and the registers, written here again from the datasheet
// rather than taken from the driver: the model is the driver's independent check.

const PARITY: u16 = 1 << 15;
const READ: u16 = 1 << 14;
const EF: u16 = 1 << 14;
const DATA: u16 = 0x3FFF;
const ERRFL_INVCOMM: u16 = 1 << 1;
const ERRFL_PARERR: u16 = 1 << 2;
const DIAAGC_LF: u16 = 1 << 8;
const DIAAGC_MAGL: u16 = 1 << 11;
/// AGC at the nominal magnet distance (datasheet: mid-range when well placed).
const AGC_NOMINAL: u16 = 128;

/// The SPI error of a failed transfer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusError;

impl embedded_hal::spi::Error for BusError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// One AS5047P on its own chip select, as an embedded-hal `SpiDevice<u16>`.
#[derive(Debug)]
pub struct As5047pModel {
    bench: Shared,
    /// 0: theta1, 1: elbow.
    index: usize,
    /// The answer the next frame carries (the pipeline), data bits only.
    pending: u16,
    /// ERRFL, latched until read.
    errfl: u16,
    /// The last good angle (a lost magnet, or a stuck chip, keeps it).
    last_angle: u16,
    /// Frames exchanged (tests count the bus traffic).
    pub frames: u64,
}

impl As5047pModel {
    /// The encoder `index` (0: theta1, 1: elbow) of `bench`, after power-up:
    /// nothing in the pipeline, no error latched.
    pub fn new(bench: Shared, index: usize) -> Self {
        Self { bench, index: index.min(1), pending: 0, errfl: 0, last_angle: 0, frames: 0 }
    }

    fn faults(&self) -> EncoderFaults {
        crate::bench::lock(&self.bench).encoder_faults[self.index]
    }

    /// The angle register now: the magnet's angle quantised to 14 bits.
    fn angle(&mut self) -> u16 {
        let f = self.faults();
        if !(f.magnet_lost || f.stuck) {
            let counts = crate::bench::lock(&self.bench).magnet_counts[self.index];
            if counts.is_finite() {
                self.last_angle = (counts.round().rem_euclid(16384.0) as u32 % 16384) as u16;
            }
        }
        self.last_angle
    }

    /// One 16-bit frame: returns the answer to the previous command and
    /// executes `command` (its answer goes out in the next frame).
    fn frame(&mut self, command: u16) -> Result<u16, BusError> {
        let faults = self.faults();
        if faults.spi_error {
            return Err(BusError);
        }
        self.frames += 1;
        let mut data = self.pending & DATA;
        if self.errfl != 0 {
            data |= EF;
        }
        let mut answer = data | (parity_bit(data) << 15);
        if faults.parity_error {
            answer ^= 1;
        }
        self.pending = if !command.count_ones().is_multiple_of(2) {
            self.errfl |= ERRFL_PARERR;
            0
        } else if command & READ == 0 {
            self.errfl |= ERRFL_INVCOMM;
            0
        } else {
            match command & DATA {
                0x0000 => 0,
                0x0001 => core::mem::take(&mut self.errfl),
                0x3FFC => {
                    if faults.magnet_lost {
                        DIAAGC_LF | DIAAGC_MAGL | 0xFF
                    } else {
                        DIAAGC_LF | AGC_NOMINAL
                    }
                }
                0x3FFF => self.angle(),
                _ => {
                    self.errfl |= ERRFL_INVCOMM;
                    0
                }
            }
        };
        Ok(answer)
    }
}

/// The even-parity bit over bits 0..14 of `w`.
fn parity_bit(w: u16) -> u16 {
    ((w & !PARITY).count_ones() & 1) as u16
}

impl ErrorType for As5047pModel {
    type Error = BusError;
}

impl SpiDevice<u16> for As5047pModel {
    /// Each word is one frame (the driver asserts chip select once per word; a
    /// transaction of several words is several frames here). A word read
    /// without a written one sends 0x0000 (a write of NOP: INVCOMM).
    fn transaction(&mut self, operations: &mut [Operation<'_, u16>]) -> Result<(), Self::Error> {
        for op in operations {
            match op {
                Operation::TransferInPlace(words) => {
                    for w in words.iter_mut() {
                        *w = self.frame(*w)?;
                    }
                }
                Operation::Write(words) => {
                    for w in words.iter() {
                        self.frame(*w)?;
                    }
                }
                Operation::Read(words) => {
                    for w in words.iter_mut() {
                        *w = self.frame(0)?;
                    }
                }
                Operation::Transfer(read, write) => {
                    for i in 0..read.len().max(write.len()) {
                        let answer = self.frame(write.get(i).copied().unwrap_or(0))?;
                        if let Some(r) = read.get_mut(i) {
                            *r = answer;
                        }
                    }
                }
                Operation::DelayNs(_) => {}
            }
        }
        Ok(())
    }
}
