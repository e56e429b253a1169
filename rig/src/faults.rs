//! Faults the rig injects (docs/hardware.md "Faults"),
//! as listed in a scenario's `[[faults]]` tables. Each fault acts over a window
//! of sample times `[at_s, at_s + duration_s)`, compiled once into a range of
//! period indices by one rounding rule ([`Fault::periods`]) and checked at load
//! (a fault none of whose periods is in the run is refused); where it acts
//! (plant side, wire, firmware side) is part of its definition, so that the
//! in-process and the iceoryx2 loops inject it at the same place.

use std::ops::Range;

use board_description::BoardDescription;
use serde::{Deserialize, Serialize};
use shared::time::{Duration, Period};

use crate::record::RunError;

/// A sensor whose counts a fault corrupts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Signal {
    /// Base-joint encoder (`theta1`).
    Theta1,
    /// Elbow encoder (`theta2 - theta1`).
    Elbow,
    /// Load cell, tangential channel.
    FT,
    /// Load cell, normal channel.
    FN,
    /// Belt encoder.
    Belt,
}

/// What goes wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// Firmware side: each step in the window starts `delay_s` late (an interrupt
    /// held off, a slow bus): its command leaves at `t_k + delay_s`. Later than
    /// one period is a deadline miss for both sides.
    LateCommand,
    /// Wire: the commands of the window are lost; the plant holds the previous one
    /// and counts a deadline miss (the firmware cannot know).
    DropCommand,
    /// Firmware process (iceoryx2 only): at the first frame of the window the
    /// process stops for `duration_s` of wall-clock time, then catches up.
    Stall,
    /// Rig (iceoryx2, spawned firmware only): the firmware process is killed
    /// (SIGKILL) at `at_s`.
    KillFirmware,
    /// Plant side: the sensor's count stays at its value at `at_s`.
    StuckSensor,
    /// Plant side: the sensor gives no reading (NaN); the frame flags it invalid.
    NanSensor,
    /// Plant side: the sensor's count is out of its range (a corrupt frame).
    OutOfRange,
    /// Boards only (twin and emulated), bus: every SPI transfer to the encoder (`signal` theta1
    /// or elbow) fails.
    SpiError,
    /// Boards only (twin and emulated), bus: a data bit of every answer of the encoder (`signal`
    /// theta1 or elbow) flips on MISO (odd parity).
    ParityError,
    /// Boards only (twin and emulated): the encoder's magnet (`signal` theta1 or elbow) is gone
    /// (DIAAGC MAGL).
    MagnetLost,
    /// Boards only (twin and emulated): the load cell's ADC conversion is missing (both channels).
    MissingConversion,
    /// Boards only (twin and emulated): the motor drivers assert their shared fault line (nFAULT).
    DriverFault,
    /// Board (twin and emulated), the encoders' acquisition by DMA (docs/board.md
    /// "The encoders by DMA"): a transfer error on DMA2's SPI1 streams (DMA_LISR
    /// TEIF, RM0090 10.5.1: a bus error, the stream disabled by the hardware). No
    /// frame reaches the encoders: both readings of the period are invalid.
    DmaTransferError,
    /// Board, the encoders' acquisition: SPI1_RX's stream reports a FIFO error
    /// (LISR FEIF, RM0090 10.3.18). Both readings of the period invalid.
    DmaFifoError,
    /// Board, the encoders' acquisition: SPI1_RX's stream reports a direct-mode
    /// error (LISR DMEIF, RM0090 10.3.18). Both readings of the period invalid.
    DmaDirectModeError,
    /// Board, the encoders' acquisition: the period's frames are not done by the
    /// acquisition's deadline (no DMA request reaches the streams; the image stops
    /// them at TIM2's compare, 40 us after the tick). Both readings invalid.
    DmaLateTransfer,
    /// Board, the encoders' acquisition: the chip select of the encoder `signal`
    /// (theta1: PA4, elbow: PB0) reads low after its release (GPIO IDR). Both
    /// readings of the period invalid.
    StuckChipSelect,
    /// Sensor: the encoder (`signal` theta1 or elbow) reads `counts` (signed,
    /// 1 to 100 in magnitude, counts of the encoder's resolution: 16 384 a turn
    /// on the reference board) off for `periods` (1 to 5) periods from `at_s`,
    /// then right again (a glitch: EMI on the SPI lines, a chip's bad sample).
    /// The window is those periods (`duration_s` is refused).
    EncoderSpike,
    /// Sensor: the load cell's axis (`signal` f_t or f_n) reads an offset growing
    /// at `rate_n_per_s` (N/s, signed, 0.05 to 0.5 in magnitude) from `at_s`,
    /// `rate (t_k - at_s)` at sample time `t_k`, gone after the window (an
    /// amplifier's offset drifting with temperature).
    LoadCellDrift,
    /// Sensor: the belt encoder counts `gain` (finite, 0.01 to 100 in
    /// magnitude, negative: the other way) times the belt's travel from `at_s`
    /// (a slipping or wrongly geared wheel, its A and B lines swapped); the
    /// count carries on from where it was, so the belt speed the firmware reads
    /// is `gain` times the true one. After the window it counts the travel
    /// again, from where the gain left it.
    BeltGain,
    /// Board (twin and emulated): from `at_s`, the board's physical truth is
    /// `board` (a whole `[board]` table: its fields left out take the
    /// reference board's values), instead of the scenario's `[board]`: a motor
    /// or an encoder rewired, weakened or slipped mid-run. The firmware's
    /// calibration stays what it was.
    Board,
}

impl FaultKind {
    /// Whether the fault acts on the board's bus or devices (the board twin and
    /// the emulated board): the devices' faults and the encoders' acquisition
    /// faults ([`FaultKind::is_acquisition_fault`]).
    pub fn is_bus_fault(self) -> bool {
        matches!(self, Self::SpiError | Self::ParityError | Self::MagnetLost | Self::MissingConversion | Self::DriverFault)
            || self.is_acquisition_fault()
    }

    /// Whether the fault is one of the encoders' acquisition by DMA (docs/board.md
    /// "The encoders by DMA"): each makes both encoders' readings of the period
    /// invalid, and `bad_frame_limit` such periods in a row latch the safe state
    /// `Acquisition` (13).
    pub fn is_acquisition_fault(self) -> bool {
        matches!(
            self,
            Self::DmaTransferError | Self::DmaFifoError | Self::DmaDirectModeError | Self::DmaLateTransfer | Self::StuckChipSelect
        )
    }
}

/// One fault of a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fault {
    /// What goes wrong.
    pub kind: FaultKind,
    /// Start of the window (sample time), s.
    pub at_s: f64,
    /// Length of the window, s (default one sample: the fault hits one period).
    #[serde(default)]
    pub duration_s: f64,
    /// `late_command`: how late the step starts, s.
    #[serde(default)]
    pub delay_s: f64,
    /// Sensor faults: which sensor.
    #[serde(default)]
    pub signal: Option<Signal>,
    /// `encoder_spike`: how far off the encoder reads, counts (signed, 1 to 100 in magnitude).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub counts: Option<i32>,
    /// `encoder_spike`: for how many periods (1 to 5); the scenario's key is `periods`.
    #[serde(default, rename = "periods", skip_serializing_if = "Option::is_none")]
    pub spike_periods: Option<u32>,
    /// `load_cell_drift`: the offset's rate, N/s (signed, 0.05 to 0.5 in magnitude).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate_n_per_s: Option<f64>,
    /// `belt_gain`: the belt encoder's gain on the travel (0.01 to 100 in magnitude, signed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain: Option<f64>,
    /// `board`: the board's truth in the window (a whole `[board]` table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub board: Option<BoardDescription>,
}

impl Fault {
    /// The periods the fault acts in, by index: period `k` (sample time
    /// `t_k = k Ts`) is in the window when `at_s <= t_k < at_s + max(duration_s,
    /// Ts)`, with `at_s` and `duration_s` first rounded to whole microseconds (the
    /// wire's resolution, [`shared::time`]). So a window of at least one period
    /// holds at least one sample time, a fault at `at_s = 3.0005` with `Ts = 1 ms`
    /// acts from period 3001 whatever its kind, and one at an exact sample time acts
    /// from that sample. The one rounding rule of every fault (docs/rig.md "Faults").
    ///
    /// An `encoder_spike`'s window is its `periods` periods from the first.
    pub fn periods(&self, period: Period) -> Range<u64> {
        let ts = period.as_us();
        let at = (self.at_s * 1e6).round().max(0.0) as u64;
        let len = ((self.duration_s * 1e6).round().max(0.0) as u64).max(ts);
        let first = at.div_ceil(ts);
        match (self.kind, self.spike_periods) {
            (FaultKind::EncoderSpike, Some(n)) => first..first + u64::from(n),
            _ => first..(at + len).div_ceil(ts),
        }
    }

    /// A fault of `kind` over `[at_s, at_s + duration_s)`, every other field
    /// left out (its TOML's defaults): add them with struct update syntax.
    pub fn new(kind: FaultKind, at_s: f64, duration_s: f64) -> Self {
        Self {
            kind,
            at_s,
            duration_s,
            delay_s: 0.0,
            signal: None,
            counts: None,
            spike_periods: None,
            rate_n_per_s: None,
            gain: None,
            board: None,
        }
    }

    /// Checks the fields only some kinds take (`counts`, `periods`,
    /// `rate_n_per_s`, `gain`, `board`): each present exactly for its kind, in its range.
    fn check_kind_fields(&self) -> Result<(), String> {
        use FaultKind::{BeltGain, Board, EncoderSpike, LoadCellDrift};
        let given = [
            ("counts", self.counts.is_some(), EncoderSpike),
            ("periods", self.spike_periods.is_some(), EncoderSpike),
            ("rate_n_per_s", self.rate_n_per_s.is_some(), LoadCellDrift),
            ("gain", self.gain.is_some(), BeltGain),
            ("board", self.board.is_some(), Board),
        ];
        for (key, present, kind) in given {
            if present && self.kind != kind {
                return Err(format!("`{key}` is a key of {} faults only", serde_kind(kind)));
            }
            if !present && self.kind == kind {
                return Err(format!("a {} fault needs `{key}`", serde_kind(kind)));
            }
        }
        match self.kind {
            EncoderSpike => {
                if !matches!(self.signal, Some(Signal::Theta1 | Signal::Elbow)) {
                    return Err("an encoder_spike needs `signal` theta1 or elbow".into());
                }
                let c = self.counts.unwrap_or(0);
                if !(1..=100).contains(&c.unsigned_abs()) {
                    return Err(format!("counts = {c}: 1 to 100 encoder counts, either sign"));
                }
                let n = self.spike_periods.unwrap_or(0);
                if !(1..=5).contains(&n) {
                    return Err(format!("periods = {n}: a spike of 1 to 5 periods"));
                }
                if self.duration_s != 0.0 {
                    return Err(format!("duration_s = {}: an encoder_spike lasts its `periods`; leave duration_s out", self.duration_s));
                }
            }
            LoadCellDrift => {
                if !matches!(self.signal, Some(Signal::FT | Signal::FN)) {
                    return Err("a load_cell_drift needs `signal` f_t or f_n".into());
                }
                let r = self.rate_n_per_s.unwrap_or(0.0);
                if !(r.is_finite() && (0.05..=0.5).contains(&r.abs())) {
                    return Err(format!("rate_n_per_s = {r}: 0.05 to 0.5 N/s, either sign"));
                }
            }
            BeltGain => {
                if self.signal.is_some_and(|s| s != Signal::Belt) {
                    return Err("a belt_gain acts on the belt encoder: `signal` belt or none".into());
                }
                let g = self.gain.unwrap_or(0.0);
                if !(g.is_finite() && (0.01..=100.0).contains(&g.abs())) {
                    return Err(format!("gain = {g}: 0.01 to 100 in magnitude, negative for the other way"));
                }
            }
            Board => {
                if self.signal.is_some() {
                    return Err("a board fault takes no `signal` (its `board` table says what changes)".into());
                }
                self.board.as_ref().map_or(Ok(()), BoardDescription::check).map_err(|e| format!("the fault's {e}"))?;
            }
            _ => {}
        }
        Ok(())
    }

    /// Checks the fault's fields; returns what is wrong.
    pub fn check(&self) -> Result<(), String> {
        if !(self.at_s.is_finite() && self.at_s >= 0.0) {
            return Err(format!("at_s = {}: a finite time >= 0", self.at_s));
        }
        if !(self.duration_s.is_finite() && (0.0..=1e5).contains(&self.duration_s)) {
            return Err(format!("duration_s = {}: a duration in [0, 1e5] s", self.duration_s));
        }
        // Every kind: a NaN or huge delay on a fault that does not use it was accepted
        // and written as `null` in summary.json (found by fuzzing, docs/fuzzing.md).
        if !(self.delay_s.is_finite() && (0.0..10.0).contains(&self.delay_s)) {
            return Err(format!("delay_s = {}: a delay in [0, 10) s (late_command: in (0, 10))", self.delay_s));
        }
        let sensor = matches!(self.kind, FaultKind::StuckSensor | FaultKind::NanSensor | FaultKind::OutOfRange);
        if sensor && self.signal.is_none() {
            return Err("a sensor fault needs `signal` (theta1, elbow, f_t, f_n or belt)".into());
        }
        let encoder =
            matches!(self.kind, FaultKind::SpiError | FaultKind::ParityError | FaultKind::MagnetLost | FaultKind::StuckChipSelect);
        if encoder && !matches!(self.signal, Some(Signal::Theta1 | Signal::Elbow)) {
            return Err("an encoder's bus fault needs `signal` theta1 or elbow".into());
        }
        if self.kind.is_acquisition_fault() && self.kind != FaultKind::StuckChipSelect && self.signal.is_some() {
            return Err("the DMA faults (dma_transfer_error, dma_fifo_error, dma_direct_mode_error, dma_late_transfer) take no `signal`: \
                 the streams carry both encoders' frames"
                .into());
        }
        if matches!(self.kind, FaultKind::MissingConversion | FaultKind::DriverFault) && self.signal.is_some() {
            return Err(
                "missing_conversion and driver_fault take no `signal` (the conversion is both channels', the fault line the drivers')"
                    .into(),
            );
        }
        if self.kind == FaultKind::LateCommand && !(self.delay_s.is_finite() && self.delay_s > 0.0 && self.delay_s < 10.0) {
            return Err(format!("delay_s = {}: a delay in (0, 10) s", self.delay_s));
        }
        if self.kind == FaultKind::Stall && !(self.duration_s > 0.0 && self.duration_s <= 60.0) {
            return Err(format!("duration_s = {}: a stall of (0, 60] s of wall time", self.duration_s));
        }
        self.check_kind_fields()
    }
}

/// `kind` as a scenario spells it (`encoder_spike`).
fn serde_kind(kind: FaultKind) -> String {
    serde_json::to_value(kind).ok().and_then(|v| v.as_str().map(str::to_owned)).unwrap_or_else(|| format!("{kind:?}"))
}

/// The faults of a run, each compiled once into the periods it acts in
/// ([`Fault::periods`]), queried by period index.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultPlan {
    faults: Vec<(Fault, Range<u64>)>,
    /// The control period, us.
    period_us: u64,
}

impl FaultPlan {
    /// The plan of `faults` at control period `period`.
    pub fn new(faults: &[Fault], period: Period) -> Self {
        Self { faults: faults.iter().map(|f| (*f, f.periods(period))).collect(), period_us: period.as_us() }
    }

    /// How far the encoder `signal` (theta1 or elbow) reads off in period `k`
    /// by the `encoder_spike` faults acting in it, counts (their sum).
    pub fn spike_counts(&self, signal: Signal, k: u64) -> i32 {
        self.active(FaultKind::EncoderSpike, k).filter(|f| f.signal == Some(signal)).filter_map(|f| f.counts).sum()
    }

    /// The load cell's offsets `[f_t, f_n]` in period `k` by the
    /// `load_cell_drift` faults acting in it, N: `rate_n_per_s (t_k - at_s)`,
    /// `t_k` the period's sample time and `at_s` rounded to the microsecond as
    /// [`Fault::periods`] rounds it; `None` when no drift acts (the readings
    /// then are the model's own, untouched).
    pub fn load_offsets_n(&self, k: u64) -> Option<[f64; 2]> {
        let t_us = k * self.period_us;
        let mut offsets = None;
        for f in self.active(FaultKind::LoadCellDrift, k) {
            let at_us = (f.at_s * 1e6).round().max(0.0) as u64;
            let o: &mut [f64; 2] = offsets.get_or_insert([0.0; 2]);
            let axis = usize::from(f.signal == Some(Signal::FN));
            o[axis] += f.rate_n_per_s.unwrap_or(0.0) * (t_us.saturating_sub(at_us) as f64 * 1e-6);
        }
        offsets
    }

    /// The belt encoder's gain on the travel in period `k` (`belt_gain`: the
    /// product of those acting in it), `None` when none acts.
    pub fn belt_gain(&self, k: u64) -> Option<f64> {
        self.active(FaultKind::BeltGain, k).filter_map(|f| f.gain).reduce(|a, b| a * b)
    }

    /// The board's truth in period `k` by a `board` fault acting in it (the
    /// last listed of those), `None` when none acts (the scenario's `[board]`).
    pub fn board(&self, k: u64) -> Option<BoardDescription> {
        self.active(FaultKind::Board, k).filter_map(|f| f.board).last()
    }

    /// Faults of `kind` acting in period `k`.
    pub fn active(&self, kind: FaultKind, k: u64) -> impl Iterator<Item = &Fault> {
        self.faults.iter().filter(move |(f, w)| f.kind == kind && w.contains(&k)).map(|(f, _)| f)
    }

    /// How late the firmware's step of period `k` starts (zero when on time),
    /// rounded to the microsecond.
    pub fn command_delay(&self, k: u64) -> Duration {
        let s = self.active(FaultKind::LateCommand, k).map(|f| f.delay_s).fold(0.0, f64::max);
        Duration::from_us((s * 1e6).round() as u64)
    }

    /// Whether the command of period `k` is lost on the wire.
    pub fn drops_command(&self, k: u64) -> bool {
        self.active(FaultKind::DropCommand, k).next().is_some()
    }

    /// The wall-clock stall (s) that starts in period `k`, the first of its window, if one does.
    pub fn stall_starting(&self, k: u64) -> Option<f64> {
        self.faults.iter().find(|(f, w)| f.kind == FaultKind::Stall && w.start == k).map(|(f, _)| f.duration_s)
    }

    /// Whether the firmware process is killed before period `k`, the first of the fault's window.
    pub fn kills_firmware_at(&self, k: u64) -> bool {
        self.faults.iter().any(|(f, w)| f.kind == FaultKind::KillFirmware && w.start == k)
    }

    /// The board twin's faults acting in period `k`: the bus faults
    /// ([`FaultKind::is_bus_fault`]) and the stuck sensors, with their signals.
    pub fn board_faults(&self, k: u64) -> impl Iterator<Item = (FaultKind, Option<Signal>)> {
        self.faults
            .iter()
            .filter(move |(f, w)| w.contains(&k) && (f.kind.is_bus_fault() || f.kind == FaultKind::StuckSensor))
            .map(|(f, _)| (f.kind, f.signal))
    }

    /// The sensor faults acting in period `k`.
    pub fn sensor_faults(&self, k: u64) -> impl Iterator<Item = (FaultKind, Signal)> {
        self.faults.iter().filter(move |(_, w)| w.contains(&k)).filter_map(|(f, _)| match f.kind {
            FaultKind::StuckSensor | FaultKind::NanSensor | FaultKind::OutOfRange => f.signal.map(|s| (f.kind, s)),
            _ => None,
        })
    }
}

/// The kinds of link to the firmware, for the faults each can inject (checked
/// in one place, [`LinkKind::check`], by the links' constructors and by the
/// commands before they write anything).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkKind {
    /// The firmware step linked into the plant's process.
    InProcess,
    /// The firmware in its own process over iceoryx2.
    Ipc,
    /// The MCU image in QEMU over a socket.
    PilQemu,
    /// The MCU image on a board behind a serial port (HIL).
    PilSerial,
    /// The arm application on the board twin (bus-level device models).
    Twin,
    /// The `arm` ELF on the emulated board (register-level models).
    Emulator,
}

impl LinkKind {
    /// Every fault this link can inject. Sensor, late and dropped commands act on
    /// the plant's side or the firmware's start time and work everywhere;
    /// `stall` needs a host process to stop, `kill_firmware` a process to kill
    /// (the firmware's, or QEMU).
    pub fn injectable(self) -> &'static [FaultKind] {
        use FaultKind::*;
        const EVERYWHERE: [FaultKind; 5] = [LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange];
        match self {
            Self::Ipc => &[LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, Stall, KillFirmware],
            Self::PilQemu => &[LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, KillFirmware],
            Self::InProcess => &[LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, EncoderSpike, LoadCellDrift, BeltGain],
            Self::PilSerial => &EVERYWHERE,
            // The twin makes its readings on the bus: the plant side's frame
            // faults (nan_sensor, out_of_range) do not reach it; a late step needs
            // a clock, which the twin's steps do not take.
            Self::Twin | Self::Emulator => &[
                DropCommand,
                StuckSensor,
                SpiError,
                ParityError,
                MagnetLost,
                MissingConversion,
                DriverFault,
                DmaTransferError,
                DmaFifoError,
                DmaDirectModeError,
                DmaLateTransfer,
                StuckChipSelect,
                EncoderSpike,
                LoadCellDrift,
                BeltGain,
                Board,
            ],
        }
    }

    /// Refuses a scenario fault this link cannot inject.
    ///
    /// # Errors
    /// [`RunError::Unsupported`] naming the first such fault, why, and what to use instead.
    pub fn check(self, faults: &[Fault]) -> Result<(), RunError> {
        let Some(f) = faults.iter().find(|f| !self.injectable().contains(&f.kind)) else { return Ok(()) };
        Err(RunError::Unsupported(match (f.kind, self) {
            (FaultKind::Stall | FaultKind::KillFirmware, Self::Twin | Self::Emulator) => format!(
                "fault {:?} acts on a firmware process, and the board {} runs in this one: run over iceoryx2 (without --link)",
                f.kind,
                if self == Self::Twin { "twin" } else { "emulator" }
            ),
            (FaultKind::Stall | FaultKind::KillFirmware, Self::InProcess) => {
                format!("fault {:?} acts on the firmware process: run over iceoryx2 (without --in-process)", f.kind)
            }
            (FaultKind::Stall, Self::PilQemu) => "fault stall stalls a host process: not available in PIL (kill_firmware is)".into(),
            (FaultKind::Stall, _) => "fault stall stalls a host process: not available over a serial port".into(),
            (FaultKind::KillFirmware, _) => {
                "fault kill_firmware kills the emulator that runs the image: not available over a serial port; \
                 to test a lost board, cut its power or unplug it during a run"
                    .into()
            }
            (FaultKind::Board, link) => format!(
                "fault board changes the board's physical truth, which only a board has: run on the board twin (`run --link twin`) \
                 or the emulated board (`run --link emulator`), not the {link:?} link"
            ),
            (kind @ (FaultKind::EncoderSpike | FaultKind::LoadCellDrift | FaultKind::BeltGain), link) => format!(
                "fault {kind:?} is made by the rig's sensor model or the board's devices: run in process (`run --in-process`), \
                 on the board twin (`run --link twin`) or the emulated board (`run --link emulator`), not the {link:?} link"
            ),
            (kind, link) if kind.is_bus_fault() => {
                format!(
                    "fault {kind:?} acts on the board's bus and devices: run on the board twin (`run --link twin`) or the emulated board \
                     (`run --link emulator`), not the {link:?} link"
                )
            }
            (kind @ (FaultKind::NanSensor | FaultKind::OutOfRange | FaultKind::LateCommand), Self::Twin | Self::Emulator) => format!(
                "fault {kind:?} acts on the wire-level frame or the step's clock, which the board twin does not have: \
                 use its bus faults (spi_error, parity_error, magnet_lost, missing_conversion, driver_fault), its acquisition faults \
                 (dma_transfer_error, dma_fifo_error, dma_direct_mode_error, dma_late_transfer, stuck_chip_select) or stuck_sensor"
            ),
            (kind, link) => format!("fault {kind:?} cannot be injected over the {link:?} link"),
        }))
    }
}

/// What [`random_schedule`] draws: how many fault windows, over which span of
/// sample time, and the bounds that keep every fault short of the firmware's safe
/// state, so that a long run (the soak test, `tests/soak.rs`) goes on after
/// each one and every fault's effect can be checked on its own.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomSchedule {
    /// Seed of the generator (ChaCha8): the same settings give the same schedule.
    pub seed: u64,
    /// The kinds drawn from, uniformly. [`FaultKind::KillFirmware`] ends the run
    /// and is refused: add it after the schedule's end if wanted.
    pub kinds: Vec<FaultKind>,
    /// Number of windows (at most 1000, a scenario's limit).
    pub count: usize,
    /// Windows start at or after this sample time, s.
    pub from_s: f64,
    /// Every window, and the periods a fault reaches past it (a stall's late
    /// answers, the recovery period after bad frames), ends before this sample time, s.
    pub to_s: f64,
    /// Control period `Ts`, s (the scenario's `timing.period()`).
    pub ts: f64,
    /// Most consecutive periods the firmware may count as missed or bad: one
    /// less than the smaller of its `deadline_miss_limit` and `bad_frame_limit`
    /// (3 by default, so 2). Bounds `late_command` past the deadline,
    /// `nan_sensor`, `out_of_range` (periods) and the misses a stall causes.
    pub max_in_a_row: u32,
    /// Longest window of the faults without a limit (`drop_command`,
    /// `stuck_sensor`, `late_command` within the deadline), periods, >= 1.
    pub max_window: u32,
    /// The plant's lockstep command timeout (`rig.command_timeout_s`), s: a stall
    /// lasts `(n + 1/2)` timeouts of wall time, `n` drawn in
    /// `0..=max_stall_timeouts`, so that the plant times out `n` periods, half a
    /// timeout from either boundary (the stall is in (0, 60] s:
    /// `(max_stall_timeouts + 1/2)` timeouts must fit).
    pub command_timeout_s: f64,
    /// Most periods a stall is drawn to time out (`n` above), at most
    /// `max_in_a_row`. A stall is wall time against the plant's wall-clock
    /// timeouts: a firmware that wakes more than half a timeout late (a machine
    /// under load) makes the plant time out `n + 1` periods, and both sides count
    /// them (docs/rig.md "Soak test"). `max_in_a_row - 1` keeps that extra one
    /// short of the safe state; `max_in_a_row` draws the longest stall the
    /// firmware survives on an idle machine.
    pub max_stall_timeouts: u32,
}

impl RandomSchedule {
    /// The kinds the iceoryx2 lockstep link injects that leave the run going:
    /// all of [`LinkKind::Ipc`]'s but [`FaultKind::KillFirmware`].
    pub fn survivable_ipc_kinds() -> Vec<FaultKind> {
        LinkKind::Ipc.injectable().iter().copied().filter(|k| *k != FaultKind::KillFirmware).collect()
    }

    /// Periods a window of `kind` may reach, from its first period to the last it
    /// affects (the window, plus a stall's misses and the answer after them, plus
    /// the recovery period after bad frames).
    fn span_periods(&self, kind: FaultKind) -> u64 {
        let n = u64::from(self.max_in_a_row);
        match kind {
            FaultKind::Stall => u64::from(self.max_stall_timeouts.min(self.max_in_a_row)) + 1,
            FaultKind::NanSensor | FaultKind::OutOfRange => n + 1,
            FaultKind::LateCommand => n.max(u64::from(self.max_window)),
            _ => u64::from(self.max_window),
        }
    }
}

/// A seeded random schedule of non-overlapping fault windows (the soak test's,
/// `scripts/soak.sh`): the span `[from_s, to_s)` is cut into `count` equal
/// slots of whole periods, and each slot holds one window of a kind drawn
/// uniformly from `kinds`, at a random start (a whole period) with at least
/// two clean periods after everything it affects. Within a kind:
///
/// - `drop_command`, `stuck_sensor`: 1 to `max_window` periods (a sensor fault's
///   `signal` drawn from the five);
/// - `late_command`: half of them on time (`delay_s` from 1 us to `Ts - 1 us`, 1
///   to `max_window` periods), half past the deadline (`delay_s` from `Ts` to
///   `3 Ts`, 1 to `max_in_a_row` periods); delays are whole microseconds, as the
///   firmware's clock counts them;
/// - `nan_sensor`, `out_of_range`: 1 to `max_in_a_row` periods;
/// - `stall`: `(n + 1/2) command_timeout_s` of wall time, `n` in `0..=max_stall_timeouts`.
///
/// Windows start at `k Ts` and last `n Ts` exactly (`duration_s`), so each hits
/// periods `k..k+n`.
///
/// # Errors
/// A message when the settings cannot give such a schedule: no kinds or
/// `kill_firmware` among them, `count` outside 1 to 1000, a non-finite or empty
/// span, a period outside (0, 1] s, `max_in_a_row` or `max_window` of 0,
/// `max_stall_timeouts` above `max_in_a_row`, slots too short for the longest
/// window plus two clean periods, or a stall longer than 60 s.
pub fn random_schedule(spec: &RandomSchedule) -> Result<Vec<Fault>, String> {
    use rand::{RngExt, SeedableRng};

    let ts = spec.ts;
    if spec.kinds.is_empty() {
        return Err("no fault kinds to draw from".into());
    }
    if spec.kinds.contains(&FaultKind::KillFirmware) {
        return Err("kill_firmware ends the run: add it after the schedule's end, not among its kinds".into());
    }
    if !(1..=1000).contains(&spec.count) {
        return Err(format!("count = {}: 1 to 1000 windows (a scenario's limit)", spec.count));
    }
    if !(ts.is_finite() && ts > 0.0 && ts <= 1.0) {
        return Err(format!("ts = {ts}: a period in (0, 1] s"));
    }
    if !(spec.from_s.is_finite() && spec.to_s.is_finite() && spec.from_s >= 0.0 && spec.to_s > spec.from_s) {
        return Err(format!("span [{}, {}) s: finite, from >= 0, to > from", spec.from_s, spec.to_s));
    }
    if spec.max_in_a_row == 0 || spec.max_window == 0 {
        return Err("max_in_a_row and max_window: at least 1 period".into());
    }
    if spec.max_stall_timeouts > spec.max_in_a_row {
        return Err(format!(
            "max_stall_timeouts = {}: at most max_in_a_row = {} (more periods timed out in a row latch the safe state)",
            spec.max_stall_timeouts, spec.max_in_a_row
        ));
    }
    let longest_stall = (f64::from(spec.max_stall_timeouts) + 0.5) * spec.command_timeout_s;
    if spec.kinds.contains(&FaultKind::Stall) && !(spec.command_timeout_s > 0.0 && longest_stall <= 60.0) {
        return Err(format!("a stall of up to {longest_stall} s: command_timeout_s > 0 and (max_stall_timeouts + 1/2) timeouts <= 60 s"));
    }
    let first = (spec.from_s / ts).ceil() as u64;
    let last = (spec.to_s / ts).floor() as u64;
    let slot = last.saturating_sub(first) / spec.count as u64;
    let longest = spec.kinds.iter().map(|k| spec.span_periods(*k)).max().unwrap_or(1);
    if slot < longest + 2 {
        return Err(format!(
            "{} windows in [{}, {}) s leave {slot} periods each: at least {} needed (the longest window and two clean periods)",
            spec.count,
            spec.from_s,
            spec.to_s,
            longest + 2
        ));
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(spec.seed);
    const SIGNALS: [Signal; 5] = [Signal::Theta1, Signal::Elbow, Signal::FT, Signal::FN, Signal::Belt];
    let period_us = (ts * 1e6).round() as u64;
    let mut faults = Vec::with_capacity(spec.count);
    for i in 0..spec.count as u64 {
        let kind = spec.kinds[rng.random_range(0..spec.kinds.len())];
        let (periods, delay_s, duration_s) = match kind {
            FaultKind::LateCommand if rng.random::<bool>() => {
                let us = rng.random_range(period_us..=3 * period_us);
                (rng.random_range(1..=spec.max_in_a_row), us as f64 * 1e-6, None)
            }
            FaultKind::LateCommand => {
                let us = rng.random_range(1..period_us.max(2));
                (rng.random_range(1..=spec.max_window), us as f64 * 1e-6, None)
            }
            FaultKind::NanSensor | FaultKind::OutOfRange => (rng.random_range(1..=spec.max_in_a_row), 0.0, None),
            FaultKind::Stall => {
                let n = rng.random_range(0..=spec.max_stall_timeouts);
                (1, 0.0, Some((f64::from(n) + 0.5) * spec.command_timeout_s))
            }
            _ => (rng.random_range(1..=spec.max_window), 0.0, None),
        };
        let start = first + i * slot + rng.random_range(0..=slot - spec.span_periods(kind) - 2);
        let signal = matches!(kind, FaultKind::StuckSensor | FaultKind::NanSensor | FaultKind::OutOfRange)
            .then(|| SIGNALS[rng.random_range(0..SIGNALS.len())]);
        faults.push(Fault { delay_s, signal, ..Fault::new(kind, start as f64 * ts, duration_s.unwrap_or(f64::from(periods) * ts)) });
    }
    Ok(faults)
}

#[cfg(test)]
#[path = "faults_tests.rs"]
mod tests;
