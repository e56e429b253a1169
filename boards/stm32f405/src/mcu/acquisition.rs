//! The encoders by DMA (issue 56; docs/board.md "The encoders by DMA"): TIM2's
//! update starts the period's frames to the two AS5047P on SPI1, DMA2 moves
//! each word (SPI1_TX on stream 3, SPI1_RX on stream 0, both channel 3: RM0090
//! 10.3.3 table 43), and the RX stream's transfer-complete interrupt releases
//! the chip select, takes the answer and starts the next frame
//! (`drivers::as5047p::SampleSequence`: theta1's frames, then the elbow's, one
//! chip-select assertion each). After the last frame the load cell's injected
//! conversions (started by the same update's TRGO, done 1.4 us after it) are
//! copied, and the control interrupt is pended: it reads memory and computes,
//! and never waits on a peripheral.
//!
//! Faults, each named ([`AcquisitionFault`]) and invalidating both encoders'
//! readings of the period (three periods in a row: the safe state, reason 2
//! `BadFrames`):
//! - a stream's TEIF, FEIF or DMEIF (DMA_LISR, RM0090 10.5.1), seen in the RX
//!   stream's interrupt (TEIE, DMEIE, FEIE on);
//! - frames not done by [`DEADLINE_US`] after the update (TIM2's compare 1), or
//!   at the latest by the next update: the streams are stopped;
//! - a chip select that reads low after its release (GPIO IDR).
//!
//! SPI1's overrun (SR's OVR, looked at once per frame end and cleared) fails
//! that encoder's sample alone, as a bus error; frames stopped by a fault or
//! the deadline leave SPI1's receiver drained (DR, then SR) for the next
//! period.
//!
//! Priorities: TIM2 and DMA2 stream 0 above the control interrupt, so the next
//! period's acquisition starts on time even behind a late step.

use core::cell::{Cell, RefCell, UnsafeCell};

use arm_app::{AcquisitionFault, EncoderAcquisition, EncoderFault};
use cortex_m::interrupt::{self, Mutex};
use drivers::as5047p::{As5047p, SampleSequence};
use stm32f4::stm32f405::{self as pac, Interrupt};

use super::{gpio, spi};
use crate::pins::{self, Pin};

/// The frames' deadline after TIM2's update, us: six frames of 16 bits at
/// 5.25 MHz take 18.3 us, plus an interrupt per frame (about 0.5 us each at
/// 168 MHz); 40 us leaves twice that, and is 40 % of the 100 us period at
/// 10 kHz, the fastest rate.
pub const DEADLINE_US: u32 = 40;

/// The interrupt the control step runs in: CAN2_TX's vector (CAN2 is unused on
/// this board), pended by software when the period's acquisition is over.
pub const CONTROL_INTERRUPT: Interrupt = Interrupt::CAN2_TX;

/// DMA2's streams and channel for SPI1 (RM0090 10.3.3 table 43).
pub const RX_STREAM: usize = 0;
/// SPI1_TX's stream.
pub const TX_STREAM: usize = 3;
/// SPI1's channel on both streams.
pub const CHANNEL: u32 = 3;

// SxCR bits (RM0090 10.5.5).
const EN: u32 = 1 << 0;
const DMEIE: u32 = 1 << 1;
const TEIE: u32 = 1 << 2;
const TCIE: u32 = 1 << 4;
const DIR_M2P: u32 = 0b01 << 6;
const MINC: u32 = 1 << 10;
const PSIZE_16: u32 = 0b01 << 11;
const MSIZE_16: u32 = 0b01 << 13;
const CHSEL: u32 = CHANNEL << 25;
// SxFCR (RM0090 10.5.10): direct mode (DMDIS = 0), FIFO error interrupt on.
const FEIE: u32 = 1 << 7;
// LISR / LIFCR bit offsets of a stream (RM0090 10.5.1): stream 0 at 0, stream 3 at 22.
const FEIF: u32 = 1 << 0;
const DMEIF: u32 = 1 << 2;
const TEIF: u32 = 1 << 3;
const TCIF: u32 = 1 << 5;
const ALL_FLAGS: u32 = 0b11_1101;
const RX_SHIFT: u32 = 0;
const TX_SHIFT: u32 = 22;

/// Cycles of chip select high between two frames to one chip: the AS5047P
/// needs 350 ns (tCSn), 59 cycles at 168 MHz; the interrupt's own path adds
/// more.
const CS_GAP_CYCLES: u32 = 32;

/// A finished acquisition: both encoders' samples and the load cell's counts.
/// Word-aligned: a copy is four word moves, not a call of `memcpy` for its
/// 14 bytes (issue 56).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(4))]
pub struct Acquired {
    /// `[theta1, elbow]`: the count or why there is none.
    pub encoders: [Result<u16, EncoderFault>; 2],
    /// The injected conversions `[f_t, f_n]`, `None` without JEOC.
    pub adc: Option<[u16; 2]>,
}

impl Acquired {
    const fn failed(fault: AcquisitionFault) -> Self {
        Self { encoders: [Err(EncoderFault::Acquisition(fault)); 2], adc: None }
    }
}

#[derive(Debug, Clone, Copy)]
struct InFlight {
    seqs: [SampleSequence; 2],
    /// The chip of the frame in flight (0 theta1, 1 elbow).
    current: usize,
}

/// The acquisition in flight, and the last one finished for the control.
static FLIGHT: Mutex<RefCell<Option<InFlight>>> = Mutex::new(RefCell::new(None));
static READY: Mutex<Cell<Option<Acquired>>> = Mutex::new(Cell::new(None));
/// What the control interrupt works on: written by [`publish`] at its start,
/// read by [`encoders`] and [`conversions_of_period`] during its step.
static CURRENT: ControlOnly = ControlOnly(UnsafeCell::new(Acquired::failed(AcquisitionFault::Timeout)));

/// The control interrupt's own copy of the period's acquisition. Only the
/// control interrupt touches it (`CONTROL_INTERRUPT`: one priority, it never
/// preempts itself; the acquisition's interrupts above it and the idle loop
/// below never touch it), so it is read without a critical section (issue 56:
/// the two reads a period had cost a critical section and a 14-byte copy each).
struct ControlOnly(UnsafeCell<Acquired>);

// SAFETY: accessed from the control interrupt only (see `ControlOnly`).
unsafe impl Sync for ControlOnly {}

/// The words DMA2 moves: a command out, an answer in (SRAM, never CCM: no DMA
/// reaches it, RM0090 2.3).
static mut TX_WORD: u16 = 0;
static mut RX_WORD: u16 = 0;

fn dma() -> &'static pac::dma2::RegisterBlock {
    // SAFETY: DMA2's streams 0 and 3 belong to this module, used from the
    // acquisition's interrupts (one priority) and start-up only.
    unsafe { &*pac::DMA2::ptr() }
}

const CS: [Pin; 2] = [pins::CS_THETA1, pins::CS_ELBOW];

/// Turns DMA2's clock on and lets SPI1 request it (RXDMAEN, TXDMAEN: RM0090
/// 28.3.9). The streams stay disabled until a frame.
pub fn init() {
    // SAFETY: RCC's AHB1ENR is only modified at start-up.
    let rcc = unsafe { &*pac::RCC::ptr() };
    rcc.ahb1enr().modify(|_, w| w.dma2en().set_bit());
    let _ = rcc.ahb1enr().read();
    spi::enable_dma_requests();
}

/// Whether frames are in flight (the blocking SPI device must then keep off the bus).
pub fn busy() -> bool {
    interrupt::free(|cs| FLIGHT.borrow(cs).borrow().is_some())
}

fn start_frame(chip: usize, command: u16) {
    let d = dma();
    // SAFETY: the words are only touched here and by DMA2 between EN and TCIF.
    unsafe {
        core::ptr::write_volatile(&raw mut TX_WORD, command);
    }
    // SAFETY (bits): flags of streams 0 and 3 only; addresses of SRAM words and SPI1's DR.
    unsafe {
        d.lifcr().write(|w| w.bits((ALL_FLAGS << RX_SHIFT) | (ALL_FLAGS << TX_SHIFT)));
        let dr = spi::data_register_address();
        let rx = d.st(RX_STREAM);
        rx.par().write(|w| w.bits(dr));
        rx.m0ar().write(|w| w.bits(&raw mut RX_WORD as u32));
        rx.ndtr().write(|w| w.bits(1));
        rx.fcr().write(|w| w.bits(FEIE));
        let tx = d.st(TX_STREAM);
        tx.par().write(|w| w.bits(dr));
        tx.m0ar().write(|w| w.bits(&raw const TX_WORD as u32));
        tx.ndtr().write(|w| w.bits(1));
        tx.fcr().write(|w| w.bits(0));
        gpio::write(&CS[chip], false);
        rx.cr().write(|w| w.bits(CHSEL | MSIZE_16 | PSIZE_16 | MINC | TCIE | TEIE | DMEIE | EN));
        tx.cr().write(|w| w.bits(CHSEL | MSIZE_16 | PSIZE_16 | MINC | DIR_M2P | EN));
    }
}

fn stop() {
    let d = dma();
    for s in [RX_STREAM, TX_STREAM] {
        d.st(s).cr().modify(|r, w| unsafe { w.bits(r.bits() & !EN) });
    }
    for c in &CS {
        gpio::write(c, true);
    }
    // A word left in DR (an overrun: SPI1 asks the RX stream for no word
    // while OVR is set) would overrun every period after.
    spi::drain();
}

/// The injected conversions, if this period's are there: one look at JEOC, no wait.
fn conversions() -> Option<[u16; 2]> {
    // SAFETY: ADC1's status and data are read here only once the tick started them.
    let a = unsafe { &*pac::ADC1::ptr() };
    if a.sr().read().jeoc().bit_is_clear() {
        return None;
    }
    let v = [a.jdr1().read().jdata().bits(), a.jdr2().read().jdata().bits()];
    a.sr().write(|w| w.jeoc().clear_bit().jstrt().clear_bit());
    Some(v)
}

fn finish(
    cs: &interrupt::CriticalSection,
    flight: &mut Option<InFlight>,
    encoders: Option<[Result<u16, EncoderFault>; 2]>,
    fault: Option<AcquisitionFault>,
) {
    *flight = None;
    let adc = conversions();
    let acquired = match (encoders, fault) {
        (Some(encoders), None) => Acquired { encoders, adc },
        (_, f) => Acquired { adc, ..Acquired::failed(f.unwrap_or(AcquisitionFault::Timeout)) },
    };
    READY.borrow(cs).set(Some(acquired));
    cortex_m::peripheral::NVIC::pend(CONTROL_INTERRUPT);
}

/// TIM2's update (the tick): a previous acquisition still in flight is over
/// ([`AcquisitionFault::Timeout`]); this period's first frame starts.
pub fn on_tick() {
    interrupt::free(|cs| {
        let mut flight = FLIGHT.borrow(cs).borrow_mut();
        if flight.is_some() {
            stop();
            finish(cs, &mut flight, None, Some(AcquisitionFault::Timeout));
        }
        let seqs = [SampleSequence::new(); 2];
        if let Some(c) = seqs[0].command() {
            *flight = Some(InFlight { seqs, current: 0 });
            start_frame(0, c);
        }
    });
}

/// TIM2's compare 1, [`DEADLINE_US`] after the update: frames still in flight
/// are stopped ([`AcquisitionFault::Timeout`], or the error flag a stream shows).
pub fn on_deadline() {
    interrupt::free(|cs| {
        let mut flight = FLIGHT.borrow(cs).borrow_mut();
        if flight.is_some() {
            let fault = error_of(dma().lisr().read().bits()).unwrap_or(AcquisitionFault::Timeout);
            stop();
            finish(cs, &mut flight, None, Some(fault));
        }
    });
}

/// The first error flag of streams 0 and 3 in `lisr`, by name.
fn error_of(lisr: u32) -> Option<AcquisitionFault> {
    let both = (lisr >> RX_SHIFT) | (lisr >> TX_SHIFT);
    if both & TEIF != 0 {
        Some(AcquisitionFault::TransferError)
    } else if both & DMEIF != 0 {
        Some(AcquisitionFault::DirectModeError)
    } else if both & FEIF != 0 {
        Some(AcquisitionFault::FifoError)
    } else {
        None
    }
}

/// DMA2 stream 0's interrupt: a frame is over (TCIF) or a stream failed.
pub fn on_rx_stream() {
    interrupt::free(|cs| {
        let d = dma();
        let lisr = d.lisr().read().bits();
        // SAFETY (bits): flags of streams 0 and 3 only.
        d.lifcr().write(|w| unsafe { w.bits((ALL_FLAGS << RX_SHIFT) | (ALL_FLAGS << TX_SHIFT)) });
        let mut flight = FLIGHT.borrow(cs).borrow_mut();
        let Some(f) = flight.as_mut() else { return };
        if let Some(fault) = error_of(lisr) {
            stop();
            finish(cs, &mut flight, None, Some(fault));
            return;
        }
        if (lisr >> RX_SHIFT) & TCIF == 0 {
            return;
        }
        let chip = f.current;
        gpio::write(&CS[chip], true);
        if !gpio::read(&CS[chip]) {
            stop();
            finish(cs, &mut flight, None, Some(AcquisitionFault::StuckChipSelect));
            return;
        }
        // SAFETY: DMA2 wrote the word before TCIF.
        let answer = unsafe { core::ptr::read_volatile(&raw const RX_WORD) };
        if spi::take_overrun() {
            // The word is not this frame's (RM0090 28.4.8): that encoder's
            // sample fails as a bus error, as the blocking driver's does.
            f.seqs[chip].transfer_failed();
        } else {
            f.seqs[chip].answer(answer);
        }
        if let Some(c) = f.seqs[chip].command() {
            cortex_m::asm::delay(CS_GAP_CYCLES);
            start_frame(chip, c);
        } else if let Some(c) = f.seqs.get(chip + 1).and_then(SampleSequence::command) {
            f.current = chip + 1;
            start_frame(chip + 1, c);
        } else {
            let out = f.seqs.map(|s| match s.outcome() {
                Some(r) => r.map_err(|e| EncoderFault::of(&e)),
                None => Err(EncoderFault::Acquisition(AcquisitionFault::Timeout)),
            });
            finish(cs, &mut flight, Some(out), None);
        }
    });
}

/// At the control interrupt's start, and from there only: the finished
/// acquisition becomes the period's (none finished: [`AcquisitionFault::Timeout`]).
pub fn publish() {
    let a = interrupt::free(|cs| READY.borrow(cs).take()).unwrap_or(Acquired::failed(AcquisitionFault::Timeout));
    // SAFETY: the control interrupt is CURRENT's only user (`ControlOnly`).
    unsafe { *CURRENT.0.get() = a };
}

/// The period's encoder samples as [`publish`] left them (from the control
/// interrupt only).
pub fn encoders() -> [Result<u16, EncoderFault>; 2] {
    // SAFETY: the control interrupt is CURRENT's only user (`ControlOnly`).
    unsafe { (*CURRENT.0.get()).encoders }
}

/// The period's injected conversions `[f_t, f_n]` as [`publish`] left them
/// (`None`: not done by the frames' end), from the control interrupt only.
pub fn conversions_of_period() -> Option<[u16; 2]> {
    // SAFETY: the control interrupt is CURRENT's only user (`ControlOnly`).
    unsafe { (*CURRENT.0.get()).adc }
}

/// The encoders as the control interrupt finds them: in memory.
#[derive(Debug, Default)]
pub struct DmaEncoders;

impl EncoderAcquisition<spi::Spi1Device> for DmaEncoders {
    fn acquire(&mut self, _theta1: &mut As5047p<spi::Spi1Device>, _elbow: &mut As5047p<spi::Spi1Device>) -> [Result<u16, EncoderFault>; 2] {
        encoders()
    }
}
