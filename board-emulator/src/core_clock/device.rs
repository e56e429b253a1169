//! The wrapped core as rsemu's `Instance` and `Device`: every method passed
//! through to rsemu's `ArmV7m` but `run` (the modes of `run.rs`) and `sink`,
//! which watches the reset input.

use std::sync::{Arc, Weak};

use rsemu::{
    core::{
        SpinDetector,
        clock::ClockControl,
        device::{DebugTranslation, Deferred, Device, DeviceClass, Export, ExportId, RealizeCtx, ResetKind, SinkPin},
        error::Result,
        sched::{Budget, Consumed, LazyHandle, TickCursor},
        space::RegionRef,
        state::{ChunkReader, ChunkWriter},
        wire::{DmaPeripheral, IntAck, LocalController, WireId, WireSource},
    },
    machine::{BindCtx, Instance},
};

use super::{Core, Mode, ResetWatch, lock};

impl Instance for Core {
    fn bind(&self, ctx: &BindCtx<'_>) -> Result<()> {
        Instance::bind(&*self.cpu, ctx)
    }
}

impl Device for Core {
    fn run(&self, budget: Budget) -> Consumed {
        Consumed::new(match self.mode {
            Mode::Functional => self.run_functional(budget.ticks),
            Mode::Counted => self.run_counted(budget.ticks),
        })
    }
    fn attach_cursor(&self, c: TickCursor) {
        *lock(&self.cursor) = Some(c.clone());
        Device::attach_cursor(&*self.cpu, c);
    }
    fn class(&self) -> &'static DeviceClass {
        Device::class(&*self.cpu)
    }
    fn realize(&self, ctx: &mut RealizeCtx<'_>) -> Result<()> {
        Device::realize(&*self.cpu, ctx)
    }
    fn unrealize(&self, ctx: &mut RealizeCtx<'_>) -> Result<()> {
        Device::unrealize(&*self.cpu, ctx)
    }
    fn reset(&self, kind: ResetKind) {
        Device::reset(&*self.cpu, kind);
        if kind == ResetKind::Warm {
            self.system_reset();
        }
    }
    fn debug_halt(&self, h: bool) {
        Device::debug_halt(&*self.cpu, h);
    }
    fn flush(&self) -> Result<()> {
        Device::flush(&*self.cpu)
    }
    fn save(&self, w: &mut ChunkWriter<'_>) -> Result<()> {
        Device::save(&*self.cpu, w)
    }
    fn load(&self, r: &mut ChunkReader<'_>) -> Result<()> {
        Device::load(&*self.cpu, r)
    }
    fn region(&self, name: &str) -> Option<RegionRef> {
        Device::region(&*self.cpu, name)
    }
    fn set_spin_detector(&self, cpu: u32, d: Option<Arc<SpinDetector>>) -> bool {
        Device::set_spin_detector(&*self.cpu, cpu, d)
    }
    fn sink(&self, port: &str, sources: &[WireId]) -> Option<SinkPin> {
        let pin = Device::sink(&*self.cpu, port, sources)?;
        if port != "reset" {
            return Some(pin);
        }
        let watch = Arc::new(ResetWatch { inner: pin.sink, seen: Arc::clone(&self.reset_seen) });
        *lock(&self.reset_watch) = Some(Arc::clone(&watch));
        Some(SinkPin { sink: watch, line: pin.line })
    }
    fn export(&self, which: ExportId) -> Option<Export> {
        Device::export(&*self.cpu, which)
    }
    fn connect(&self, port: &str, source: WireSource) -> Result<()> {
        Device::connect(&*self.cpu, port, source)
    }
    fn int_ack(&self, port: &str) -> Option<Arc<dyn IntAck>> {
        Device::int_ack(&*self.cpu, port)
    }
    fn attach_int_ack(&self, port: &str, ack: Weak<dyn IntAck>) {
        Device::attach_int_ack(&*self.cpu, port, ack);
    }
    fn dma_peripheral(&self, port: &str) -> Option<Arc<dyn DmaPeripheral>> {
        Device::dma_peripheral(&*self.cpu, port)
    }
    fn attach_dma_peripheral(&self, port: &str, p: Weak<dyn DmaPeripheral>) {
        Device::attach_dma_peripheral(&*self.cpu, port, p);
    }
    fn local_controller(&self, port: &str) -> Option<Arc<dyn LocalController>> {
        Device::local_controller(&*self.cpu, port)
    }
    fn attach_local_controller(&self, port: &str, p: Weak<dyn LocalController>) {
        Device::attach_local_controller(&*self.cpu, port, p);
    }
    fn announce(&self, port: &str) {
        Device::announce(&*self.cpu, port);
    }
    fn debug_translate(&self, va: u64) -> DebugTranslation {
        Device::debug_translate(&*self.cpu, va)
    }
    fn combinational(&self) -> bool {
        Device::combinational(&*self.cpu)
    }
    fn is_runnable(&self) -> bool {
        Device::is_runnable(&*self.cpu)
    }
    fn event(&self, token: u64, d: &mut Deferred) {
        Device::event(&*self.cpu, token, d);
    }
    fn is_lazy(&self) -> bool {
        Device::is_lazy(&*self.cpu)
    }
    fn current_tick(&self) -> u64 {
        Device::current_tick(&*self.cpu)
    }
    fn advance_to(&self, tick: u64) {
        Device::advance_to(&*self.cpu, tick);
    }
    fn next_event_tick(&self) -> Option<u64> {
        Device::next_event_tick(&*self.cpu)
    }
    fn sampled_every_cycle(&self) -> bool {
        Device::sampled_every_cycle(&*self.cpu)
    }
    fn attach_lazy(&self, h: LazyHandle) {
        Device::attach_lazy(&*self.cpu, h);
    }
    fn attach_clock_control(&self, c: Arc<ClockControl>) {
        Device::attach_clock_control(&*self.cpu, c);
    }
}
