//! Our device classes in rsemu's machine, through its public seams (a class in
//! the registry, a constructor in the bindings, a schema in the class table):
//!
//! - `painleve.regs`: a register window whose reads and writes go to a
//!   [`RegisterModel`] of ours (SPI1, ADC1, USART1), with one interrupt output
//!   (`irq`) and input lines (`in0`..`in7`: chip selects, a trigger);
//! - `painleve.pins`: the board's side of the MCU's pins: lines the host drives
//!   (`out0`..`out15`: the fault line, the button, the belt's quadrature) and
//!   lines it reads (`in0`..`in15`: the drivers' enable and directions).
//!
//! Every access to an offset a model does not implement, and every
//! configuration the real part would not work with, is a [`BoardError`] kept in
//! the machine's [`ErrorLog`]; the emulated board stops the run with the first.

use std::{
    collections::HashMap,
    sync::{Arc, Mutex, MutexGuard, PoisonError},
};

use rsemu::{
    core::{
        device::{Device, DeviceClass, RealizeCtx, ResetKind, SinkPin},
        error::{Error, Result},
        props::{Props, ValueKind},
        space::{AccessConstraints, MemAttrs, MemOps, MemResult, Region, RegionRef},
        value::{Endian, Width},
        wire::{Level, WireId, WireSink, WireSource},
    },
    machine::{
        Bindings, ClassTable, Instance,
        validate::{ClassSchema, PortDir, PropSchema},
    },
};

/// A configuration the real part would not work with, or an access the models
/// do not implement: the register, its value, and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{register} = {value:#x}: {why}")]
pub struct BoardError {
    /// The register, by name and address (`SPI1_CR1 (0x40013000)`).
    pub register: String,
    /// The value written or found.
    pub value: u32,
    /// What the part or the board needs instead (RM0090, a datasheet, docs/board.md).
    pub why: String,
}

impl BoardError {
    /// An error on `register` holding `value`.
    pub fn new(register: impl Into<String>, value: u32, why: impl Into<String>) -> Self {
        Self { register: register.into(), value, why: why.into() }
    }
}

/// The errors found so far, shared by every model of a machine.
#[derive(Debug, Clone, Default)]
pub struct ErrorLog(Arc<Mutex<Vec<BoardError>>>);

impl ErrorLog {
    /// Records `e` (each distinct error once).
    pub fn push(&self, e: BoardError) {
        let mut v = self.lock();
        if !v.contains(&e) {
            v.push(e);
        }
    }

    /// The first error, if any.
    pub fn first(&self) -> Option<BoardError> {
        self.lock().first().cloned()
    }

    /// Every error so far.
    pub fn all(&self) -> Vec<BoardError> {
        self.lock().clone()
    }

    fn lock(&self) -> MutexGuard<'_, Vec<BoardError>> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A peripheral's registers, modelled by us.
pub trait RegisterModel: Send + std::any::Any {
    /// The register at byte offset `offset` (word-aligned) reads `Ok(value)`;
    /// `Err` for an offset the model does not implement.
    ///
    /// # Errors
    /// [`BoardError`] naming the register.
    fn read(&mut self, offset: u32) -> Result2<u32>;
    /// `value` written to the register at `offset` (a narrower write arrives
    /// zero-extended, as the APB bus delivers it).
    ///
    /// # Errors
    /// [`BoardError`]: an unimplemented register, or a configuration the part
    /// would not work with.
    fn write(&mut self, offset: u32, value: u32) -> Result2<()>;
    /// Input line `line` went to `high`.
    ///
    /// # Errors
    /// [`BoardError`] when the event finds the part misconfigured (an ADC
    /// trigger with the wrong channels, say).
    fn input(&mut self, _line: u32, _high: bool) -> Result2<()> {
        Ok(())
    }
    /// What a debugger reads at `offset`: the register's value without the
    /// side effects of a read (no flag cleared, no byte taken); 0 where none.
    fn peek(&self, _offset: u32) -> u32 {
        0
    }
    /// The level the model's interrupt output should have now.
    fn irq(&self) -> bool {
        false
    }
    /// Back to its reset state (a system reset, RM0090 6.1.2).
    fn reset(&mut self);
    /// The bus a bus master reaches memory by (the machine's `dmabus`) and its
    /// requester id; models that master no bus ignore it.
    fn bind_bus(&mut self, _space: Arc<rsemu::core::space::AddressSpace>, _requester: rsemu::core::space::RequesterId) {}
}

/// A model's result.
pub type Result2<T> = std::result::Result<T, BoardError>;

/// A model behind its lock, with the interrupt wire and the error log.
pub struct Window {
    model: Mutex<Box<dyn RegisterModel>>,
    irq: Mutex<Option<WireSource>>,
    errors: ErrorLog,
    sink: Arc<WindowSink>,
}

impl std::fmt::Debug for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Window")
    }
}

impl Window {
    /// Runs `f` on the model (the host's side: set what the device senses),
    /// then updates the interrupt line.
    pub fn with<R>(&self, f: impl FnOnce(&mut dyn RegisterModel) -> R) -> R {
        let (r, irq) = {
            let mut m = self.model.lock().unwrap_or_else(PoisonError::into_inner);
            let r = f(&mut **m);
            (r, m.irq())
        };
        self.drive_irq(irq);
        r
    }

    fn drive_irq(&self, level: bool) {
        if let Some(s) = self.irq.lock().unwrap_or_else(PoisonError::into_inner).as_ref() {
            s.set(Level::from_bool(level));
        }
    }

    fn record<T: Default>(&self, r: Result2<T>) -> T {
        r.unwrap_or_else(|e| {
            self.errors.push(e);
            T::default()
        })
    }
}

/// The input lines' sink: forwards a level to the model.
struct WindowSink {
    window: std::sync::Weak<Window>,
}

impl WireSink for WindowSink {
    fn set_level(&self, _src: WireId, line: u32, level: Level) {
        if let Some(w) = self.window.upgrade() {
            let r = w.with(|m| m.input(line, level.is_high()));
            w.record(r);
        }
    }
}

impl MemOps for Window {
    fn read(&self, offset: u64, dst: &mut [u8], attrs: MemAttrs) -> MemResult {
        let base = (offset & !3) as u32;
        let v = if attrs.debug {
            // A debugger's read: no side effect.
            self.with(|m| m.peek(base))
        } else {
            let r = self.with(|m| m.read(base));
            self.record(r)
        };
        let s = (offset as usize) & 3;
        dst.copy_from_slice(&v.to_le_bytes()[s..s + dst.len()]);
        Ok(())
    }

    fn write(&self, offset: u64, src: &[u8], _attrs: MemAttrs) -> MemResult {
        let base = (offset & !3) as u32;
        let mut w = [0u8; 4];
        let s = (offset as usize) & 3;
        w[s..s + src.len()].copy_from_slice(src);
        let r = self.with(|m| m.write(base, u32::from_le_bytes(w)));
        self.record(r);
        Ok(())
    }

    fn constraints(&self) -> AccessConstraints {
        AccessConstraints::word(Width::U32, Endian::Little).with_widths(Width::U8, Width::U32)
    }
}

/// The `painleve.regs` device.
#[derive(Debug)]
pub struct RegsDevice {
    window: Arc<Window>,
    region: RegionRef,
}

impl Device for RegsDevice {
    fn class(&self) -> &'static DeviceClass {
        &REGS_CLASS
    }
    fn realize(&self, _ctx: &mut RealizeCtx<'_>) -> Result<()> {
        Ok(())
    }
    fn reset(&self, _kind: ResetKind) {
        self.window.with(|m| m.reset());
    }
    fn region(&self, name: &str) -> Option<RegionRef> {
        matches!(name, "" | "regs").then(|| Arc::clone(&self.region))
    }
    fn connect(&self, port: &str, source: WireSource) -> Result<()> {
        if port != "irq" {
            return Err(Error::Config { at: port.into(), message: "painleve.regs has one output, `irq`".into() });
        }
        *self.window.irq.lock().unwrap_or_else(PoisonError::into_inner) = Some(source);
        Ok(())
    }
    fn sink(&self, port: &str, _sources: &[WireId]) -> Option<SinkPin> {
        let line: u32 = port.strip_prefix("in")?.parse().ok()?;
        Some(SinkPin { sink: Arc::clone(&self.window.sink) as Arc<dyn WireSink>, line })
    }
}

impl Instance for RegsDevice {
    fn bind(&self, ctx: &rsemu::machine::BindCtx<'_>) -> Result<()> {
        if let Some(space) = ctx.space_named("dmabus") {
            let requester = ctx.requester();
            self.window.with(|m| m.bind_bus(Arc::clone(space), requester));
        }
        Ok(())
    }
}

/// The class of our register windows.
pub static REGS_CLASS: DeviceClass = DeviceClass {
    name: "painleve.regs",
    version: 1,
    summary: "a peripheral's registers modelled by the painleve board emulator",
    properties: &[],
    construct: |_| Err(Error::Config { at: "painleve.regs".into(), message: "bound by board_emulator, not constructed".into() }),
};

/// Lines of the pins device, each way.
pub const PIN_LINES: usize = 16;

/// The `painleve.pins` device's state.
#[derive(Debug, Default)]
pub struct PinLevels {
    /// What the MCU drives on each input line (`inN`).
    pub level: [bool; PIN_LINES],
    /// Rising edges seen on each input line.
    pub rises: [u64; PIN_LINES],
}

/// The `painleve.pins` device: the board's side of the MCU's pins.
#[derive(Debug)]
pub struct PinsDevice {
    levels: Arc<Mutex<PinLevels>>,
    sink: Arc<PinSink>,
    outs: Mutex<[Option<WireSource>; PIN_LINES]>,
    /// The level each output line idles at before the host drives it.
    idle: [bool; PIN_LINES],
}

#[derive(Debug)]
struct PinSink(Arc<Mutex<PinLevels>>);

impl WireSink for PinSink {
    fn set_level(&self, _src: WireId, line: u32, level: Level) {
        let mut s = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        let l = (line as usize).min(PIN_LINES - 1);
        if level.is_high() && !s.level[l] {
            s.rises[l] += 1;
        }
        s.level[l] = level.is_high();
    }
}

impl PinsDevice {
    /// Drives output line `line` (the host's side of a wire).
    pub fn drive(&self, line: usize, high: bool) {
        if let Some(s) = self.outs.lock().unwrap_or_else(PoisonError::into_inner).get(line).and_then(Option::as_ref) {
            s.set(Level::from_bool(high));
        }
    }

    /// What the MCU drives on input line `line` now.
    pub fn level(&self, line: usize) -> bool {
        self.levels.lock().unwrap_or_else(PoisonError::into_inner).level.get(line).copied().unwrap_or(false)
    }
}

impl Device for PinsDevice {
    fn class(&self) -> &'static DeviceClass {
        &PINS_CLASS
    }
    fn realize(&self, _ctx: &mut RealizeCtx<'_>) -> Result<()> {
        Ok(())
    }
    fn reset(&self, _kind: ResetKind) {}
    fn connect(&self, port: &str, source: WireSource) -> Result<()> {
        let n: usize = port
            .strip_prefix("out")
            .and_then(|s| s.parse().ok())
            .filter(|&n| n < PIN_LINES)
            .ok_or_else(|| Error::Config { at: port.into(), message: "painleve.pins outputs are out0..out15".into() })?;
        source.set(Level::from_bool(self.idle[n]));
        self.outs.lock().unwrap_or_else(PoisonError::into_inner)[n] = Some(source);
        Ok(())
    }
    fn sink(&self, port: &str, _sources: &[WireId]) -> Option<SinkPin> {
        let line: u32 = port.strip_prefix("in")?.parse().ok().filter(|&n: &u32| (n as usize) < PIN_LINES)?;
        Some(SinkPin { sink: Arc::clone(&self.sink) as Arc<dyn WireSink>, line })
    }
}

impl Instance for PinsDevice {}

/// The class of the board's pins.
pub static PINS_CLASS: DeviceClass = DeviceClass {
    name: "painleve.pins",
    version: 1,
    summary: "the reference board's side of the MCU's pins (painleve board emulator)",
    properties: &[],
    construct: |_| Err(Error::Config { at: "painleve.pins".into(), message: "bound by board_emulator, not constructed".into() }),
};

/// What the machine's text refers to by role, and where the host finds it after
/// the build.
#[derive(Default)]
pub struct Hub {
    models: Mutex<HashMap<String, Box<dyn RegisterModel>>>,
    windows: Mutex<HashMap<String, Arc<Window>>>,
    pins: Mutex<Option<Arc<PinsDevice>>>,
    idle: [bool; PIN_LINES],
    errors: ErrorLog,
}

impl Hub {
    /// A hub whose models report to `errors`, the pins' outputs idling at `idle`.
    pub fn new(errors: ErrorLog, idle: [bool; PIN_LINES]) -> Self {
        Self { idle, errors, ..Self::default() }
    }

    /// Offers `model` under `role` (the machine text's `role = "..."`).
    pub fn offer(&self, role: &str, model: Box<dyn RegisterModel>) {
        self.models.lock().unwrap_or_else(PoisonError::into_inner).insert(role.into(), model);
    }

    /// The window built for `role`.
    pub fn window(&self, role: &str) -> Option<Arc<Window>> {
        self.windows.lock().unwrap_or_else(PoisonError::into_inner).get(role).cloned()
    }

    /// The pins device.
    pub fn pins(&self) -> Option<Arc<PinsDevice>> {
        self.pins.lock().unwrap_or_else(PoisonError::into_inner).clone()
    }
}

/// Adds our two classes to rsemu's registry, bindings and class table.
///
/// # Errors
/// rsemu's, when a class is already there.
pub fn install(reg: &mut rsemu::core::Registry, bindings: &mut Bindings, classes: &mut ClassTable, hub: Arc<Hub>) -> Result<()> {
    reg.add(&REGS_CLASS)?;
    reg.add(&PINS_CLASS)?;
    let h = Arc::clone(&hub);
    bindings.bind("painleve.regs", move |props: &Props| {
        let mut r = props.reader();
        let role = r.or_str("role", "")?.to_string();
        let size: u64 = r.or("size", 0x400u64)?;
        r.finish()?;
        let model = h
            .models
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .remove(&role)
            .ok_or_else(|| Error::Config { at: role.clone(), message: "no model offered for this role".into() })?;
        let window = Arc::new_cyclic(|weak| Window {
            model: Mutex::new(model),
            irq: Mutex::new(None),
            errors: h.errors.clone(),
            sink: Arc::new(WindowSink { window: weak.clone() }),
        });
        let region = Arc::new(Region::io(role.clone(), size, Arc::clone(&window) as Arc<dyn MemOps>));
        h.windows.lock().unwrap_or_else(PoisonError::into_inner).insert(role, Arc::clone(&window));
        Ok(Arc::new(RegsDevice { window, region }) as Arc<dyn Instance>)
    })?;
    let h = Arc::clone(&hub);
    bindings.bind("painleve.pins", move |_props: &Props| {
        let levels: Arc<Mutex<PinLevels>> = Arc::default();
        let dev = Arc::new(PinsDevice {
            sink: Arc::new(PinSink(Arc::clone(&levels))),
            levels,
            outs: Mutex::new(Default::default()),
            idle: h.idle,
        });
        *h.pins.lock().unwrap_or_else(PoisonError::into_inner) = Some(Arc::clone(&dev));
        Ok(dev as Arc<dyn Instance>)
    })?;
    classes.insert(
        ClassSchema::new("painleve.regs")
            .prop(PropSchema::new("role", ValueKind::Str))
            .prop(PropSchema::new("size", ValueKind::Int))
            .region("")
            .region("regs")
            .port("irq", PortDir::Out)
            .port_bank("in", PortDir::In, 8),
    );
    classes.insert(ClassSchema::new("painleve.pins").port_bank("out", PortDir::Out, PIN_LINES as u32).port_bank(
        "in",
        PortDir::In,
        PIN_LINES as u32,
    ));
    Ok(())
}
