//! SPI1 with the two AS5047P on their chip selects (RM0090 28 "Serial
//! peripheral interface"; AS5047P datasheet v1-06, "SPI Interface"): the
//! registers the image uses, and each frame handed to the board twin's AS5047P
//! model (`board_twin::as5047p`) of the encoder whose chip select is low.
//!
//! Strict: a frame sent while SPI1 is enabled with a configuration the AS5047P
//! cannot speak is a [`BoardError`] naming `SPI1_CR1` and its value: not master,
//! CPOL 1, CPHA 0 (it needs mode 1: CPOL 0, CPHA 1), 8-bit frames, LSB first, a
//! clock above the AS5047P's 10 MHz (APB2 at 84 MHz: `BR` at least /16), a
//! hardware NSS that would raise a mode fault. So is a frame with no chip
//! select low or both low, and a second frame in one chip-select assertion (the
//! AS5047P needs CSn high between frames). Behaviour as the part's: a frame
//! while `SPE` is clear goes nowhere; a word received while the last is unread
//! sets `OVR` and is lost (cleared by reading DR then SR); a mode fault sets
//! `MODF` and clears `SPE` and `MSTR` (RM0090 28.4.8).
//!
//! DMA: with CR2's TXDMAEN and RXDMAEN, DMA2's streams move the words
//! ([`crate::dma2`], [`Spi1::dma_exchange`]). Not modelled: the transfer's
//! duration (a frame completes at once: `TXE` is always set, `BSY` never), CRC,
//! TI mode, I2S.

use board_twin::as5047p::As5047pModel;
use embedded_hal::spi::{Operation, SpiDevice};

use crate::device::{BoardError, RegisterModel, Result2};

const BASE: u32 = 0x4001_3000;
const CR1: u32 = 0x00;
const CR2: u32 = 0x04;
const SR: u32 = 0x08;
const DR: u32 = 0x0C;
const CRCPR: u32 = 0x10;

const CPHA: u32 = 1 << 0;
const CPOL: u32 = 1 << 1;
const MSTR: u32 = 1 << 2;
const SPE: u32 = 1 << 6;
const LSBFIRST: u32 = 1 << 7;
const SSI: u32 = 1 << 8;
const SSM: u32 = 1 << 9;
const DFF: u32 = 1 << 11;
const SSOE: u32 = 1 << 2; // CR2
const RXDMAEN: u32 = 1 << 0; // CR2
const TXDMAEN: u32 = 1 << 1; // CR2

const RXNE: u32 = 1 << 0;
const TXE: u32 = 1 << 1;
const MODF: u32 = 1 << 5;
const OVR: u32 = 1 << 6;

/// APB2's clock on the reference board (RM0090 clock tree: 168 MHz / 2), Hz.
pub const APB2_HZ: u32 = 84_000_000;
/// The AS5047P's fastest SPI clock (datasheet: f_SPI 10 MHz), Hz.
pub const AS5047P_MAX_SCK_HZ: u32 = 10_000_000;

/// Faults acting on SPI1's registers this period (issue 38, "faults at the
/// register level").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SpiFaults {
    /// The next received word finds the last one unread: `OVR`, the word lost.
    pub overrun: bool,
    /// Another master pulls NSS: `MODF`; the hardware clears `SPE` and `MSTR`.
    pub mode_fault: bool,
}

/// SPI1 and the two encoders behind it.
pub struct Spi1 {
    cr1: u32,
    cr2: u32,
    /// The received word not yet read (`RXNE`).
    rx: Option<u16>,
    ovr: bool,
    /// `OVR` is cleared by a read of DR then of SR.
    ovr_dr_read: bool,
    modf: bool,
    /// Each chip select's level `[theta1 (PA4), elbow (PB0)]` (high: deselected).
    cs_high: [bool; 2],
    /// Frames in the current assertion of each chip select.
    frames_in_assertion: [u32; 2],
    encoders: [As5047pModel; 2],
    /// This period's faults (set by the host, consumed by the next frame).
    pub faults: SpiFaults,
    /// Frames exchanged with each encoder.
    pub frames: [u64; 2],
}

impl Spi1 {
    /// SPI1 at reset, the encoders `[theta1, elbow]` behind it, both chip
    /// selects high (the board's pull-ups).
    pub fn new(encoders: [As5047pModel; 2]) -> Self {
        Self {
            cr1: 0,
            cr2: 0,
            rx: None,
            ovr: false,
            ovr_dr_read: false,
            modf: false,
            cs_high: [true; 2],
            frames_in_assertion: [0; 2],
            encoders,
            faults: SpiFaults::default(),
            frames: [0; 2],
        }
    }

    fn sr(&self) -> u32 {
        TXE | if self.rx.is_some() { RXNE } else { 0 } | if self.ovr { OVR } else { 0 } | if self.modf { MODF } else { 0 }
    }

    /// Why the AS5047P could not speak with SPI1 configured as `cr1`, `cr2`.
    fn check(&self) -> Result2<()> {
        let err = |why: String| Err(BoardError::new(format!("SPI1_CR1 ({BASE:#010x})"), self.cr1, why));
        let c = self.cr1;
        if c & MSTR == 0 {
            return err("slave mode: the MCU must be the master of the encoders' bus (MSTR = 1)".into());
        }
        if c & CPOL != 0 || c & CPHA == 0 {
            return err(format!(
                "SPI mode {} (CPOL {}, CPHA {}): the AS5047P speaks mode 1 only (CPOL 0, CPHA 1; datasheet, SPI timing)",
                (c & CPOL) | (c & CPHA),
                (c & CPOL) >> 1,
                c & CPHA
            ));
        }
        if c & DFF == 0 {
            return err("8-bit frames: the AS5047P's frames are 16 bits (DFF = 1)".into());
        }
        if c & LSBFIRST != 0 {
            return err("LSB first: the AS5047P sends and takes the MSB first (LSBFIRST = 0)".into());
        }
        let br = (c >> 3) & 0b111;
        let sck = APB2_HZ >> (br + 1);
        if sck > AS5047P_MAX_SCK_HZ {
            return err(format!("SCK {:.2} MHz (APB2 84 MHz / {}): above the AS5047P's 10 MHz", f64::from(sck) / 1e6, 2 << br));
        }
        if c & SSM == 0 && self.cr2 & SSOE == 0 {
            return err(
                "hardware NSS without SSOE: NSS would float and raise a mode fault; use SSM = 1, SSI = 1 (software chip selects)".into()
            );
        }
        if c & SSM != 0 && c & SSI == 0 {
            return err("SSM = 1 with SSI = 0: the internal NSS is low, a mode fault (RM0090 28.3.3)".into());
        }
        Ok(())
    }

    /// One frame out: to the encoder whose chip select is low, its answer into DR.
    fn frame(&mut self, word: u16) -> Result2<()> {
        if self.cr1 & SPE == 0 {
            // A disabled SPI sends nothing; RXNE never comes.
            return Ok(());
        }
        if core::mem::take(&mut self.faults.mode_fault) {
            self.modf = true;
            self.cr1 &= !(SPE | MSTR);
            return Ok(());
        }
        self.check()?;
        let selected = match self.cs_high {
            [false, true] => 0,
            [true, false] => 1,
            [true, true] => {
                return Err(BoardError::new(
                    format!("SPI1_DR ({:#010x})", BASE + DR),
                    u32::from(word),
                    "a frame with no chip select low (PA4 theta1, PB0 elbow): it reaches no encoder",
                ));
            }
            [false, false] => {
                return Err(BoardError::new(
                    format!("SPI1_DR ({:#010x})", BASE + DR),
                    u32::from(word),
                    "a frame with both chip selects low: the two AS5047P drive MISO together",
                ));
            }
        };
        self.frames_in_assertion[selected] += 1;
        if self.frames_in_assertion[selected] > 1 {
            return Err(BoardError::new(
                format!("SPI1_DR ({:#010x})", BASE + DR),
                u32::from(word),
                format!(
                    "a second frame to the {} encoder in one chip-select assertion: the AS5047P needs CSn high between frames (datasheet: t_CSn >= 350 ns)",
                    ["theta1", "elbow"][selected]
                ),
            ));
        }
        let mut buf = [word];
        // A dead bus reads MISO's pull-up: all ones.
        let answer = match self.encoders[selected].transaction(&mut [Operation::TransferInPlace(&mut buf)]) {
            Ok(()) => buf[0],
            Err(_) => 0xFFFF,
        };
        self.frames[selected] += 1;
        let injected = core::mem::take(&mut self.faults.overrun);
        if self.rx.is_some() || injected {
            // RM0090 28.4.8: the new word does not overwrite the unread one (an
            // injected overrun: an earlier word, never read, holds DR).
            self.ovr = true;
            self.ovr_dr_read = false;
            self.rx.get_or_insert(0);
        } else {
            self.rx = Some(answer);
        }
        Ok(())
    }
}

impl Spi1 {
    /// DMA2's TX stream writes `word` to DR (RM0090 28.3.9): `Ok(None)` when
    /// SPI1 does not ask for it (TXDMAEN or SPE clear: the stream waits);
    /// otherwise the frame goes out, and the word received is returned for
    /// the RX stream when `rx_stream` is enabled and RXDMAEN set (`Some(None)`:
    /// it stays in DR, RXNE set).
    ///
    /// # Errors
    /// As a frame written by the core ([`BoardError`]).
    pub fn dma_exchange(&mut self, word: u16, rx_stream: bool) -> Result2<Option<Option<u16>>> {
        if self.cr2 & TXDMAEN == 0 || self.cr1 & SPE == 0 {
            return Ok(None);
        }
        self.frame(word)?;
        if rx_stream && self.cr2 & RXDMAEN != 0 && !self.ovr {
            return Ok(Some(self.rx.take()));
        }
        Ok(Some(None))
    }
}

impl RegisterModel for Spi1 {
    fn read(&mut self, offset: u32) -> Result2<u32> {
        match offset {
            CR1 => Ok(self.cr1),
            CR2 => Ok(self.cr2),
            SR => {
                let sr = self.sr();
                if self.ovr && self.ovr_dr_read {
                    self.ovr = false;
                    self.ovr_dr_read = false;
                }
                Ok(sr)
            }
            DR => {
                self.ovr_dr_read = self.ovr;
                Ok(u32::from(self.rx.take().unwrap_or(0)))
            }
            CRCPR => Ok(7),
            _ => Err(unmodelled(offset)),
        }
    }

    fn write(&mut self, offset: u32, value: u32) -> Result2<()> {
        match offset {
            CR1 => {
                // Writing CR1 after reading SR clears MODF (RM0090 28.4.8).
                self.modf = false;
                self.cr1 = value & 0xFFFF;
                Ok(())
            }
            CR2 => {
                self.cr2 = value & 0xF7;
                Ok(())
            }
            SR => Ok(()),
            DR => self.frame(value as u16),
            _ => Err(unmodelled(offset)),
        }
    }

    fn input(&mut self, line: u32, high: bool) -> Result2<()> {
        if let Some(l) = self.cs_high.get_mut(line as usize) {
            if high && !*l {
                self.frames_in_assertion[line as usize] = 0;
            }
            *l = high;
        }
        Ok(())
    }

    fn peek(&self, offset: u32) -> u32 {
        match offset {
            CR1 => self.cr1,
            CR2 => self.cr2,
            SR => self.sr(),
            DR => u32::from(self.rx.unwrap_or(0)),
            _ => 0,
        }
    }

    fn reset(&mut self) {
        // The MCU's registers only: the chip selects' levels are the GPIO's, the
        // encoders are chips of their own, the faults and counts the host's.
        self.cr1 = 0;
        self.cr2 = 0;
        self.rx = None;
        self.ovr = false;
        self.ovr_dr_read = false;
        self.modf = false;
        self.frames_in_assertion = [0; 2];
    }
}

fn unmodelled(offset: u32) -> BoardError {
    BoardError::new(
        format!("SPI1 +{offset:#x} ({:#010x})", BASE + offset),
        0,
        "a register the SPI1 model does not implement (CR1, CR2, SR, DR, CRCPR only): the image uses more of SPI1 than the board was checked for",
    )
}

#[cfg(test)]
mod tests {
    use board_twin::bench::{Bench, Shared, lock};

    use super::*;

    /// The image's configuration (`mcu/spi.rs`): master, mode 1, /16, SSM and SSI, 16-bit, enabled.
    const GOOD: u32 = CPHA | MSTR | (0b011 << 3) | SSI | SSM | DFF | SPE;

    fn spi() -> (Spi1, Shared) {
        let bench: Shared = std::sync::Arc::new(std::sync::Mutex::new(Bench::default()));
        lock(&bench).magnet_counts = [1234.0, 4321.0];
        (Spi1::new([As5047pModel::new(bench.clone(), 0), As5047pModel::new(bench.clone(), 1)]), bench)
    }

    /// One frame to encoder `cs` (0 or 1) the way the image sends it: CS low,
    /// DR, RXNE, DR read, CS high.
    fn frame(s: &mut Spi1, cs: u32, word: u16) -> Result2<u16> {
        s.input(cs, false)?;
        s.write(DR, u32::from(word))?;
        assert_ne!(s.read(SR)? & RXNE, 0, "RXNE after a frame");
        let r = s.read(DR)? as u16;
        s.input(cs, true)?;
        Ok(r)
    }

    #[test]
    fn the_images_configuration_reads_each_encoder_on_its_own_chip_select() {
        let (mut s, _) = spi();
        s.write(CR1, GOOD).unwrap();
        // ANGLECOM read (0x3FFF | read bit, even parity: 0xFFFF), answered in the next frame.
        frame(&mut s, 0, 0xFFFF).unwrap();
        let a = frame(&mut s, 0, 0xC000).unwrap();
        frame(&mut s, 1, 0xFFFF).unwrap();
        let b = frame(&mut s, 1, 0xC000).unwrap();
        assert_eq!((a & 0x3FFF, b & 0x3FFF), (1234, 4321));
        assert_eq!(s.frames, [2, 2]);
    }

    #[test]
    fn every_configuration_the_as5047p_cannot_speak_is_an_error_naming_cr1() {
        for (bad, why) in [
            (GOOD & !CPHA, "mode 1"),
            (GOOD | CPOL, "mode 1"),
            (GOOD & !DFF, "16 bits"),
            (GOOD | LSBFIRST, "MSB first"),
            (GOOD & !(0b111 << 3) | (0b010 << 3), "10 MHz"),
            (GOOD & !MSTR, "master"),
            (GOOD & !SSM, "NSS"),
            (GOOD & !SSI, "mode fault"),
        ] {
            let (mut s, _) = spi();
            s.write(CR1, bad).unwrap();
            let e = frame(&mut s, 0, 0xFFFF).unwrap_err();
            assert!(e.register.starts_with("SPI1_CR1") && e.value == bad && e.why.contains(why), "{bad:#x}: {e}");
        }
    }

    #[test]
    fn chip_selects_must_frame_exactly_one_word_for_one_encoder() {
        let (mut s, _) = spi();
        s.write(CR1, GOOD).unwrap();
        let e = s.write(DR, 0xFFFF).unwrap_err();
        assert!(e.why.contains("no chip select"), "{e}");
        s.input(0, false).unwrap();
        s.input(1, false).unwrap();
        assert!(s.write(DR, 0xFFFF).unwrap_err().why.contains("both chip selects"));
        s.input(1, true).unwrap();
        s.write(DR, 0xFFFF).unwrap();
        let _ = s.read(DR);
        assert!(s.write(DR, 0xFFFF).unwrap_err().why.contains("CSn high between frames"));
    }

    #[test]
    fn an_injected_overrun_sets_ovr_cleared_by_dr_then_sr_and_a_mode_fault_disables_spi1() {
        let (mut s, _) = spi();
        s.write(CR1, GOOD).unwrap();
        s.faults.overrun = true;
        s.input(0, false).unwrap();
        s.write(DR, 0xFFFF).unwrap();
        assert_ne!(s.read(SR).unwrap() & OVR, 0);
        let _ = s.read(DR).unwrap();
        let _ = s.read(SR).unwrap();
        assert_eq!(s.read(SR).unwrap() & OVR, 0, "DR then SR clears OVR (RM0090 28.4.8)");
        s.input(0, true).unwrap();
        s.faults.mode_fault = true;
        s.input(0, false).unwrap();
        s.write(DR, 0xFFFF).unwrap();
        assert_ne!(s.read(SR).unwrap() & MODF, 0);
        assert_eq!(s.read(CR1).unwrap() & (SPE | MSTR), 0, "MODF clears SPE and MSTR");
        // A disabled SPI sends nothing: no RXNE, no error.
        s.input(0, true).unwrap();
        s.input(0, false).unwrap();
        s.write(DR, 0xFFFF).unwrap();
        assert_eq!(s.read(SR).unwrap() & RXNE, 0);
    }

    #[test]
    fn a_register_the_model_lacks_is_an_error_with_its_address() {
        let (mut s, _) = spi();
        let e = s.read(0x1C).unwrap_err();
        assert!(e.register.contains("0x4001301c"), "{e}");
    }
}
