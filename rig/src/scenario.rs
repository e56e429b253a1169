//! Scenario files (TOML): the plant, the controller, timing and sensor models of
//! one run. Unknown keys and out-of-range values are errors naming the key.

use serde::{Deserialize, Serialize};

use firmware::{ControllerKind, config::FrictionCompensation};
use plant::{
    impact::{ImpactLaw, IwcRule},
    initial::PaperX0,
};
use shared::Period;

use super::faults::Fault;

/// The embedded default scenario (`scenarios/default.toml`).
pub const DEFAULT_TOML: &str = include_str!("../../scenarios/default.toml");

/// The plant section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlantSection {
    /// Friction coefficient `mu`.
    pub mu: f64,
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Initial condition: `a`, `d` or `u`.
    pub x0: PaperX0,
    /// Impact law.
    pub impact_law: ImpactLaw,
    /// Restitution coefficient.
    pub e_n: f64,
    /// What an impact without collision leaves behind: `restitution` (default) or
    /// `plastic` (docs/plant.md "Impact without collision").
    #[serde(default)]
    pub iwc: IwcRule,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Integrator absolute tolerance.
    pub atol: f64,
}

/// The controller section (the firmware's configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSection {
    /// `hybrid` or `pid`.
    pub kind: ControllerKind,
    /// Tangential target `z_t*`, m.
    pub target_z_t: f64,
    /// Duration of the move, s.
    pub move_time_s: f64,
    /// Normal force reference, N.
    pub f_n_ref: f64,
    /// Hybrid force-integral gain `K'_I`, 1/s.
    pub hybrid_ki: f64,
    /// Friction term: `commanded`, `measured_normal`, `measured` or `none`.
    pub friction: FrictionCompensation,
    /// The firmware's friction estimate `mu_hat`.
    pub mu_hat: f64,
}

/// The timing section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimingSection {
    /// Control rate, Hz (250 to 10 000).
    pub rate_hz: f64,
    /// Delay from sampling to the command taking effect, s (< one period).
    pub delta_s: f64,
    /// Run length, s.
    pub duration_s: f64,
}

impl TimingSection {
    /// The lowest and highest control rates, Hz (docs/hardware.md "Timing").
    pub const RATE_RANGE_HZ: (f64, f64) = (250.0, 10_000.0);

    /// The control period both sides of the wire use: `rate_hz` rounded once to
    /// whole microseconds ([`Period::from_rate_hz`]; 6 kHz runs at 167 us). A
    /// rate outside [`Self::RATE_RANGE_HZ`], which [`Scenario::validate`]
    /// rejects, is first clamped into it (NaN to the lowest rate), so the loop
    /// never runs on an unvalidated period.
    pub fn period(&self) -> Period {
        let (lo, hi) = Self::RATE_RANGE_HZ;
        let rate = if self.rate_hz.is_nan() { lo } else { self.rate_hz.clamp(lo, hi) };
        // Within the range the period is 100 to 4000 us: always a Period.
        Period::from_rate_hz(rate).unwrap_or(Period::MILLISECOND)
    }

    /// Control periods in the run: `duration_s / period`, rounded.
    pub fn periods(&self) -> u64 {
        (self.duration_s / self.period().as_secs_f64()).round() as u64
    }
}

/// The sensor-model section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSection {
    /// Seed of the noise generator.
    pub seed: u64,
    /// Load-cell white noise, N rms.
    pub load_noise_n: f64,
}

/// The rig section: how the plant and firmware processes wait for each other.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigSection {
    /// Lockstep: wall-clock time the plant waits for a period's command before it
    /// counts a deadline miss (a stalled or dead firmware), s.
    pub command_timeout_s: f64,
    /// Bounded spin before a blocking wait, microseconds of wall time.
    pub spin_us: f64,
    /// Wall-clock time without a frame after which the firmware process checks
    /// whether the plant is alive (and, if not, enters its safe state), s.
    pub peer_check_s: f64,
    /// Consecutive command timeouts after which the plant gives the firmware up
    /// as dead even if its process still runs.
    pub max_consecutive_timeouts: u32,
    /// Real time: the CPU both processes run their control loop on: `"last"` (the
    /// last CPU the process may use), `"none"` (no pinning) or a CPU number. On
    /// one CPU the plant hands the core to the firmware when it publishes a frame
    /// and gets it back with the command, so the answer never waits for a sleeping
    /// core to wake up (on a virtual machine that can take milliseconds).
    pub realtime_cpu: String,
    /// Real time: `SCHED_FIFO` priority of both control loops (1 to 99), or 0 for
    /// the normal scheduler. Neither loop busy-waits for long, so the kernel's
    /// real-time throttling never applies; without the privilege the run goes on
    /// under the normal scheduler and says so.
    pub realtime_fifo_priority: u8,
}

/// What [`RigSection::realtime_cpu`] accepts.
pub const REALTIME_CPU_FORMS: &str = "\"last\", \"none\" or a CPU number below 1024";

/// Where a real-time control loop runs ([`RigSection::realtime_cpu`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CpuPin {
    /// Not pinned.
    None,
    /// The last CPU of the process's affinity mask.
    Last,
    /// This CPU.
    Cpu(usize),
}

impl RigSection {
    /// The parsed `realtime_cpu`.
    ///
    /// # Errors
    /// A message naming the accepted forms when it is none of them.
    pub fn realtime_pin(&self) -> Result<CpuPin, &'static str> {
        match self.realtime_cpu.trim() {
            "none" => Ok(CpuPin::None),
            "last" => Ok(CpuPin::Last),
            n => n.parse::<usize>().ok().filter(|&c| c < 1024).map(CpuPin::Cpu).ok_or(REALTIME_CPU_FORMS),
        }
    }
}

impl Default for RigSection {
    fn default() -> Self {
        Self {
            command_timeout_s: 0.05,
            spin_us: 200.0,
            peer_check_s: 0.5,
            max_consecutive_timeouts: 100,
            realtime_cpu: "last".into(),
            realtime_fifo_priority: 10,
        }
    }
}

/// One run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Name, for outputs.
    pub name: String,
    /// Plant.
    pub plant: PlantSection,
    /// Controller.
    pub controller: ControllerSection,
    /// Timing.
    pub timing: TimingSection,
    /// Sensors.
    pub sensors: SensorSection,
    /// Rig (inter-process waiting); defaults when absent.
    #[serde(default)]
    pub rig: RigSection,
    /// Injected faults (`[[faults]]` tables); none when absent.
    #[serde(default)]
    pub faults: Vec<Fault>,
}

/// Why a scenario was rejected.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// Not valid TOML, or keys unknown, missing or of the wrong type.
    #[error("{0}")]
    Parse(String),
    /// A value out of range.
    #[error("scenario key `{key}` = {value}: {expected}")]
    OutOfRange {
        /// Dotted key.
        key: &'static str,
        /// The value as written.
        value: String,
        /// What is allowed.
        expected: &'static str,
    },
    /// A `[[faults]]` entry is invalid.
    #[error("scenario key `faults[{index}]`: {what}")]
    Fault {
        /// Index of the entry (0-based, in file order).
        index: usize,
        /// What is wrong, naming the key and value.
        what: String,
    },
}

impl Scenario {
    /// The embedded default scenario.
    pub fn default_scenario() -> Self {
        // The embedded file is checked by a test; a parse failure here is a build defect.
        Self::from_toml(DEFAULT_TOML).unwrap_or_else(|e| panic!("embedded default scenario is invalid: {e}"))
    }

    /// Parses and validates a scenario.
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] (with the key and line from the TOML parser) or
    /// [`ScenarioError::OutOfRange`] naming the key and value.
    pub fn from_toml(text: &str) -> Result<Self, ScenarioError> {
        // The path names the key of a bad value (`controller.kind`), the TOML error its line.
        let de = toml::de::Deserializer::parse(text).map_err(|e| ScenarioError::Parse(e.to_string()))?;
        let s: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            if path == "." {
                ScenarioError::Parse(inner.to_string())
            } else {
                ScenarioError::Parse(format!("scenario key `{path}`: {inner}"))
            }
        })?;
        s.validate()?;
        Ok(s)
    }

    /// Checks ranges.
    ///
    /// # Errors
    /// [`ScenarioError::OutOfRange`] naming the first bad key.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let bad = |key: &'static str, value: String, expected: &'static str| Err(ScenarioError::OutOfRange { key, value, expected });
        let finite = |x: f64| x.is_finite();
        let p = &self.plant;
        if !(finite(p.mu) && p.mu >= 0.0) {
            return bad("plant.mu", p.mu.to_string(), "a finite value >= 0");
        }
        if !finite(p.v_belt) || p.v_belt.abs() > 5.0 {
            return bad("plant.v_belt", p.v_belt.to_string(), "a finite speed within +-5 m/s");
        }
        if !(finite(p.e_n) && (0.0..=1.0).contains(&p.e_n)) {
            return bad("plant.e_n", p.e_n.to_string(), "a value in [0, 1]");
        }
        for (key, v) in [("plant.rtol", p.rtol), ("plant.atol", p.atol)] {
            if !(finite(v) && v > 0.0 && v <= 0.1) {
                return bad(key, v.to_string(), "a value in (0, 0.1]");
            }
        }
        let c = &self.controller;
        if !(finite(c.target_z_t) && c.target_z_t.abs() < 0.42) {
            return bad("controller.target_z_t", c.target_z_t.to_string(), "a finite position within the arm's reach (|z_t*| < 2 l)");
        }
        for (key, v) in [("controller.move_time_s", c.move_time_s)] {
            if !(finite(v) && v > 0.0) {
                return bad(key, v.to_string(), "a finite value > 0");
            }
        }
        for (key, v) in [("controller.f_n_ref", c.f_n_ref), ("controller.hybrid_ki", c.hybrid_ki), ("controller.mu_hat", c.mu_hat)] {
            if !(finite(v) && v >= 0.0) {
                return bad(key, v.to_string(), "a finite value >= 0");
            }
        }
        let t = &self.timing;
        if !(finite(t.rate_hz) && (TimingSection::RATE_RANGE_HZ.0..=TimingSection::RATE_RANGE_HZ.1).contains(&t.rate_hz)) {
            return bad("timing.rate_hz", t.rate_hz.to_string(), "250 to 10000 Hz (docs/hardware.md)");
        }
        if !(finite(t.delta_s) && t.delta_s >= 0.0 && t.delta_s < t.period().as_secs_f64()) {
            return bad("timing.delta_s", t.delta_s.to_string(), "in [0, one period)");
        }
        if !(finite(t.duration_s) && t.duration_s > 0.0 && t.duration_s <= 1e5) {
            return bad("timing.duration_s", t.duration_s.to_string(), "in (0, 1e5] s");
        }
        if !(finite(self.sensors.load_noise_n) && self.sensors.load_noise_n >= 0.0) {
            return bad("sensors.load_noise_n", self.sensors.load_noise_n.to_string(), "a finite value >= 0");
        }
        let r = &self.rig;
        if !(finite(r.command_timeout_s) && r.command_timeout_s > 0.0 && r.command_timeout_s <= 60.0) {
            return bad("rig.command_timeout_s", r.command_timeout_s.to_string(), "in (0, 60] s");
        }
        if !(finite(r.spin_us) && (0.0..=1e6).contains(&r.spin_us)) {
            return bad("rig.spin_us", r.spin_us.to_string(), "in [0, 1e6] us");
        }
        if !(finite(r.peer_check_s) && r.peer_check_s > 0.0 && r.peer_check_s <= 60.0) {
            return bad("rig.peer_check_s", r.peer_check_s.to_string(), "in (0, 60] s");
        }
        if r.max_consecutive_timeouts == 0 {
            return bad("rig.max_consecutive_timeouts", "0".into(), ">= 1");
        }
        if let Err(want) = r.realtime_pin() {
            return bad("rig.realtime_cpu", format!("{:?}", r.realtime_cpu), want);
        }
        if r.realtime_fifo_priority > 99 {
            return bad("rig.realtime_fifo_priority", r.realtime_fifo_priority.to_string(), "0 (normal scheduler) or 1 to 99");
        }
        for (i, f) in self.faults.iter().enumerate() {
            if let Err(what) = f.check() {
                return Err(ScenarioError::Fault { index: i, what });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_default_parses_and_matches_the_issue() {
        let s = Scenario::from_toml(DEFAULT_TOML).unwrap();
        assert_eq!((s.plant.mu, s.plant.v_belt, s.plant.x0), (0.6, -0.4, PaperX0::D));
        assert_eq!((s.controller.kind, s.controller.target_z_t, s.controller.f_n_ref), (ControllerKind::Hybrid, 0.10, 10.0));
        assert_eq!((s.timing.rate_hz, s.timing.duration_s), (1000.0, 10.0));
    }

    #[test]
    fn errors_name_the_bad_key_and_value() {
        let bad_key = DEFAULT_TOML.replace("mu = 0.6\n", "mu = 0.6\nmuu = 1\n");
        let e = Scenario::from_toml(&bad_key).unwrap_err().to_string();
        assert!(e.contains("muu"), "{e}");
        let bad_value = DEFAULT_TOML.replace("rate_hz = 1000.0", "rate_hz = 50.0");
        let e = Scenario::from_toml(&bad_value).unwrap_err().to_string();
        assert!(e.contains("timing.rate_hz") && e.contains("50"), "{e}");
        let bad_type = DEFAULT_TOML.replace("e_n = 0.2", "e_n = \"high\"");
        let e = Scenario::from_toml(&bad_type).unwrap_err().to_string();
        assert!(e.contains("e_n"), "{e}");
        let bad_fault = format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"stuck_sensor\"\nat_s = 1.0\n");
        let e = Scenario::from_toml(&bad_fault).unwrap_err().to_string();
        assert!(e.contains("faults[0]") && e.contains("signal"), "{e}");
        let bad_fault_kind = format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"gremlins\"\nat_s = 1.0\n");
        let e = Scenario::from_toml(&bad_fault_kind).unwrap_err().to_string();
        assert!(e.contains("gremlins"), "{e}");
        let bad_kind = DEFAULT_TOML.replace("kind = \"hybrid\"", "kind = \"lqr\"");
        assert!(Scenario::from_toml(&bad_kind).unwrap_err().to_string().contains("controller.kind"));
        let bad_cpu = DEFAULT_TOML.replace("realtime_cpu = \"last\"", "realtime_cpu = \"first\"");
        let e = Scenario::from_toml(&bad_cpu).unwrap_err().to_string();
        assert!(e.contains("rig.realtime_cpu") && e.contains("first"), "{e}");
        let bad_prio = DEFAULT_TOML.replace("realtime_fifo_priority = 10", "realtime_fifo_priority = 100");
        let e = Scenario::from_toml(&bad_prio).unwrap_err().to_string();
        assert!(e.contains("rig.realtime_fifo_priority") && e.contains("100"), "{e}");
    }

    #[test]
    fn realtime_cpu_accepts_last_none_and_numbers() {
        let pin = |v: &str| RigSection { realtime_cpu: v.into(), ..RigSection::default() }.realtime_pin();
        assert_eq!(pin("last"), Ok(CpuPin::Last));
        assert_eq!(pin("none"), Ok(CpuPin::None));
        assert_eq!(pin("3"), Ok(CpuPin::Cpu(3)));
        assert!(pin("-1").is_err() && pin("1024").is_err() && pin("").is_err());
    }
}
