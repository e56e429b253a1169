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

mod link_kind;
mod schedule;

pub use link_kind::LinkKind;
pub use schedule::{RandomSchedule, random_schedule};

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

#[cfg(test)]
mod tests;
