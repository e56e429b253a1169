//! Narrow writes for rsemu's register windows that take only 32-bit ones: the
//! STM32F4's APB peripherals take 8- and 16-bit accesses (the halfword reaches
//! the register zero-extended), and the image writes `IWDG_KR` with a `STRH`;
//! rsemu 0.0.7's `st.iwdg` answers anything but a word with a bus fault
//! (`dev/stm32/iwdg.rs`). The same wrapper checks the flash interface's
//! programming sequence ([`check_flash_class`], [`crate::flash_sequence`]).
//! [`widen_class`] replaces a class's constructor with
//! one that wraps its instances, every `Device` method passed through but the
//! register window's width. To be raised upstream.
use std::sync::{Arc, Weak};

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
