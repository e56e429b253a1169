//! AS5047P 14-bit magnetic absolute encoder over SPI (AS5047P datasheet, ams
//! v1-06, "SPI Interface"; docs/hardware.md "Reference board": two of them, one
//! chip select each, on one bus).
//!
//! The bus is SPI mode 1 with 16-bit frames, one chip-select assertion per frame
//! (one [`SpiDevice::transfer_in_place`] of one `u16`). The chip answers a read
//! command in the *next* frame (datasheet "SPI Timing"/"SPI Read"), so every read
//! here is a command frame followed by a frame whose answer is the register; the
//! last frame of every operation is a NOP read, which leaves the pipeline with a
//! harmless command in it.
//!
//! Every answer is checked for even parity and for the error flag EF; an EF makes
//! the driver read (and so clear) ERRFL and report its bits.

use core::fmt;

use embedded_hal::spi::SpiDevice;

/// Register NOP (datasheet "Register Description", address 0x0000): reading it
/// returns 0 and is used to clock out the previous command's answer.
pub const REG_NOP: u16 = 0x0000;
/// Register ERRFL (address 0x0001): error flags, cleared by reading them.
pub const REG_ERRFL: u16 = 0x0001;
/// Register DIAAGC (address 0x3FFC): diagnostics and the AGC value.
pub const REG_DIAAGC: u16 = 0x3FFC;
/// Register ANGLECOM (address 0x3FFF): the angle with dynamic angle error
/// compensation, 14 bit per revolution.
pub const REG_ANGLECOM: u16 = 0x3FFF;

/// ERRFL bit 0 FRERR: framing error (a frame that was not 16 bits long).
pub const ERRFL_FRERR: u16 = 1 << 0;
/// ERRFL bit 1 INVCOMM: invalid command (a read or write of a bad address).
pub const ERRFL_INVCOMM: u16 = 1 << 1;
/// ERRFL bit 2 PARERR: a command frame had odd parity.
pub const ERRFL_PARERR: u16 = 1 << 2;
/// The `errfl` of [`Error::ErrorFlag`] when EF was set but ERRFL itself could not
/// be read (bus error or bad parity on that read): no 14-bit register reads as
/// this value.
pub const ERRFL_UNKNOWN: u16 = 0xFFFF;

/// Bit 15 of every frame: even parity over the whole 16 bits.
const PARITY: u16 = 1 << 15;
/// Bit 14 of a command frame: 1 = read.
const READ: u16 = 1 << 14;
/// Bit 14 of an answer frame: EF, an error happened in a previous frame.
const EF: u16 = 1 << 14;
/// Bits 0..13: address in a command, data in an answer.
const DATA: u16 = 0x3FFF;

/// DIAAGC bits (datasheet "DIAAGC (0x3FFC)").
const DIAAGC_LF: u16 = 1 << 8;
const DIAAGC_COF: u16 = 1 << 9;
const DIAAGC_MAGH: u16 = 1 << 10;
const DIAAGC_MAGL: u16 = 1 << 11;

/// The encoder's resolution, counts per revolution (datasheet: 14 bit).
pub const COUNTS_PER_REV: u16 = 1 << 14;

/// A read command frame for `addr` (datasheet "SPI Command Frame"): bits 0..13
/// the address (bits 14..15 of `addr` are ignored), bit 14 = 1 (read), bit 15 the
/// even-parity bit over bits 0..14, so the whole word has even parity.
pub fn read_command(addr: u16) -> u16 {
    let w = (addr & DATA) | READ;
    w | (parity_of(w) << 15)
}

/// 1 when `w` has an odd number of ones in bits 0..14, else 0.
fn parity_of(w: u16) -> u16 {
    ((w & !PARITY).count_ones() & 1) as u16
}

/// Whether the 16-bit `frame` has even parity (as every valid frame does).
pub fn has_even_parity(frame: u16) -> bool {
    frame.count_ones().is_multiple_of(2)
}

/// Errors of the AS5047P driver. `E` is the SPI device's error type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error<E> {
    /// The SPI transfer failed.
    Bus(E),
    /// An answer `frame` had odd parity (datasheet "SPI Read Data Frame"): a bit
    /// was corrupted on MISO.
    Parity {
        /// The received 16-bit word.
        frame: u16,
    },
    /// An answer had EF set (an earlier frame went wrong). ERRFL was read, which
    /// clears it; `errfl` holds its bits ([`ERRFL_FRERR`], [`ERRFL_INVCOMM`],
    /// [`ERRFL_PARERR`]), or [`ERRFL_UNKNOWN`] if that read failed too. A MISO
    /// line floating high (answers 0xFFFF) ends here.
    ErrorFlag {
        /// ERRFL bits 0..13, or [`ERRFL_UNKNOWN`].
        errfl: u16,
    },
    /// DIAAGC LF = 0: the offset compensation has not finished, the angle is not
    /// valid yet. A chip missing from the bus (MISO reads all zeros, which pass
    /// parity and EF) ends here too.
    NotReady,
    /// DIAAGC MAGH/MAGL: the magnetic field is out of range (magnet too close,
    /// too far, or missing).
    Magnet {
        /// MAGH: field too strong.
        too_strong: bool,
        /// MAGL: field too weak.
        too_weak: bool,
    },
    /// DIAAGC COF: the CORDIC overflowed, the angle is not valid.
    CordicOverflow,
}

impl<E: fmt::Debug> fmt::Display for Error<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Bus(e) => write!(f, "AS5047P: SPI error {e:?}"),
            Error::Parity { frame } => write!(f, "AS5047P: parity error in answer {frame:#06x}"),
            Error::ErrorFlag { errfl } => write!(f, "AS5047P: error flag set, ERRFL = {errfl:#06x}"),
            Error::NotReady => write!(f, "AS5047P: offset compensation not finished (or no chip)"),
            Error::Magnet { too_strong, too_weak } => {
                write!(f, "AS5047P: magnetic field out of range (too strong: {too_strong}, too weak: {too_weak})")
            }
            Error::CordicOverflow => write!(f, "AS5047P: CORDIC overflow"),
        }
    }
}

/// The DIAAGC register decoded (datasheet "DIAAGC (0x3FFC)").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Diagnostics {
    /// Bits 0..7: the automatic gain control value (0 = strong field, 255 = weak).
    pub agc: u8,
    /// Bit 8 LF: the offset compensation has finished (the angle is valid).
    pub offset_compensation_finished: bool,
    /// Bit 9 COF: CORDIC overflow.
    pub cordic_overflow: bool,
    /// Bit 10 MAGH: magnetic field too strong.
    pub magnet_too_strong: bool,
    /// Bit 11 MAGL: magnetic field too weak.
    pub magnet_too_weak: bool,
}

impl Diagnostics {
    /// Decodes a DIAAGC value (bits 12..15 ignored).
    pub fn from_register(diaagc: u16) -> Self {
        Self {
            agc: (diaagc & 0xFF) as u8,
            offset_compensation_finished: diaagc & DIAAGC_LF != 0,
            cordic_overflow: diaagc & DIAAGC_COF != 0,
            magnet_too_strong: diaagc & DIAAGC_MAGH != 0,
            magnet_too_weak: diaagc & DIAAGC_MAGL != 0,
        }
    }

    /// Whether the angle sampled with these diagnostics is valid.
    ///
    /// # Errors
    /// In this order: [`Error::NotReady`] (LF = 0; the other bits mean nothing
    /// then), [`Error::Magnet`] (MAGH or MAGL), [`Error::CordicOverflow`] (COF).
    pub fn check<E>(&self) -> Result<(), Error<E>> {
        if !self.offset_compensation_finished {
            Err(Error::NotReady)
        } else if self.magnet_too_strong || self.magnet_too_weak {
            Err(Error::Magnet { too_strong: self.magnet_too_strong, too_weak: self.magnet_too_weak })
        } else if self.cordic_overflow {
            Err(Error::CordicOverflow)
        } else {
            Ok(())
        }
    }
}

impl Error<()> {
    /// The same error with the transport's error `bus` in place of `Bus(())`
    /// (`None`: [`Error::NotReady`], as a chip that never answered).
    pub fn with_bus<E>(self, bus: Option<E>) -> Error<E> {
        match self {
            Error::Bus(()) => bus.map_or(Error::NotReady, Error::Bus),
            Error::Parity { frame } => Error::Parity { frame },
            Error::ErrorFlag { errfl } => Error::ErrorFlag { errfl },
            Error::NotReady => Error::NotReady,
            Error::Magnet { too_strong, too_weak } => Error::Magnet { too_strong, too_weak },
            Error::CordicOverflow => Error::CordicOverflow,
        }
    }
}

/// Where a [`SampleSequence`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Sending frame `n` of READ ANGLECOM, READ DIAAGC, READ NOP.
    Sampling(u8),
    /// An answer carried EF: sending READ ERRFL.
    ErrflCommand,
    /// Sending READ NOP, whose answer is ERRFL.
    ErrflValue,
    /// Over.
    Done,
}

/// One encoder's sample as a sequence of frames, without a bus: the commands
/// to send one frame at a time and what their answers mean, for a driver that
/// blocks on each frame ([`As5047p::sample`]) and for an interrupt-driven
/// acquisition (the `arm` image's DMA, docs/board.md "The encoders by DMA")
/// alike, so both put the same frames on the bus.
///
/// The frames (AS5047P datasheet v1-06, "SPI Read", one chip-select assertion
/// each): READ ANGLECOM, READ DIAAGC, READ NOP; the answers of the second and
/// third are the angle and DIAAGC. An answer of odd parity ends the sample
/// ([`Error::Parity`]); when every answer has even parity and one carries EF,
/// two more frames, READ ERRFL and READ NOP, read (and so clear) ERRFL
/// ([`Error::ErrorFlag`]; [`ERRFL_UNKNOWN`] when that read fails). At most 5
/// frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleSequence {
    phase: Phase,
    answers: [u16; 3],
    outcome: Option<Result<u16, Error<()>>>,
}

impl Default for SampleSequence {
    fn default() -> Self {
        Self::new()
    }
}

/// The most frames a [`SampleSequence`] sends.
pub const SAMPLE_MAX_FRAMES: usize = 5;

impl SampleSequence {
    /// A sample not started: its first command is READ ANGLECOM.
    pub const fn new() -> Self {
        Self { phase: Phase::Sampling(0), answers: [0; 3], outcome: None }
    }

    /// The command of the next frame (16-bit, even parity), or `None` once
    /// the sample is over ([`SampleSequence::outcome`]).
    pub fn command(&self) -> Option<u16> {
        match self.phase {
            Phase::Sampling(0) => Some(read_command(REG_ANGLECOM)),
            Phase::Sampling(1) => Some(read_command(REG_DIAAGC)),
            Phase::Sampling(_) | Phase::ErrflValue => Some(read_command(REG_NOP)),
            Phase::ErrflCommand => Some(read_command(REG_ERRFL)),
            Phase::Done => None,
        }
    }

    /// The answer `word` to the frame of [`SampleSequence::command`] (ignored
    /// once the sample is over).
    pub fn answer(&mut self, word: u16) {
        let parity_ok = has_even_parity(word);
        match self.phase {
            Phase::Sampling(n) => {
                if !parity_ok {
                    self.finish(Err(Error::Parity { frame: word }));
                    return;
                }
                self.answers[usize::from(n)] = word;
                if n < 2 {
                    self.phase = Phase::Sampling(n + 1);
                } else if self.answers.iter().any(|a| a & EF != 0) {
                    self.phase = Phase::ErrflCommand;
                } else {
                    let [_, angle, diaagc] = self.answers;
                    self.finish(Diagnostics::from_register(diaagc).check().map(|()| angle & DATA));
                }
            }
            // EF in the answer to READ ERRFL is expected (reading ERRFL is how
            // EF is cleared); only its parity counts.
            Phase::ErrflCommand if parity_ok => self.phase = Phase::ErrflValue,
            Phase::ErrflCommand => self.finish(Err(Error::ErrorFlag { errfl: ERRFL_UNKNOWN })),
            Phase::ErrflValue => {
                let errfl = if parity_ok { word & DATA } else { ERRFL_UNKNOWN };
                self.finish(Err(Error::ErrorFlag { errfl }));
            }
            Phase::Done => {}
        }
    }

    /// The frame of [`SampleSequence::command`] did not complete (the bus
    /// failed): the sample ends as [`Error::Bus`], or, while reading ERRFL,
    /// as [`Error::ErrorFlag`] with [`ERRFL_UNKNOWN`].
    pub fn transfer_failed(&mut self) {
        match self.phase {
            Phase::Sampling(_) => self.finish(Err(Error::Bus(()))),
            Phase::ErrflCommand | Phase::ErrflValue => self.finish(Err(Error::ErrorFlag { errfl: ERRFL_UNKNOWN })),
            Phase::Done => {}
        }
    }

    fn finish(&mut self, outcome: Result<u16, Error<()>>) {
        self.outcome = Some(outcome);
        self.phase = Phase::Done;
    }

    /// The sample's outcome once over (`None` before): the 14-bit angle in
    /// `[0, 2^14)` or the error, as [`As5047p::sample`] returns them
    /// (`Error::Bus(())` for a failed transfer: [`Error::with_bus`]).
    pub fn outcome(&self) -> Option<Result<u16, Error<()>>> {
        self.outcome
    }
}

/// One AS5047P on its own chip select.
///
/// `SPI` is the device (bus plus chip select) configured for mode 1 (CPOL 0,
/// CPHA 1), 16-bit words, at most 10 MHz, with chip select high for at least
/// 350 ns between frames (datasheet "SPI Timing", tCSn).
#[derive(Debug)]
pub struct As5047p<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice<u16>> As5047p<SPI> {
    /// Wraps `spi`; talks to nothing yet (call [`As5047p::check_ready`] at start-up).
    pub fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// One frame: sends `command`, returns the answer (to the previous command)
    /// after checking its parity. EF is left to the caller.
    fn frame(&mut self, command: u16) -> Result<u16, Error<SPI::Error>> {
        let mut word = [command];
        self.spi.transfer_in_place(&mut word).map_err(Error::Bus)?;
        let [answer] = word;
        if has_even_parity(answer) { Ok(answer) } else { Err(Error::Parity { frame: answer }) }
    }

    /// Sends `commands`, one frame each, and returns their answers: answer `i`
    /// is the reply to command `i - 1` (answer 0 to whatever came before). Every
    /// answer is checked for parity, then all of them for EF.
    fn frames<const N: usize>(&mut self, commands: [u16; N]) -> Result<[u16; N], Error<SPI::Error>> {
        let mut answers = [0u16; N];
        for (answer, command) in answers.iter_mut().zip(commands) {
            *answer = self.frame(command)?;
        }
        if answers.iter().any(|a| a & EF != 0) {
            return Err(Error::ErrorFlag { errfl: self.read_errfl().unwrap_or(ERRFL_UNKNOWN) });
        }
        Ok(answers)
    }

    /// READ ERRFL then READ NOP, ignoring EF in the answers (reading ERRFL is how
    /// EF is cleared; its own answer may still carry it). Returns bits 0..13.
    fn read_errfl(&mut self) -> Result<u16, Error<SPI::Error>> {
        self.frame(read_command(REG_ERRFL))?;
        Ok(self.frame(read_command(REG_NOP))? & DATA)
    }

    /// Reads register `addr` (bits 0..13; bits 14..15 ignored): 2 frames, the
    /// read command then a NOP read whose answer is the register (datasheet "SPI
    /// Read"). Returns the 14-bit data. For ERRFL use [`As5047p::error_flags`].
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::Parity`], [`Error::ErrorFlag`].
    pub fn read_register(&mut self, addr: u16) -> Result<u16, Error<SPI::Error>> {
        let [_, value] = self.frames([read_command(addr), read_command(REG_NOP)])?;
        Ok(value & DATA)
    }

    /// A fresh angle, sampled now: READ ANGLECOM then READ NOP (2 frames).
    /// Returns the 14-bit count in `[0, 2^14)`, one count = `2 pi / 2^14` rad.
    /// Does not look at the diagnostics: use [`As5047p::sample`] in the loop.
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::Parity`], [`Error::ErrorFlag`].
    pub fn angle(&mut self) -> Result<u16, Error<SPI::Error>> {
        self.read_register(REG_ANGLECOM)
    }

    /// The angle and the diagnostics of the same sample: READ ANGLECOM, READ
    /// DIAAGC, READ NOP (3 frames; datasheet "SPI Read", pipelined). Returns the
    /// 14-bit count in `[0, 2^14)` only if the diagnostics say it is valid.
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::Parity`], [`Error::ErrorFlag`], then from
    /// DIAAGC (see [`Diagnostics::check`]): [`Error::NotReady`],
    /// [`Error::Magnet`], [`Error::CordicOverflow`].
    pub fn sample(&mut self) -> Result<u16, Error<SPI::Error>> {
        // The frames of [`SampleSequence`], one chip-select assertion each: the
        // same bus traffic as a DMA acquisition of the same sequence.
        let mut seq = SampleSequence::new();
        let mut bus = None;
        while let Some(command) = seq.command() {
            let mut word = [command];
            match self.spi.transfer_in_place(&mut word) {
                Ok(()) => seq.answer(word[0]),
                Err(e) => {
                    bus.get_or_insert(e);
                    seq.transfer_failed();
                }
            }
        }
        match seq.outcome() {
            Some(Ok(angle)) => Ok(angle),
            Some(Err(e)) => Err(e.with_bus(bus)),
            // Unreachable: the loop runs until the sequence is done; a
            // sequence without an outcome is reported as a bus error.
            None => Err(Error::NotReady),
        }
    }

    /// Reads DIAAGC (2 frames) and decodes it, without judging it.
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::Parity`], [`Error::ErrorFlag`].
    pub fn diagnostics(&mut self) -> Result<Diagnostics, Error<SPI::Error>> {
        self.read_register(REG_DIAAGC).map(Diagnostics::from_register)
    }

    /// Reads ERRFL, which clears it (2 frames; EF in these answers is expected
    /// and ignored). Returns its bits 0..13 ([`ERRFL_FRERR`], [`ERRFL_INVCOMM`],
    /// [`ERRFL_PARERR`]).
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::Parity`].
    pub fn error_flags(&mut self) -> Result<u16, Error<SPI::Error>> {
        self.read_errfl()
    }

    /// Start-up check: clears the error flags left from power-up (their value
    /// is dropped), then reads DIAAGC and requires a finished offset compensation
    /// and a good field. Returns the diagnostics (AGC for the log). Only LF
    /// catches a chip missing from the bus (MISO all zeros); MISO floating high
    /// gives [`Error::ErrorFlag`].
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::Parity`], [`Error::ErrorFlag`],
    /// [`Error::NotReady`], [`Error::Magnet`], [`Error::CordicOverflow`].
    pub fn check_ready(&mut self) -> Result<Diagnostics, Error<SPI::Error>> {
        self.error_flags()?;
        let diagnostics = self.diagnostics()?;
        diagnostics.check()?;
        Ok(diagnostics)
    }
}

#[cfg(test)]
#[path = "as5047p_tests.rs"]
mod tests;
