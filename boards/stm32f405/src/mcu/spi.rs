//! SPI1 as the encoders' bus: master, mode 1 (CPOL 0, CPHA 1), 16-bit frames,
//! APB2 / 16 = 5.25 MHz (the AS5047P takes up to 10 MHz), software chip
//! selects (RM0090 28.3). Each encoder is an embedded-hal 1.0 `SpiDevice<u16>`
//! over the shared bus with its own chip select; every wait is bounded, so a
//! bus that never answers is an error, never a hang.

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use stm32f4::stm32f405 as pac;

use super::gpio;
use crate::pins::{self, Pin};

/// Polls of a status flag before a transfer counts as failed (a 16-bit frame
/// at 5.25 MHz is about 500 core cycles; a poll is a few).
const MAX_POLLS: u32 = 10_000;

/// Why a transfer failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum SpiError {
    /// A flag (TXE, RXNE, BSY) did not come within the bounded wait.
    Timeout,
    /// A received word was overwritten before it was read (SR.OVR).
    Overrun,
    /// Another master pulled NSS (SR.MODF).
    ModeFault,
    /// The period's frames are in flight by DMA (the acquisition): the
    /// bus is not free.
    Busy,
}

impl embedded_hal::spi::Error for SpiError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Timeout => ErrorKind::Other,
            Self::Overrun => ErrorKind::Overrun,
            Self::ModeFault => ErrorKind::ModeFault,
            Self::Busy => ErrorKind::Other,
        }
    }
}

fn spi() -> &'static pac::spi1::RegisterBlock {
    // SAFETY: SPI1 is used by the control interrupt only, one transfer at a time.
    unsafe { &*pac::SPI1::ptr() }
}

/// Sets up SPI1 and its pins (the clocks must be on).
pub fn init() {
    for p in [pins::SPI1_SCK, pins::SPI1_MISO, pins::SPI1_MOSI, pins::CS_THETA1, pins::CS_ELBOW] {
        gpio::configure(&p);
    }
    spi().cr1().write(|w| {
        w.cpha().second_edge().cpol().idle_low().mstr().master().br().div16().ssm().enabled().ssi().slave_not_selected();
        w.dff().sixteen_bit().spe().enabled()
    });
}

/// SPI1 asks DMA2 for each word (CR2 RXDMAEN, TXDMAEN: RM0090 28.3.9); the
/// streams decide whether anything moves.
pub fn enable_dma_requests() {
    spi().cr2().modify(|_, w| w.rxdmaen().set_bit().txdmaen().set_bit());
}

/// SPI1's DR, the address DMA2's streams move words to and from.
pub fn data_register_address() -> u32 {
    spi().dr().as_ptr() as u32
}

/// Whether SPI1 overran since the last look (SR's OVR: a word received before
/// the last was read, RM0090 28.4.8), cleared if so (DR, then SR, read). One
/// look, no wait: the acquisition's frame end (DMA2 stream 0's interrupt)
/// calls it, since the streams never read SR and an overrun left set would
/// freeze DR for every frame after.
pub fn take_overrun() -> bool {
    if spi().sr().read().ovr().bit_is_clear() {
        return false;
    }
    let _ = spi().dr().read();
    let _ = spi().sr().read();
    true
}

/// Empties SPI1's receiver after stopped frames: DR read (RXNE cleared), then
/// SR (OVR cleared, RM0090 28.4.8), so the next period's first word is not
/// taken for an overrun. One read each, no wait.
pub fn drain() {
    let _ = spi().dr().read();
    let _ = spi().sr().read();
}

fn wait(flag: impl Fn(&pac::spi1::sr::R) -> bool) -> Result<(), SpiError> {
    for _ in 0..MAX_POLLS {
        let sr = spi().sr().read();
        if sr.modf().bit_is_set() {
            return Err(SpiError::ModeFault);
        }
        if flag(&sr) {
            return Ok(());
        }
    }
    Err(SpiError::Timeout)
}

/// One 16-bit frame out and in.
fn exchange(word: u16) -> Result<u16, SpiError> {
    wait(|sr| sr.txe().bit_is_set())?;
    // SAFETY (bits): any 16-bit value is a frame.
    spi().dr().write(|w| unsafe { w.bits(word) });
    wait(|sr| sr.rxne().bit_is_set())?;
    if spi().sr().read().ovr().bit_is_set() {
        // Clear OVR: read DR then SR (RM0090 28.4.8).
        let _ = spi().dr().read();
        let _ = spi().sr().read();
        return Err(SpiError::Overrun);
    }
    Ok(spi().dr().read().bits())
}

/// One encoder on SPI1: its chip select, and who else may hold the bus.
#[derive(Debug, Clone, Copy)]
pub struct Spi1Device {
    cs: Pin,
    /// Whether the bus is taken by a DMA acquisition (`super::acquisition::busy`,
    /// given by the caller so that this driver knows nothing above it).
    bus_taken: fn() -> bool,
}

impl Spi1Device {
    /// The device behind chip select `cs` (a pin of the map, configured by [`init`]);
    /// `bus_taken` says when frames are in flight by DMA: the device then refuses a
    /// transaction ([`SpiError::Busy`]).
    pub fn new(cs: Pin, bus_taken: fn() -> bool) -> Self {
        Self { cs, bus_taken }
    }
}

impl ErrorType for Spi1Device {
    type Error = SpiError;
}

impl SpiDevice<u16> for Spi1Device {
    fn transaction(&mut self, operations: &mut [Operation<'_, u16>]) -> Result<(), SpiError> {
        // Start-up and bring-up only (the tick's frames go by DMA): never
        // across a period's frames.
        if (self.bus_taken)() {
            return Err(SpiError::Busy);
        }
        gpio::write(&self.cs, false);
        let result = operations.iter_mut().try_for_each(|op| match op {
            Operation::Read(words) => words.iter_mut().try_for_each(|w| exchange(0).map(|r| *w = r)),
            Operation::Write(words) => words.iter().try_for_each(|&w| exchange(w).map(drop)),
            Operation::Transfer(read, write) => {
                for i in 0..read.len().max(write.len()) {
                    let r = exchange(write.get(i).copied().unwrap_or(0))?;
                    if let Some(slot) = read.get_mut(i) {
                        *slot = r;
                    }
                }
                Ok(())
            }
            Operation::TransferInPlace(words) => words.iter_mut().try_for_each(|w| exchange(*w).map(|r| *w = r)),
            Operation::DelayNs(ns) => {
                cortex_m::asm::delay(ns.saturating_mul(crate::clock_tree::SYSCLK_HZ / 1_000_000) / 1000 + 1);
                Ok(())
            }
        });
        let idle = wait(|sr| sr.bsy().bit_is_clear());
        gpio::write(&self.cs, true);
        // The AS5047P needs CSn high for 350 ns between frames: about 60 cycles.
        cortex_m::asm::delay(64);
        result.and(idle)
    }
}
