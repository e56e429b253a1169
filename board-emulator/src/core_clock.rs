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
//!   runnable: rsemu's DMA controllers are bound as not runnable
//!   ([`crate::machine`]; DMA2 is the board's own model, which moves a frame
//!   at once).
//! - **One instruction at a time** ([`Mode::Functional`]): the awake core runs
//!   rsemu's `step` (one instruction or one exception entry), its position
//!   published to the scheduler's cursor before each (`anchor + used`: a
//!   device read inside the instruction sees the instant it began), the last
//!   instruction's overshoot carried into the next run as the core's own debt.
//!   Between two steps the board repairs the frame of an exception taken
//!   inside an `IT` block, which rsemu's entry stacks without `ITSTATE`
//!   ([`itstate`]; both modes).
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
        Arc, Mutex, MutexGuard, PoisonError,
        atomic::{AtomicU64, Ordering::Relaxed},
    },
};

use rsemu::{
    core::{
        sched::TickCursor,
        wire::{WireId, WireSink},
    },
    cpu::arm::v7m::{ArmV7m, sys::Sys},
    machine::{Bindings, Instance},
};

use crate::{
    accelerator::{Accelerator, Acr},
    device::PinsDevice,
};

mod device;
pub mod itstate;
mod run;

/// External interrupt inputs folded in (the STM32F405 has 82; three words).
const IRQS: u16 = 96;
/// TIM2's interrupt line (the tick: its update, and the acquisition's
/// deadline on compare 1).
pub const TIM2_IRQ: u16 = 28;
/// The control interrupt's line: CAN2_TX's vector, pended by the image when the
/// period's acquisition is over (`board_stm32f405::mcu::acquisition`, issue 56).
pub const CONTROL_IRQ: u16 = 63;
const CONTROL_EXCEPTION: u16 = 16 + CONTROL_IRQ;

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

/// One execution of the control handler ([`Mode::Counted`]; TIM2's before issue 56).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HandlerRun {
    /// Core cycles from TIM2's interrupt line rising (the tick's update) to the
    /// control handler's first instruction: the interrupt's entry, TIM2's
    /// handler and the acquisition's frames (DMA2 stream 0's handlers).
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
    /// TIM2's line at the last step (its rising edges are the tick and the deadline).
    tim2_level: bool,
    /// The running control handler's latency from the tick, cycles.
    latency: u64,
    first: Option<u64>,
    instructions: u64,
    wait: u64,
    accel: Option<Accel>,
    /// The address of the last instruction stepped in the control handler.
    last_pc: u32,
    /// Cycles and instructions by address ([`Core::profile`]), when on.
    profile: Option<std::collections::BTreeMap<u32, PcCost>>,
}

/// What the control handler spent at one instruction's address over the runs
/// profiled ([`Core::profile`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PcCost {
    /// Times the instruction executed.
    pub instructions: u64,
    /// Core cycles charged to it: its own and its stall on the flash's wait
    /// states (a cycle is charged to the instruction that started last; the
    /// exception's entry to the handler's first, its return to its last).
    pub cycles: u64,
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
    /// The NVIC and the system control block as the part comes out of its
    /// power-on reset, which a system reset returns them to
    /// ([`Core::system_reset`]).
    power_on: Sys,
    /// [`Mode::Functional`]'s cycle debt: the cycles the last instruction of a
    /// run took past its budget, paid at the start of the next (it steps the
    /// core itself, `run.rs`; the counted core's debt is rsemu's own).
    debt: AtomicU64,
    /// The interrupt lines the machine wires to the core, ascending
    /// ([`Core::set_wired_irqs`]): the only ones a device can assert, so the
    /// only ones a sleeping core's wake-up check reads (`run.rs`). Unset: all
    /// [`IRQS`].
    wired: std::sync::OnceLock<Vec<u16>>,
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
        let cpu = Arc::new(ArmV7m::from_props(props)?);
        let power_on = cpu.with_sys(|s| s.clone());
        let core = Arc::new(Core {
            cpu,
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
            power_on,
            debt: AtomicU64::new(0),
            wired: std::sync::OnceLock::new(),
        });
        *lock(&s) = Some(Arc::clone(&core));
        Ok(core as Arc<dyn Instance>)
    });
    slot
}

impl Core {
    /// A system reset (NRST, the IWDG's reset: RM0090 section 6.1.2) on the
    /// core's system block: the NVIC's enables, pending and active bits and
    /// priorities, the SCB's registers (SHCSR, CCR, the fault status, CPACR),
    /// the FPU's context control (FPCCR, FPCAR: a lazily preserved frame is
    /// forgotten), SysTick and the MPU back to their reset values (ARMv7-M ARM,
    /// DDI 0403E, B3.2.2 and B3.4.3: reset by a system reset), the debug block
    /// (DEMCR, the DWT) kept: a power-on reset alone clears it (C1.6.5).
    ///
    /// rsemu's warm reset restarts the core's reset sequence (registers, the
    /// exception state, the vector table's SP and PC) and keeps this block as
    /// the image left it: the restarted image booted with its interrupts
    /// still enabled at their old priorities, taken before its `main` set
    /// them up (issue 56: a bus fault after `board reset` on a board whose
    /// tick had run at 4 kHz).
    fn system_reset(&self) {
        self.cpu.with_sys(|s| {
            let (demcr, dwt_ctrl, dwt_cyccnt) = (s.demcr, s.dwt_ctrl, s.dwt_cyccnt);
            *s = self.power_on.clone();
            (s.demcr, s.dwt_ctrl, s.dwt_cyccnt) = (demcr, dwt_ctrl, dwt_cyccnt);
        });
    }

    /// Sets the interrupt lines wired to the core (the machine description's
    /// `-> cpu.irqN` wires), once; a later call is ignored. Lines at or above
    /// [`IRQS`] are dropped.
    pub fn set_wired_irqs(&self, mut lines: Vec<u16>) {
        lines.retain(|&l| l < IRQS);
        lines.sort_unstable();
        lines.dedup();
        let _ = self.wired.set(lines);
    }

    /// The lines the wake-up check reads: the wired ones, or all [`IRQS`].
    fn wake_lines(&self) -> &[u16] {
        static ALL: std::sync::LazyLock<Vec<u16>> = std::sync::LazyLock::new(|| (0..IRQS).collect());
        self.wired.get().map_or(ALL.as_slice(), Vec::as_slice)
    }

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

    /// Starts (`true`) or stops profiling the control handler by instruction
    /// address ([`Mode::Counted`]): where its cycles go, for `llvm-objdump` or
    /// `addr2line` on the image's ELF. Starting clears the profile.
    pub fn set_profile(&self, on: bool) {
        lock(&self.track).profile = on.then(std::collections::BTreeMap::new);
    }

    /// Empties the profile, if on (the link's period 0 starts it again).
    pub fn clear_profile(&self) {
        if let Some(p) = lock(&self.track).profile.as_mut() {
            p.clear();
        }
    }

    /// The profile so far (empty when off): each Thumb address's cost.
    pub fn profile(&self) -> Vec<(u32, PcCost)> {
        lock(&self.track).profile.as_ref().map(|p| p.iter().map(|(&a, &c)| (a, c)).collect()).unwrap_or_default()
    }
}
