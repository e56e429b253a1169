//! Faults the rig injects (docs/hardware.md "Faults"),
//! as listed in a scenario's `[[faults]]` tables. Each fault acts over a window
//! of sample times `[at_s, at_s + duration_s)`; where it acts (plant side, wire,
//! firmware side) is part of its definition, so that the in-process and the
//! iceoryx2 loops inject it at the same place.

use serde::{Deserialize, Serialize};

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
}

impl Fault {
    /// Whether sample time `t` (s) is in the window (at least the period at `at_s`).
    pub fn active(&self, t: f64, ts: f64) -> bool {
        t >= self.at_s - 0.5 * ts && t < self.at_s + self.duration_s.max(ts) - 0.5 * ts
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
        if self.kind == FaultKind::LateCommand && !(self.delay_s.is_finite() && self.delay_s > 0.0 && self.delay_s < 10.0) {
            return Err(format!("delay_s = {}: a delay in (0, 10) s", self.delay_s));
        }
        if self.kind == FaultKind::Stall && !(self.duration_s > 0.0 && self.duration_s <= 60.0) {
            return Err(format!("duration_s = {}: a stall of (0, 60] s of wall time", self.duration_s));
        }
        Ok(())
    }
}

/// The faults of a run, queried per period.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultPlan {
    faults: Vec<Fault>,
    ts: f64,
}

impl FaultPlan {
    /// The plan of `faults` at sampling period `ts` (s).
    pub fn new(faults: &[Fault], ts: f64) -> Self {
        Self { faults: faults.to_vec(), ts }
    }

    /// Faults of `kind` active at sample time `t`.
    pub fn active(&self, kind: FaultKind, t: f64) -> impl Iterator<Item = &Fault> {
        self.faults.iter().filter(move |f| f.kind == kind && f.active(t, self.ts))
    }

    /// How late the firmware's step starts at sample time `t`, s (0 when on time).
    pub fn command_delay(&self, t: f64) -> f64 {
        self.active(FaultKind::LateCommand, t).map(|f| f.delay_s).fold(0.0, f64::max)
    }

    /// Whether the command of sample time `t` is lost on the wire.
    pub fn drops_command(&self, t: f64) -> bool {
        self.active(FaultKind::DropCommand, t).next().is_some()
    }

    /// The wall-clock stall (s) that starts at sample time `t`, if one does.
    pub fn stall_starting(&self, t: f64) -> Option<f64> {
        self.faults.iter().find(|f| f.kind == FaultKind::Stall && (t - f.at_s).abs() < 0.5 * self.ts).map(|f| f.duration_s)
    }

    /// Whether the firmware process is killed at sample time `t`.
    pub fn kills_firmware_at(&self, t: f64) -> bool {
        self.faults.iter().any(|f| f.kind == FaultKind::KillFirmware && (t - f.at_s).abs() < 0.5 * self.ts)
    }

    /// The sensor faults active at sample time `t`.
    pub fn sensor_faults(&self, t: f64) -> impl Iterator<Item = (FaultKind, Signal)> {
        self.faults.iter().filter(move |f| f.active(t, self.ts)).filter_map(|f| match f.kind {
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
            Self::InProcess | Self::PilSerial => &EVERYWHERE,
        }
    }

    /// Refuses a scenario fault this link cannot inject.
    ///
    /// # Errors
    /// [`RunError::Unsupported`] naming the first such fault, why, and what to use instead.
    pub fn check(self, faults: &[Fault]) -> Result<(), RunError> {
        let Some(f) = faults.iter().find(|f| !self.injectable().contains(&f.kind)) else { return Ok(()) };
        Err(RunError::Unsupported(match (f.kind, self) {
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
            (kind, link) => format!("fault {kind:?} cannot be injected over the {link:?} link"),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_cover_whole_periods() {
        let f = Fault { kind: FaultKind::DropCommand, at_s: 0.5, duration_s: 0.003, delay_s: 0.0, signal: None };
        let ts = 1e-3;
        let hits: Vec<u32> = (0..1000).filter(|k| f.active(*k as f64 * ts, ts)).collect();
        assert_eq!(hits, [500, 501, 502]);
        let one = Fault { duration_s: 0.0, ..f };
        let hits: Vec<u32> = (0..1000).filter(|k| one.active(*k as f64 * ts, ts)).collect();
        assert_eq!(hits, [500]);
    }

    #[test]
    fn checks_name_the_problem() {
        let f = Fault { kind: FaultKind::StuckSensor, at_s: 1.0, duration_s: 1.0, delay_s: 0.0, signal: None };
        assert!(f.check().unwrap_err().contains("signal"));
        let f = Fault { kind: FaultKind::LateCommand, at_s: 1.0, duration_s: 0.0, delay_s: f64::NAN, signal: None };
        assert!(f.check().unwrap_err().contains("delay_s"));
        // Regression (fuzzing): a fault that does not use its delay still gets a sane one.
        for delay_s in [f64::NAN, f64::INFINITY, -1.0, 10.0] {
            let f = Fault { kind: FaultKind::StuckSensor, at_s: 1.0, duration_s: 0.0, delay_s, signal: Some(Signal::FN) };
            assert!(f.check().unwrap_err().contains("delay_s"), "{delay_s}");
        }
        let f = Fault { kind: FaultKind::StuckSensor, at_s: 1.0, duration_s: 0.0, delay_s: 0.0, signal: Some(Signal::FN) };
        assert_eq!(f.check(), Ok(()));
    }

    /// Each link refuses exactly the faults it cannot inject, in one table: the
    /// firmware in its own process takes them all; QEMU can be killed but not
    /// stalled; in-process and a board behind a serial port take neither.
    #[test]
    fn links_refuse_exactly_what_they_cannot_inject() {
        use FaultKind::*;
        let all = [LateCommand, DropCommand, Stall, KillFirmware, StuckSensor, NanSensor, OutOfRange];
        let fault = |kind| Fault { kind, at_s: 1.0, duration_s: 0.5, delay_s: 1e-3, signal: None };
        for link in [LinkKind::InProcess, LinkKind::Ipc, LinkKind::PilQemu, LinkKind::PilSerial] {
            for kind in all {
                let refused = link.check(&[fault(kind)]).is_err();
                let process_fault = matches!(kind, Stall | KillFirmware);
                let expected = match link {
                    LinkKind::Ipc => false,
                    LinkKind::PilQemu => kind == Stall,
                    LinkKind::InProcess | LinkKind::PilSerial => process_fault,
                };
                assert_eq!(refused, expected, "{link:?} {kind:?}");
            }
        }
        let e = LinkKind::InProcess.check(&[fault(Stall)]).unwrap_err().to_string();
        assert!(e.contains("Stall") && e.contains("--in-process"), "{e}");
    }
}
