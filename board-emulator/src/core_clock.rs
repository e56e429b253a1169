//! The Cortex-M4F core, wrapped: rsemu's `ArmV7m` bound in place of the stock
//! `cpu.arm.v7m` constructor, every `Device` method passed through but `run`.
//!
//! - **A sleeping core skips to the next event.** rsemu charges a core asleep
//!   in WFI one step per cycle (`cpu/arm/v7m/exec.rs`, the `asleep` branch of
//!   `Exec::step`): 164 000 steps of a 168 000-cycle period for this image.
//!   When the core sleeps, owes no cycles, and no exception is pending or
//!   could pend (every asserted interrupt line is folded in as `Exec::step`
//!   folds it), `run` charges the budget at once and advances DWT `CYCCNT` and
//!   SysTick as the steps would have, one cycle at a time; SysTick with its
//!   interrupt enabled stops the skip where it would wrap. The image sees the
//!   same cycles (its tick interval reads 168 000 cycles per 1 ms period).
//! - **Host edges at exact core positions** ([`Mode::Functional`]): the belt
//!   encoder's quadrature edges ([`crate::belt`]) are queued at core ticks and
//!   driven from inside `run`, with the scheduler's cursor set to the edge's
//!   position so that TIM4 (a lazily advanced device) sees each at its instant
//!   and its input filter settles between them. This needs the machine's
//!   live positions, which rsemu arms only when the core is the crystal's one
//!   runnable: the DMA controllers are bound as not runnable
//!   ([`crate::machine`]; the image never enables DMA, which the board checks).
//! - **The tick handler's instructions** ([`Mode::Counted`]): the awake core is
//!   stepped one budget tick at a time (`run_budget(1)` steps an instruction
//!   exactly when the core owes no cycle), counting the instructions executed
//!   in TIM2's handler (exception 44), its cycles, and the latency from TIM2's
//!   interrupt line rising to the handler's first instruction. Later calls of
//!   one `run` publish the core's position early (rsemu anchors each call at
//!   the round's start), which only an unchanging machine without live
//!   positions tolerates: the counted mode keeps rsemu's runnable DMA (no live
//!   positions) and drives the belt between rounds instead.

use std::{
    collections::VecDeque,
    sync::{
        Arc, Mutex, MutexGuard, PoisonError, Weak,
        atomic::{AtomicU64, Ordering::Relaxed},
    },
};

use rsemu::{
    core::{
        SpinDetector,
        clock::ClockControl,
        device::{DebugTranslation, Deferred, Device, DeviceClass, Export, ExportId, RealizeCtx, ResetKind, SinkPin},
        error::Result,
        sched::{Budget, Consumed, LazyHandle, TickCursor},
        space::RegionRef,
        state::{ChunkReader, ChunkWriter},
        wire::{DmaPeripheral, IntAck, LocalController, WireId, WireSink, WireSource},
    },
    cpu::arm::v7m::{ArmV7m, sys::Exception},
    machine::{BindCtx, Bindings, Instance},
};

use crate::{
    accelerator::{Accelerator, Acr, FLASH},
    device::PinsDevice,
    flash_reads,
};

/// External interrupt inputs folded in (the STM32F405 has 82; three words).
const IRQS: u16 = 96;
/// TIM2's interrupt line and exception number.
pub const TIM2_IRQ: u16 = 28;
const TIM2_EXCEPTION: u16 = 16 + TIM2_IRQ;

/// How the core is run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Fast and exact: sleep skipped, the belt's edges driven at core positions.
    Functional,
    /// Every instruction of TIM2's handler counted (slower; no live positions).
    Counted,
}

/// A host edge: drive the pins device's output `line` to `high` at core tick `at`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// The core tick (the core clock's count since power-up).
    pub at: u64,
    /// The pins device's output line.
    pub line: usize,
    /// The level.
    pub high: bool,
}

/// One execution of TIM2's handler ([`Mode::Counted`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HandlerRun {
    /// Core cycles from TIM2's interrupt line rising to the handler's first instruction.
    pub latency_cycles: u64,
    /// Instructions executed in the handler (preempting handlers excluded).
    pub instructions: u64,
    /// Core cycles from the first instruction to the end of the return (rsemu's
    /// cost model: the Cortex-M4 TRM's figures with flash at zero wait states).
    pub cycles: u64,
    /// The cycles the flash's wait states add behind the ART accelerator
    /// ([`crate::accelerator`]; 0 until [`Core::set_accelerator`]).
    pub wait_cycles: u64,
    /// The core tick of its first instruction.
    pub started_at: u64,
}

#[derive(Debug, Default)]
struct Track {
    tick: u64,
    irq_seen: Option<u64>,
    first: Option<u64>,
    instructions: u64,
    wait: u64,
    accel: Option<Accel>,
}

/// The accelerator model and the code it decodes.
#[derive(Debug)]
struct Accel {
    art: Accelerator,
    code: Arc<[u8]>,
    reads: Vec<u32>,
}

/// The wrapped core.
#[derive(Debug)]
pub struct Core {
    /// rsemu's core (registers, counters, faults).
    pub cpu: Arc<ArmV7m>,
    mode: Mode,
    cursor: Mutex<Option<TickCursor>>,
    edges: Mutex<VecDeque<Edge>>,
    pins: Mutex<Option<Arc<PinsDevice>>>,
    /// The core's tick when its last `run` ended.
    end_tick: AtomicU64,
    /// Edges driven after their tick (the core owed cycles there).
    pub late_edges: AtomicU64,
    track: Mutex<Track>,
    handlers: Mutex<Vec<HandlerRun>>,
    /// A reset arrived on the core's reset input (the IWDG's, NRST): the core
    /// must step to take it (rsemu latches it where only a step sees it).
    reset_seen: Arc<std::sync::atomic::AtomicBool>,
    /// The watch on the reset input, held here: a net holds its sinks weakly.
    reset_watch: Mutex<Option<Arc<ResetWatch>>>,
}

/// The core's reset input, watched: forwards the level, notes a rise.
struct ResetWatch {
    inner: Arc<dyn WireSink>,
    seen: Arc<std::sync::atomic::AtomicBool>,
}

impl std::fmt::Debug for ResetWatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ResetWatch")
    }
}

impl WireSink for ResetWatch {
    fn set_level(&self, src: WireId, line: u32, level: rsemu::core::wire::Level) {
        if level.is_high() {
            self.seen.store(true, Relaxed);
        }
        self.inner.set_level(src, line, level);
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Binds the wrapped core in place of `cpu.arm.v7m`; the slot receives it at the build.
pub fn bind(b: &mut Bindings, mode: Mode) -> Arc<Mutex<Option<Arc<Core>>>> {
    let slot: Arc<Mutex<Option<Arc<Core>>>> = Arc::default();
    let s = Arc::clone(&slot);
    b.replace("cpu.arm.v7m", move |props| {
        let core = Arc::new(Core {
            cpu: Arc::new(ArmV7m::from_props(props)?),
            mode,
            cursor: Mutex::new(None),
            edges: Mutex::new(VecDeque::new()),
            pins: Mutex::new(None),
            end_tick: AtomicU64::new(0),
            late_edges: AtomicU64::new(0),
            track: Mutex::default(),
            handlers: Mutex::default(),
            reset_seen: Arc::default(),
            reset_watch: Mutex::new(None),
        });
        *lock(&s) = Some(Arc::clone(&core));
        Ok(core as Arc<dyn Instance>)
    });
    slot
}

impl Core {
    /// The mode it runs in.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The core's tick when its last `run` ended (where the machine stands).
    pub fn end_tick(&self) -> u64 {
        self.end_tick.load(Relaxed)
    }

    /// Queues `edges` (ascending ticks) on the pins device `pins` ([`Mode::Functional`]).
    pub fn queue_edges(&self, pins: &Arc<PinsDevice>, edges: impl IntoIterator<Item = Edge>) {
        *lock(&self.pins) = Some(Arc::clone(pins));
        lock(&self.edges).extend(edges);
    }

    /// Edges queued and not yet driven.
    pub fn pending_edges(&self) -> usize {
        lock(&self.edges).len()
    }

    /// Costs the flash's wait states from now on ([`Mode::Counted`]): a cold
    /// accelerator configured by `acr` (`FLASH_ACR`), `code` the flash's
    /// content from its base. Called at each boot (a reset clears the caches).
    pub fn set_accelerator(&self, acr: Acr, code: Arc<[u8]>) {
        lock(&self.track).accel = Some(Accel { art: Accelerator::new(acr), code, reads: Vec::new() });
    }

    /// The handler runs counted since the last call ([`Mode::Counted`]).
    pub fn take_handlers(&self) -> Vec<HandlerRun> {
        std::mem::take(&mut lock(&self.handlers))
    }

    /// Ticks of `ticks` that may be charged without a step (0: the core must
    /// step): the core sleeps, owes nothing, nothing is pending or could pend.
    fn sleepable(&self, ticks: u64) -> u64 {
        let c = &*self.cpu;
        if self.reset_seen.swap(false, Relaxed) {
            // The next step takes the reset.
            return 0;
        }
        if !c.is_asleep() || c.cycle_debt() != 0 || c.reset_pending() || c.is_locked_up() || c.nmi_asserted() {
            return 0;
        }
        c.with_sys(|s| {
            // As Exec::step's merge_external: an asserted line pends unless
            // active. Only enabled lines can wake the core; a disabled line's
            // pending bit is folded in by the next step, which nothing reads
            // before (the image reads no NVIC pending bits).
            for irq in 0..IRQS {
                let e = Exception(irq + 16);
                if s.is_enabled(e) && c.irq_asserted(irq) && !s.is_active(e) {
                    s.set_pending(e, true);
                }
            }
            if s.highest_pending().is_some() {
                return 0;
            }
            let mut n = ticks;
            if s.syst_csr & 0b11 == 0b11 && s.syst_rvr & 0xFF_FFFF != 0 {
                let current = u64::from(s.syst_cvr & 0xFF_FFFF);
                if current == 0 {
                    return 0;
                }
                n = n.min(current);
            }
            s.tick_cyccnt(n);
            if s.tick_systick(n) && s.syst_csr & 0b10 != 0 {
                s.set_pending(Exception::SYSTICK, true);
            }
            n
        })
    }

    fn run_functional(&self, ticks: u64) -> u64 {
        let c = &*self.cpu;
        let cursor = lock(&self.cursor).clone();
        let anchor = cursor.as_ref().map_or(0, TickCursor::anchor);
        let mut edges = lock(&self.edges);
        let pins = lock(&self.pins).clone();
        let mut used = 0;
        let mut calls = 0u64;
        while used < ticks {
            let mut rest = ticks - used;
            // A host edge where the core owes nothing: its position is then
            // exactly anchor + used.
            if let (Some(e), Some(cur), Some(pins)) = (edges.front().copied(), cursor.as_ref(), pins.as_ref())
                && c.cycle_debt() == 0
            {
                let pos = anchor + used;
                if e.at <= pos {
                    if e.at < pos {
                        self.late_edges.fetch_add(1, Relaxed);
                    }
                    edges.pop_front();
                    cur.set(pos);
                    pins.drive(e.line, e.high);
                    continue;
                }
                if c.is_asleep() {
                    rest = rest.min(e.at - pos);
                }
            }
            // A sleeping core's debt is paid without a step.
            let d = if c.is_asleep() { c.cycle_debt().min(rest) } else { 0 };
            if d > 0 {
                used += c.run_budget(d);
                continue;
            }
            let n = self.sleepable(rest);
            if n > 0 {
                used += n;
                continue;
            }
            // Awake: only the first run_budget call of a run publishes exact
            // positions; a later one runs a short chunk.
            let chunk = if calls == 0 { rest } else { rest.min(64) };
            let r = c.run_budget(chunk);
            calls += 1;
            used += r;
            if r < chunk {
                break;
            }
        }
        self.end_tick.store(anchor + used, Relaxed);
        used
    }

    fn run_counted(&self, ticks: u64) -> u64 {
        let c = &*self.cpu;
        let anchor = lock(&self.cursor).as_ref().map_or(0, TickCursor::anchor);
        let mut tr = lock(&self.track);
        let mut used = 0;
        while used < ticks {
            let n = self.sleepable(ticks - used);
            if n > 0 {
                used += n;
                tr.tick += n;
                continue;
            }
            if tr.irq_seen.is_none() && c.irq_asserted(TIM2_IRQ) {
                tr.irq_seen = Some(tr.tick);
            }
            let debt = c.cycle_debt();
            let before = c.current_exception().0;
            let now = tr.tick;
            let stall = match (debt, tr.accel.as_mut()) {
                (0, Some(a)) => {
                    let r = c.regs().r;
                    let pc = r[15];
                    match flash_reads::instruction_at(&a.code, FLASH.start, pc) {
                        Some((width, insn)) => {
                            a.reads.clear();
                            flash_reads::data_reads(&insn, pc, &r, &mut a.reads);
                            a.art.instruction(pc, width, &a.reads, now)
                        }
                        None => 0,
                    }
                }
                _ => 0,
            };
            let n = c.run_budget(1);
            if n == 0 {
                break;
            }
            if debt == 0 && before == TIM2_EXCEPTION {
                tr.instructions += 1;
                tr.wait += stall;
                let tick = tr.tick;
                let start = *tr.first.get_or_insert(tick);
                if !c.with_sys(|s| s.is_active(Exception(TIM2_EXCEPTION))) {
                    // Returned (a preempting handler leaves TIM2 active).
                    let end = tr.tick + 1 + c.cycle_debt();
                    let latency = tr.irq_seen.take().map_or(0, |s| start.saturating_sub(s));
                    let run = HandlerRun {
                        latency_cycles: latency,
                        instructions: std::mem::take(&mut tr.instructions),
                        cycles: end - start,
                        wait_cycles: std::mem::take(&mut tr.wait),
                        started_at: start,
                    };
                    tr.first = None;
                    lock(&self.handlers).push(run);
                }
            }
            used += n;
            tr.tick += n;
        }
        self.end_tick.store(anchor + used, Relaxed);
        used
    }
}

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
