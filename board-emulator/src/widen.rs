//! Narrow writes for rsemu's register windows that take only 32-bit ones: the
//! STM32F4's APB peripherals take 8- and 16-bit accesses (the halfword reaches
//! the register zero-extended), and the image writes `IWDG_KR` with a `STRH`;
//! rsemu 0.0.7's `st.iwdg` answers anything but a word with a bus fault
//! (`dev/stm32/iwdg.rs`). The same wrapper checks the flash interface's
//! programming sequence ([`check_flash_class`], [`crate::flash_sequence`]), and
//! makes the board's chip-select faults in GPIOA's and GPIOB's `IDR`
//! ([`stuck_low_class`], [`StuckLow`]).
//! [`widen_class`] replaces a class's constructor with
//! one that wraps its instances, every `Device` method passed through but the
//! register window's width. To be raised upstream.
use std::sync::{
    Arc, Weak,
    atomic::{AtomicU32, Ordering},
};

use rsemu::core::SpinDetector;
use rsemu::core::clock::ClockControl;
use rsemu::core::device::{DebugTranslation, Deferred, Device, DeviceClass, Export, ExportId, RealizeCtx, ResetKind, SinkPin};
use rsemu::core::error::Result;
use rsemu::core::sched::{Budget, Consumed, LazyHandle, TickCursor};
use rsemu::core::space::{AccessConstraints, MemAttrs, MemOps, MemResult, Region, RegionKind, RegionRef};
use rsemu::core::state::{ChunkReader, ChunkWriter};
use rsemu::core::value::{Endian, Width};
use rsemu::core::wire::{DmaPeripheral, IntAck, LocalController, WireId, WireSource};
use rsemu::machine::{BindCtx, Bindings, Instance};

use crate::{device::ErrorLog, flash_sequence::FlashSequence};

#[derive(Debug)]
struct WidenOps(Arc<dyn MemOps>);
impl MemOps for WidenOps {
    fn read(&self, offset: u64, dst: &mut [u8], attrs: MemAttrs) -> MemResult {
        let base = offset & !3;
        let mut w = [0u8; 4];
        self.0.read(base, &mut w, attrs)?;
        let s = (offset - base) as usize;
        dst.copy_from_slice(&w[s..s + dst.len()]);
        Ok(())
    }
    fn write(&self, offset: u64, src: &[u8], attrs: MemAttrs) -> MemResult {
        if src.len() == 4 {
            return self.0.write(offset, src, attrs);
        }
        // APB: a narrow write reaches the register zero-extended (no RMW on the
        // bus); that is what IWDG_KR/USART_BRR see on silicon.
        let base = offset & !3;
        let mut w = [0u8; 4];
        let s = (offset - base) as usize;
        w[s..s + src.len()].copy_from_slice(src);
        self.0.write(base, &w, attrs)
    }
    fn constraints(&self) -> AccessConstraints {
        AccessConstraints::word(Width::U32, Endian::Little).with_widths(Width::U8, Width::U32)
    }
}

/// What a wrapper does to an instance's register windows.
#[derive(Debug, Clone)]
pub enum Windows {
    /// Passed through.
    Unchanged,
    /// Narrow writes taken ([`WidenOps`]).
    Narrow,
    /// The flash interface's sequence checked ([`crate::flash_sequence`]).
    FlashSequence(ErrorLog),
    /// A GPIO port's `IDR` with the pins of the mask read low ([`StuckLow`]).
    StuckLow(Arc<AtomicU32>),
}

/// GPIO pins that read low in `IDR` whatever the port drives (issue 66: a chip
/// select stuck low after its release, seen by the image's read-back in DMA2
/// stream 0's interrupt, docs/board.md "The encoders by DMA"). Only the read-back
/// changes: the pin's output, which the SPI1 model's chip-select inputs follow,
/// is the port's own (rsemu's `st.gpio` reads back what it drives, so a fault on
/// the net cannot show there). One bit a pin; the host sets them before a tick.
#[derive(Debug, Clone, Default)]
pub struct StuckLow {
    /// GPIOA's pins that read low.
    pub gpioa: Arc<AtomicU32>,
    /// GPIOB's pins that read low.
    pub gpiob: Arc<AtomicU32>,
    /// The ports wrapped when the machine was built (bit 0 GPIOA, bit 1 GPIOB).
    wrapped: Arc<AtomicU32>,
}

impl StuckLow {
    /// Sets the pins that read low: `gpioa` and `gpiob`, one bit a pin.
    pub fn set(&self, gpioa: u32, gpiob: u32) {
        self.gpioa.store(gpioa, Ordering::Relaxed);
        self.gpiob.store(gpiob, Ordering::Relaxed);
    }

    /// Whether both GPIOA and GPIOB were wrapped ([`stuck_low_class`]) when the
    /// machine was built.
    pub fn wraps_both_ports(&self) -> bool {
        self.wrapped.load(Ordering::Relaxed) == 0b11
    }
}

/// `GPIOx_IDR`'s offset in a port's window (RM0090 8.4.5).
const GPIO_IDR: u64 = 0x10;
/// `GPIOx_MODER`'s reset values of GPIOA and GPIOB (RM0090 8.4.1, the debug
/// pins), the `moder-reset` property rsemu's STM32F407 description gives
/// those two ports and no other: how a port's instance is told apart here.
const MODER_RESET: [u64; 2] = [0xA800_0000, 0x0000_0280];

#[derive(Debug)]
struct StuckLowOps(Arc<dyn MemOps>, Arc<AtomicU32>);
impl MemOps for StuckLowOps {
    fn read(&self, offset: u64, dst: &mut [u8], attrs: MemAttrs) -> MemResult {
        self.0.read(offset, dst, attrs)?;
        let mask = self.1.load(Ordering::Relaxed);
        for (i, b) in dst.iter_mut().enumerate() {
            let at = offset + i as u64;
            if (GPIO_IDR..GPIO_IDR + 4).contains(&at) {
                *b &= !((mask >> (8 * (at - GPIO_IDR))) as u8);
            }
        }
        Ok(())
    }
    fn write(&self, offset: u64, src: &[u8], attrs: MemAttrs) -> MemResult {
        self.0.write(offset, src, attrs)
    }
    fn constraints(&self) -> AccessConstraints {
        self.0.constraints()
    }
}

/// An rsemu instance passed through, its register windows as `.1` says,
/// runnable or not (`.2`).
#[derive(Debug)]
pub struct Widen(pub Arc<dyn Instance>, pub Windows, pub bool);

/// Wraps every instance of `class` in [`Widen`] (nothing when the class is not bound).
pub fn widen_class(b: &mut Bindings, class: &'static str) {
    let Some(inner) = b.get(class) else { return };
    b.replace(class, move |props| Ok(Arc::new(Widen(inner(props)?, Windows::Narrow, true)) as Arc<dyn Instance>));
}

/// Wraps every instance of `class` (`st.flash`) so that its register window
/// checks the programming sequence, reporting into `errors`.
pub fn check_flash_class(b: &mut Bindings, class: &'static str, errors: ErrorLog) {
    let Some(inner) = b.get(class) else { return };
    b.replace(class, move |props| Ok(Arc::new(Widen(inner(props)?, Windows::FlashSequence(errors.clone()), true)) as Arc<dyn Instance>));
}

/// Wraps GPIOA's and GPIOB's instances of `class` (`st.gpio`) so that the pins
/// `stuck` names read low in their `IDR`; the other ports are left as they are.
pub fn stuck_low_class(b: &mut Bindings, class: &'static str, stuck: StuckLow) {
    let Some(inner) = b.get(class) else { return };
    b.replace(class, move |props| {
        let port = props.get("moder-reset").and_then(rsemu::core::props::Value::as_uint);
        let instance = inner(props)?;
        let Some(i) = MODER_RESET.iter().position(|r| port == Some(*r)) else { return Ok(instance) };
        stuck.wrapped.fetch_or(1 << i, Ordering::Relaxed);
        let mask = if i == 0 { stuck.gpioa.clone() } else { stuck.gpiob.clone() };
        Ok(Arc::new(Widen(instance, Windows::StuckLow(mask), true)) as Arc<dyn Instance>)
    });
}

/// Binds every instance of `class` as not runnable (a lazily advanced device
/// only), its windows unchanged: for the DMA controllers, which the image never
/// enables, so that the core is its crystal's one runnable and rsemu arms live
/// positions.
pub fn not_runnable_class(b: &mut Bindings, class: &'static str) {
    let Some(inner) = b.get(class) else { return };
    b.replace(class, move |props| Ok(Arc::new(Widen(inner(props)?, Windows::Unchanged, false)) as Arc<dyn Instance>));
}

impl Instance for Widen {
    fn bind(&self, ctx: &BindCtx<'_>) -> Result<()> {
        self.0.bind(ctx)
    }
}
impl Device for Widen {
    fn class(&self) -> &'static DeviceClass {
        self.0.class()
    }
    fn realize(&self, ctx: &mut RealizeCtx<'_>) -> Result<()> {
        self.0.realize(ctx)
    }
    fn unrealize(&self, ctx: &mut RealizeCtx<'_>) -> Result<()> {
        self.0.unrealize(ctx)
    }
    fn reset(&self, kind: ResetKind) {
        self.0.reset(kind)
    }
    fn debug_halt(&self, h: bool) {
        self.0.debug_halt(h)
    }
    fn flush(&self) -> Result<()> {
        self.0.flush()
    }
    fn save(&self, w: &mut ChunkWriter<'_>) -> Result<()> {
        self.0.save(w)
    }
    fn load(&self, r: &mut ChunkReader<'_>) -> Result<()> {
        self.0.load(r)
    }
    fn region(&self, name: &str) -> Option<RegionRef> {
        let r = self.0.region(name)?;
        let ops: Arc<dyn MemOps> = match (&self.1, r.kind()) {
            (Windows::Narrow, RegionKind::Io(ops)) => Arc::new(WidenOps(Arc::clone(ops))),
            (Windows::FlashSequence(errors), RegionKind::Io(ops)) if matches!(name, "" | "regs") => {
                Arc::new(FlashSequence::new(Arc::clone(ops), errors.clone()))
            }
            (Windows::StuckLow(mask), RegionKind::Io(ops)) if matches!(name, "" | "regs") => {
                Arc::new(StuckLowOps(Arc::clone(ops), Arc::clone(mask)))
            }
            _ => return Some(r),
        };
        Some(Arc::new(Region::io(r.name().to_string(), r.len(), ops)))
    }
    fn set_spin_detector(&self, cpu: u32, d: Option<Arc<SpinDetector>>) -> bool {
        self.0.set_spin_detector(cpu, d)
    }
    fn sink(&self, port: &str, sources: &[WireId]) -> Option<SinkPin> {
        self.0.sink(port, sources)
    }
    fn export(&self, which: ExportId) -> Option<Export> {
        self.0.export(which)
    }
    fn connect(&self, port: &str, source: WireSource) -> Result<()> {
        self.0.connect(port, source)
    }
    fn int_ack(&self, port: &str) -> Option<Arc<dyn IntAck>> {
        self.0.int_ack(port)
    }
    fn attach_int_ack(&self, port: &str, ack: Weak<dyn IntAck>) {
        self.0.attach_int_ack(port, ack)
    }
    fn dma_peripheral(&self, port: &str) -> Option<Arc<dyn DmaPeripheral>> {
        self.0.dma_peripheral(port)
    }
    fn attach_dma_peripheral(&self, port: &str, p: Weak<dyn DmaPeripheral>) {
        self.0.attach_dma_peripheral(port, p)
    }
    fn local_controller(&self, port: &str) -> Option<Arc<dyn LocalController>> {
        self.0.local_controller(port)
    }
    fn attach_local_controller(&self, port: &str, p: Weak<dyn LocalController>) {
        self.0.attach_local_controller(port, p)
    }
    fn announce(&self, port: &str) {
        self.0.announce(port)
    }
    fn debug_translate(&self, va: u64) -> DebugTranslation {
        self.0.debug_translate(va)
    }
    fn combinational(&self) -> bool {
        self.0.combinational()
    }
    fn is_runnable(&self) -> bool {
        self.2 && self.0.is_runnable()
    }
    fn run(&self, budget: Budget) -> Consumed {
        self.0.run(budget)
    }
    fn attach_cursor(&self, c: TickCursor) {
        self.0.attach_cursor(c)
    }
    fn event(&self, token: u64, d: &mut Deferred) {
        self.0.event(token, d)
    }
    fn is_lazy(&self) -> bool {
        self.0.is_lazy()
    }
    fn current_tick(&self) -> u64 {
        self.0.current_tick()
    }
    fn advance_to(&self, tick: u64) {
        self.0.advance_to(tick)
    }
    fn next_event_tick(&self) -> Option<u64> {
        self.0.next_event_tick()
    }
    fn sampled_every_cycle(&self) -> bool {
        self.0.sampled_every_cycle()
    }
    fn attach_lazy(&self, h: LazyHandle) {
        self.0.attach_lazy(h)
    }
    fn attach_clock_control(&self, c: Arc<ClockControl>) {
        self.0.attach_clock_control(c)
    }
}
