//! DMA2 as the board uses it (RM0090 10 "DMA controller"; issue 56): SPI1's
//! requests on their streams, each word moved between SRAM and SPI1's DR, the
//! frames handed to [`crate::spi1::Spi1`] and so to the board twin's AS5047P
//! models. The register face is the part's (LISR, HISR, LIFCR, HIFCR; per
//! stream SxCR, SxNDTR, SxPAR, SxM0AR, SxM1AR, SxFCR); memory is reached over
//! the machine's `dmabus` space, where CCM is not mapped (RM0090 2.3).
//!
//! Strict: enabling a stream with a configuration that would not move SPI1's
//! words is a [`BoardError`] naming the stream's register and its value: a
//! stream SPI1 does not request (SPI1_RX is stream 0 or 2, SPI1_TX stream 3 or
//! 5, RM0090 10.3.3 table 43), another channel than 3, the wrong direction (RX
//! peripheral-to-memory, TX memory-to-peripheral), a size other than 16 bits
//! on either side (SPI1's frames are 16 bits), a peripheral address other than
//! SPI1_DR or incremented, circular, double-buffer or peripheral-flow-control
//! modes (not what the image does, not modelled), an empty count. A memory
//! address the DMA cannot reach is the part's TEIF (the stream disabled).
//!
//! Timing as the SPI1 model's: a frame completes at once. The transfer runs when
//! a TX stream is enabled while SPI1 asks for it (CR2 TXDMAEN, SPE); each word
//! received goes to the enabled RX stream (CR2 RXDMAEN) or stays in SPI1's DR.
//! A stream whose count reaches zero sets TCIF and clears EN. The interrupt
//! output is stream 0's (the board wires DMA2_Stream0, IRQ 56): TCIF, TEIF,
//! DMEIF and FEIF with their enables; stream 3's interrupt line is not wired,
//! so its enables are refused.
//!
//! Faults the host injects ([`DmaFaults`], consumed by the next transfer): a
//! TEIF on the TX stream (its memory read fails; the stream disabled), an
//! FEIF or a DMEIF on the RX stream (no word moves), or no request at all (a
//! stalled transfer).

use std::sync::{Arc, Weak};

use rsemu::core::{
    space::{AddressSpace, MemAttrs, RequesterId},
    value::Width,
};

use crate::{
    device::{BoardError, Hub, RegisterModel, Result2},
    spi1::Spi1,
};

const BASE: u32 = 0x4002_6400;
const LISR: u32 = 0x00;
const HISR: u32 = 0x04;
const LIFCR: u32 = 0x08;
const HIFCR: u32 = 0x0C;
const STREAMS: u32 = 8;
const STREAM_BASE: u32 = 0x10;
const STREAM_STRIDE: u32 = 0x18;

const EN: u32 = 1 << 0;
const DMEIE: u32 = 1 << 1;
const TEIE: u32 = 1 << 2;
const HTIE: u32 = 1 << 3;
const TCIE: u32 = 1 << 4;
const PFCTRL: u32 = 1 << 5;
const CIRC: u32 = 1 << 8;
const PINC: u32 = 1 << 9;
const MINC: u32 = 1 << 10;
const DBM: u32 = 1 << 18;
const FEIE: u32 = 1 << 7; // SxFCR

// A stream's flags, normalised (RM0090 10.5.1's bit order within a group).
const FEIF: u32 = 1 << 0;
const DMEIF: u32 = 1 << 2;
const TEIF: u32 = 1 << 3;
const HTIF: u32 = 1 << 4;
const TCIF: u32 = 1 << 5;
const FLAGS: u32 = FEIF | DMEIF | TEIF | HTIF | TCIF;
/// Where stream `s % 4`'s group starts in LISR/HISR.
const SHIFT: [u32; 4] = [0, 6, 16, 22];

/// SPI1's data register, the only peripheral address a stream may hold here.
pub const SPI1_DR: u32 = 0x4001_300C;
/// SPI1's channel on its streams (RM0090 table 43).
pub const SPI1_CHANNEL: u32 = 3;
/// The streams SPI1_RX may use.
pub const SPI1_RX_STREAMS: [usize; 2] = [0, 2];
/// The streams SPI1_TX may use.
pub const SPI1_TX_STREAMS: [usize; 2] = [3, 5];

/// Faults acting on DMA2's next transfer (issue 56: the acquisition's faults
/// at the register level).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DmaFaults {
    /// The TX stream's memory read fails: TEIF, the stream disabled, no frame.
    pub transfer_error: bool,
    /// The RX stream's FIFO error: FEIF, no frame.
    pub fifo_error: bool,
    /// The RX stream's direct-mode error: DMEIF, no frame.
    pub direct_mode_error: bool,
    /// No request reaches the streams: nothing moves, no flag.
    pub stall: bool,
}

impl DmaFaults {
    fn any(&self) -> bool {
        self.transfer_error || self.fifo_error || self.direct_mode_error || self.stall
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct Stream {
    cr: u32,
    ndtr: u32,
    par: u32,
    m0ar: u32,
    m1ar: u32,
    fcr: u32,
    /// Words moved so far in this transfer.
    done: u32,
}

/// DMA2 and the link to SPI1.
pub struct Dma2 {
    streams: [Stream; 8],
    flags: [u32; 8],
    hub: Weak<Hub>,
    bus: Option<(Arc<AddressSpace>, RequesterId)>,
    /// The next transfer's faults (set by the host).
    pub faults: DmaFaults,
    /// Words moved by each stream since power-up.
    pub words: [u64; 8],
}

impl Dma2 {
    /// DMA2 at reset, reaching SPI1 through `hub`'s `spi1` window.
    pub fn new(hub: Weak<Hub>) -> Self {
        Self { streams: [Stream::default(); 8], flags: [0; 8], hub, bus: None, faults: DmaFaults::default(), words: [0; 8] }
    }

    fn reg(s: usize, name: &str) -> String {
        format!("DMA2_S{s}{name} ({:#010x})", BASE + STREAM_BASE + STREAM_STRIDE * s as u32)
    }

    /// Why stream `s` enabled with `cr` could not move SPI1's words.
    fn check(&self, s: usize, cr: u32) -> Result2<()> {
        let st = &self.streams[s];
        let err = |why: String| Err(BoardError::new(Self::reg(s, "CR"), cr, why));
        let rx = SPI1_RX_STREAMS.contains(&s);
        let tx = SPI1_TX_STREAMS.contains(&s);
        if !rx && !tx {
            return err(format!(
                "stream {s}: SPI1 requests no such stream (SPI1_RX: stream 0 or 2, SPI1_TX: stream 3 or 5, channel 3; RM0090 10.3.3 table 43), and nothing else on this board uses DMA2"
            ));
        }
        let chsel = (cr >> 25) & 0b111;
        if chsel != SPI1_CHANNEL {
            return err(format!("channel {chsel}: SPI1's requests are channel 3 of streams 0, 2, 3, 5 (RM0090 table 43)"));
        }
        let dir = (cr >> 6) & 0b11;
        let (want, what) =
            if rx { (0b00, "SPI1_RX: peripheral to memory (DIR = 00)") } else { (0b01, "SPI1_TX: memory to peripheral (DIR = 01)") };
        if dir != want {
            return err(format!("direction {dir:#04b}: stream {s} is {what}"));
        }
        let (psize, msize) = ((cr >> 11) & 0b11, (cr >> 13) & 0b11);
        if psize != 0b01 || msize != 0b01 {
            return err(format!(
                "PSIZE {psize:#04b}, MSIZE {msize:#04b}: SPI1's frames are 16 bits (DFF = 1), so both sizes must be half-words (01)"
            ));
        }
        if cr & (CIRC | DBM | PFCTRL) != 0 {
            return err(
                "circular, double-buffer or peripheral flow control: not what the image's acquisition does, and not modelled".into()
            );
        }
        if cr & PINC != 0 || cr & MINC == 0 {
            return err("the peripheral address incremented or the memory address fixed: SPI1_DR is one register, the words are an array (PINC = 0, MINC = 1)".into());
        }
        if st.par != SPI1_DR {
            return Err(BoardError::new(Self::reg(s, "PAR"), st.par, "the peripheral address is not SPI1_DR (0x4001300c)"));
        }
        if st.ndtr == 0 {
            return Err(BoardError::new(Self::reg(s, "NDTR"), 0, "an empty transfer: the stream would complete at once (RM0090 10.3.10)"));
        }
        if s != 0 && (cr & (TCIE | TEIE | DMEIE | HTIE) != 0 || st.fcr & FEIE != 0) {
            return err(format!(
                "stream {s}'s interrupts: the emulated board wires only DMA2_Stream0's line (IRQ 56); take the TX stream's flags in stream 0's handler"
            ));
        }
        Ok(())
    }

    fn enabled(&self, streams: [usize; 2]) -> Option<usize> {
        streams.into_iter().find(|&s| self.streams[s].cr & EN != 0)
    }

    fn end(&mut self, s: usize, flag: u32) {
        self.flags[s] |= flag;
        self.streams[s].cr &= !EN;
    }

    /// Moves words while a TX stream is enabled and SPI1 asks for them.
    fn run(&mut self) -> Result2<()> {
        let Some(tx) = self.enabled(SPI1_TX_STREAMS) else { return Ok(()) };
        let Some(hub) = self.hub.upgrade() else { return Ok(()) };
        let Some(window) = hub.window("spi1") else { return Ok(()) };
        if self.faults.any() {
            let f = std::mem::take(&mut self.faults);
            let rx = self.enabled(SPI1_RX_STREAMS);
            if f.transfer_error {
                self.end(tx, TEIF);
            } else if let (true, Some(rx)) = (f.fifo_error, rx) {
                self.flags[rx] |= FEIF;
            } else if let (true, Some(rx)) = (f.direct_mode_error, rx) {
                self.flags[rx] |= DMEIF;
            }
            return Ok(());
        }
        let Some((space, requester)) = self.bus.clone() else { return Ok(()) };
        let attrs = MemAttrs::DEFAULT.with_requester(requester);
        while self.streams[tx].cr & EN != 0 && self.streams[tx].done < self.streams[tx].ndtr {
            let st = self.streams[tx];
            let word = match space.read(u64::from(st.m0ar + 2 * st.done), Width::U16, attrs) {
                Ok(w) => w as u16,
                Err(_) => {
                    self.end(tx, TEIF);
                    return Ok(());
                }
            };
            let rx_stream = self.enabled(SPI1_RX_STREAMS);
            let answer = window.with(|m| {
                (m as &mut dyn std::any::Any).downcast_mut::<Spi1>().map(|spi| spi.dma_exchange(word, rx_stream.is_some())).transpose()
            })?;
            let Some(exchanged) = answer else { return Ok(()) };
            // SPI1 not asking (TXDMAEN clear, SPE clear): the stream waits.
            let Some(received) = exchanged else { return Ok(()) };
            self.streams[tx].done += 1;
            self.words[tx] += 1;
            if self.streams[tx].done == self.streams[tx].ndtr {
                self.end(tx, TCIF);
            }
            if let (Some(rx), Some(received)) = (rx_stream, received) {
                let r = self.streams[rx];
                if space.write(u64::from(r.m0ar + 2 * r.done), Width::U16, u64::from(received), attrs).is_err() {
                    self.end(rx, TEIF);
                    continue;
                }
                self.streams[rx].done += 1;
                self.words[rx] += 1;
                if self.streams[rx].done == r.ndtr {
                    self.end(rx, TCIF);
                }
            }
        }
        Ok(())
    }

    fn status(&self, high: bool) -> u32 {
        let first = if high { 4 } else { 0 };
        (0..4).map(|i| (self.flags[first + i] & FLAGS) << SHIFT[i]).fold(0, |a, b| a | b)
    }

    fn clear(&mut self, high: bool, value: u32) {
        let first = if high { 4 } else { 0 };
        for (f, shift) in self.flags[first..first + 4].iter_mut().zip(SHIFT) {
            *f &= !((value >> shift) & FLAGS);
        }
    }
}

impl RegisterModel for Dma2 {
    fn read(&mut self, offset: u32) -> Result2<u32> {
        self.peek_checked(offset)
    }

    fn write(&mut self, offset: u32, value: u32) -> Result2<()> {
        match offset {
            LISR | HISR => Ok(()),
            LIFCR => {
                self.clear(false, value);
                Ok(())
            }
            HIFCR => {
                self.clear(true, value);
                Ok(())
            }
            o if (STREAM_BASE..STREAM_BASE + STREAM_STRIDE * STREAMS).contains(&o) => {
                let s = ((o - STREAM_BASE) / STREAM_STRIDE) as usize;
                let r = (o - STREAM_BASE) % STREAM_STRIDE;
                let enabled = self.streams[s].cr & EN != 0;
                if enabled && r != 0 {
                    // RM0090 10.5.5: the other registers are write-protected while EN = 1.
                    return Err(BoardError::new(
                        Self::reg(s, ["CR", "NDTR", "PAR", "M0AR", "M1AR", "FCR"][r as usize / 4]),
                        value,
                        "written while the stream is enabled (EN = 1): the write is ignored on the part (RM0090 10.3.17)",
                    ));
                }
                match r {
                    0x00 => {
                        if value & EN != 0 && !enabled {
                            self.check(s, value)?;
                            if self.flags[s] & (TCIF | TEIF | FEIF | DMEIF) != 0 {
                                return Err(BoardError::new(
                                    Self::reg(s, "CR"),
                                    value,
                                    "EN set with the stream's flags still set in LISR/HISR: clear them first (RM0090 10.3.17)",
                                ));
                            }
                            self.streams[s].done = 0;
                            self.streams[s].cr = value & 0x0FFF_FFFF;
                            self.run()?;
                        } else {
                            self.streams[s].cr = value & 0x0FFF_FFFF;
                        }
                    }
                    0x04 => self.streams[s].ndtr = value & 0xFFFF,
                    0x08 => self.streams[s].par = value,
                    0x0C => self.streams[s].m0ar = value,
                    0x10 => self.streams[s].m1ar = value,
                    _ => self.streams[s].fcr = value & 0b1000_0111,
                }
                Ok(())
            }
            _ => Err(unmodelled(offset)),
        }
    }

    fn peek(&self, offset: u32) -> u32 {
        self.peek_checked(offset).unwrap_or(0)
    }

    fn irq(&self) -> bool {
        let (cr, fcr, f) = (self.streams[0].cr, self.streams[0].fcr, self.flags[0]);
        (f & TCIF != 0 && cr & TCIE != 0)
            || (f & TEIF != 0 && cr & TEIE != 0)
            || (f & DMEIF != 0 && cr & DMEIE != 0)
            || (f & FEIF != 0 && fcr & FEIE != 0)
    }

    fn reset(&mut self) {
        self.streams = [Stream::default(); 8];
        self.flags = [0; 8];
    }

    fn bind_bus(&mut self, space: Arc<AddressSpace>, requester: RequesterId) {
        self.bus = Some((space, requester));
    }
}

impl Dma2 {
    fn peek_checked(&self, offset: u32) -> Result2<u32> {
        match offset {
            LISR => Ok(self.status(false)),
            HISR => Ok(self.status(true)),
            LIFCR | HIFCR => Ok(0),
            o if (STREAM_BASE..STREAM_BASE + STREAM_STRIDE * STREAMS).contains(&o) => {
                let st = &self.streams[((o - STREAM_BASE) / STREAM_STRIDE) as usize];
                Ok(match (o - STREAM_BASE) % STREAM_STRIDE {
                    0x00 => st.cr,
                    0x04 => st.ndtr - st.done.min(st.ndtr),
                    0x08 => st.par,
                    0x0C => st.m0ar,
                    0x10 => st.m1ar,
                    // FS = 100: the FIFO empty (direct mode moves each word at once).
                    _ => st.fcr | 0b100 << 3,
                })
            }
            _ => Err(unmodelled(offset)),
        }
    }
}

fn unmodelled(offset: u32) -> BoardError {
    BoardError::new(
        format!("DMA2 +{offset:#x} ({:#010x})", BASE + offset),
        0,
        "a register the DMA2 model does not implement (LISR, HISR, LIFCR, HIFCR and the eight streams' registers only)",
    )
}
