//! Scenario files (TOML): the plant, the controller, timing and sensor models of
//! one run. Unknown keys and out-of-range values are errors naming the key.
//!
//! The arm's parameters (paper Table I) and the controller's gains (paper eqs. 8
//! to 11) are optional keys whose defaults are the paper's values
//! ([`shared::Params::paper`], [`firmware::Config::default`]). A scenario can be
//! changed key by key before it is read ([`Scenario::from_toml_with`] and
//! [`crate::overrides`], the command line's `--set KEY=VALUE`).

use serde::{Deserialize, Serialize};

use firmware::{ControllerKind, config::FrictionCompensation};
use plant::{
    impact::{ImpactLaw, IwcRule},
    initial::PaperX0,
};
use shared::{ParamError, Params, Period};

use super::faults::Fault;
use super::overrides::{self, Override};

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
    /// Mass of each link `m`, kg (paper Table I: 0.12; optional).
    #[serde(default = "paper::m")]
    pub m: f64,
    /// Length of each link `l`, m (paper Table I: 0.21; optional).
    #[serde(default = "paper::l")]
    pub l: f64,
    /// Joint damping `sigma`, N m s/rad (paper Table I: 0.005; optional).
    #[serde(default = "paper::sigma")]
    pub sigma: f64,
    /// Stiffness of the spring between the links `k`, N m/rad (paper Table I: 1.3; optional).
    #[serde(default = "paper::k")]
    pub k: f64,
    /// Height of the base joint above the belt `H`, m (paper Table I: 0.3775; optional).
    #[serde(default = "paper::h")]
    pub h: f64,
    /// Spring rest angle `alpha0`, radians (paper Table I: 13.72 degrees; optional).
    #[serde(default = "paper::alpha0")]
    pub alpha0: f64,
    /// Gravity `g`, m/s^2 (paper Table I: 9.81; optional).
    #[serde(default = "paper::g")]
    pub g: f64,
}

/// The keys of `[plant]` (and `[controller.model]`) that hold the arm's
/// parameters of paper Table I, in [`Params`] order: `m`, `l`, `sigma`, `k`, `h`,
/// `alpha0`, `g`.
pub const ARM_KEYS: [&str; 7] = ["m", "l", "sigma", "k", "h", "alpha0", "g"];

/// Defaults of the optional keys: paper Table I ([`Params::paper`]) and the
/// paper's gains ([`firmware::Config::default`], eqs. 8 to 11).
mod paper {
    use shared::Params;

    fn p() -> Params<f64> {
        Params::paper()
    }
    pub(super) fn m() -> f64 {
        p().m
    }
    pub(super) fn l() -> f64 {
        p().l
    }
    pub(super) fn sigma() -> f64 {
        p().sigma
    }
    pub(super) fn k() -> f64 {
        p().k
    }
    pub(super) fn h() -> f64 {
        p().h
    }
    pub(super) fn alpha0() -> f64 {
        p().alpha0
    }
    pub(super) fn g() -> f64 {
        p().g
    }
}

impl PlantSection {
    /// The plant's parameters: paper Table I as the scenario sets it, with its
    /// `mu` and `v_belt` (not validated; [`Scenario::validate`] checks them).
    pub fn params(&self) -> Params<f64> {
        Params {
            m: self.m,
            l: self.l,
            sigma: self.sigma,
            k: self.k,
            h: self.h,
            alpha0: self.alpha0,
            g: self.g,
            mu: self.mu,
            v_belt: self.v_belt,
        }
    }
}

/// `[controller.model]`: the arm as the firmware models it, when it is not the
/// plant (a deliberate mismatch). Every key is optional and defaults to the
/// plant's value (`[plant]`); the firmware's `mu` is always `controller.mu_hat`
/// and its `v_belt` the plant's. Units as in `[plant]` (SI, radians).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    /// Mass of each link `m`, kg (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub m: Option<f64>,
    /// Length of each link `l`, m (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub l: Option<f64>,
    /// Joint damping `sigma`, N m s/rad (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// Spring stiffness `k`, N m/rad (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// Base height `H`, m (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub h: Option<f64>,
    /// Spring rest angle `alpha0`, radians (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha0: Option<f64>,
    /// Gravity `g`, m/s^2 (paper Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g: Option<f64>,
}

impl ModelSection {
    /// The keys' values in [`ARM_KEYS`] order (`None`: not set).
    pub fn values(&self) -> [Option<f64>; 7] {
        [self.m, self.l, self.sigma, self.k, self.h, self.alpha0, self.g]
    }

    /// `plant` with the keys this section sets replaced.
    pub fn over(&self, plant: Params<f64>) -> Params<f64> {
        Params {
            m: self.m.unwrap_or(plant.m),
            l: self.l.unwrap_or(plant.l),
            sigma: self.sigma.unwrap_or(plant.sigma),
            k: self.k.unwrap_or(plant.k),
            h: self.h.unwrap_or(plant.h),
            alpha0: self.alpha0.unwrap_or(plant.alpha0),
            g: self.g.unwrap_or(plant.g),
            ..plant
        }
    }
}

/// `[controller.pid]`: the PID's gains per joint of `q' = [theta1, theta2 - theta1]`
/// (paper eq. 8), each `[joint 1, joint 2]`. Optional; the defaults are the
/// paper's (`K_P,1 = 200`, `K_I,1 = 25`, `K_D,1 = 2`, joint-2 gains 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PidSection {
    /// `[K_P,1, K_P,2]`, N m/rad.
    pub kp: [f64; 2],
    /// `[K_I,1, K_I,2]`, N m/(rad s).
    pub ki: [f64; 2],
    /// `[K_D,1, K_D,2]`, N m s/rad.
    pub kd: [f64; 2],
}

impl Default for PidSection {
    /// The paper's gains (eq. 8), as in [`firmware::Config::default`].
    fn default() -> Self {
        let g = firmware::Config::default().pid;
        let f = |v: [f32; 2]| v.map(f64::from);
        Self { kp: f(g.kp), ki: f(g.ki), kd: f(g.kd) }
    }
}

/// `[controller.hybrid]`: the hybrid force/motion law's gains (paper eqs. 9 to
/// 11). Optional; the defaults are the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HybridSection {
    /// `K'_P`, 1/s^2 (paper eq. 10: 900).
    pub kp: f64,
    /// `K'_D`, 1/s (paper eq. 10: 900).
    pub kd: f64,
    /// `K'_I`, 1/s (paper eq. 11). Absent: the paper's, which depends on the
    /// initial condition ([`paper_hybrid_ki`]: 650 from `x0a` and `x0d`, 0 from
    /// `x0u`). The old key `controller.hybrid_ki` is read as this one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ki: Option<f64>,
}

impl Default for HybridSection {
    /// The paper's `K'_P` and `K'_D` ([`firmware::Config::default`]); `K'_I` by initial condition.
    fn default() -> Self {
        let g = firmware::Config::default().hybrid;
        Self { kp: f64::from(g.kp), kd: f64::from(g.kd), ki: None }
    }
}

/// The paper's `K'_I` of the hybrid law from initial condition `x0`, 1/s: 0 from
/// `x0u`, 650 otherwise (docs/model.md, experiment 6). The default of
/// `controller.hybrid.ki`.
pub fn paper_hybrid_ki(x0: PaperX0) -> f64 {
    match x0 {
        PaperX0::U => 0.0,
        PaperX0::A | PaperX0::D => f64::from(firmware::Config::default().hybrid.ki),
    }
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
    /// Friction term: `commanded`, `measured_normal`, `measured` or `none`.
    pub friction: FrictionCompensation,
    /// The firmware's friction estimate `mu_hat`.
    pub mu_hat: f64,
    /// PID gains (paper eq. 8); the paper's when absent.
    #[serde(default)]
    pub pid: PidSection,
    /// Hybrid gains (paper eqs. 9 to 11); the paper's when absent.
    #[serde(default)]
    pub hybrid: HybridSection,
    /// The arm as the firmware models it, when it differs from the plant
    /// (`[controller.model]`); absent: the firmware knows the plant's parameters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<ModelSection>,
}

impl ControllerSection {
    /// `K'_I` as run from initial condition `x0`, 1/s: `hybrid.ki`, or the paper's
    /// ([`paper_hybrid_ki`]) when it is absent.
    pub fn hybrid_ki(&self, x0: PaperX0) -> f64 {
        self.hybrid.ki.unwrap_or_else(|| paper_hybrid_ki(x0))
    }
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
    /// Resolution of both joint encoders, bits per revolution (10 to 16; the
    /// reference board's 14 by default). The firmware is configured with the same.
    #[serde(default = "default_encoder_bits")]
    pub encoder_bits: u8,
}

fn default_encoder_bits() -> u8 {
    shared::wire::ENCODER_BITS
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
    /// Wall-clock time the plant waits for the firmware to connect before the run
    /// fails with a hint (a spawned firmware, or one started by hand for
    /// `--attach`), s (0 to 600).
    pub connect_timeout_s: f64,
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
            connect_timeout_s: 20.0,
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
    /// The board twin's physical truth (`run --link twin`): the reference board
    /// when absent (and then not written back, so that outputs of scenarios
    /// without it are unchanged).
    #[serde(default, skip_serializing_if = "is_default")]
    pub board: board_twin::BoardDescription,
    /// The firmware's calibration of the board (`run --link twin`): the reference
    /// board's when absent (not written back then).
    #[serde(default, skip_serializing_if = "is_default")]
    pub calibration: crate::calibration::CalibrationSection,
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

/// Why a scenario was rejected.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// Not valid TOML, or keys unknown, missing or of the wrong type.
    #[error("{0}")]
    Parse(String),
    /// A value out of range.
    #[error("scenario key `{key}` = {value} is out of range: expected {expected}")]
    OutOfRange {
        /// Dotted key.
        key: String,
        /// The value as written.
        value: String,
        /// What is allowed.
        expected: String,
    },
    /// The `[board]` or `[calibration]` table is invalid (the message names the key).
    #[error("scenario key {0}")]
    Board(String),
    /// A `[[faults]]` entry is invalid.
    #[error("scenario key `faults[{index}]`: {what}")]
    Fault {
        /// Index of the entry (0-based, in file order).
        index: usize,
        /// What is wrong, naming the key and value.
        what: String,
    },
    /// A `--set KEY=VALUE` override is malformed, names no key this command
    /// takes, or contradicts a flag ([`crate::overrides`]).
    #[error("{0}")]
    Override(#[from] overrides::OverrideError),
}

/// `Err(OutOfRange)` for `key` unless `ok`.
fn check(ok: bool, key: &str, value: impl std::fmt::Display, expected: &str) -> Result<(), ScenarioError> {
    if ok { Ok(()) } else { Err(ScenarioError::OutOfRange { key: key.into(), value: value.to_string(), expected: expected.into() }) }
}

/// Checks the arm's parameters of paper Table I under the key prefix `prefix`
/// (`plant` or `controller.model`): `m`, `l`, `h`, `g` finite and > 0; `sigma`,
/// `k` finite and >= 0; `alpha0` finite; `h < 2 l` (the belt within reach); then
/// [`Params::validate`].
///
/// # Errors
/// [`ScenarioError::OutOfRange`] naming the first bad key (`plant.m`) and its value.
pub fn validate_arm(prefix: &str, p: &Params<f64>) -> Result<(), ScenarioError> {
    let key = |name: &str| format!("{prefix}.{name}");
    for (name, v) in [("m", p.m), ("l", p.l), ("h", p.h), ("g", p.g)] {
        check(v.is_finite() && v > 0.0, &key(name), v, "a finite value > 0")?;
    }
    for (name, v) in [("sigma", p.sigma), ("k", p.k)] {
        check(v.is_finite() && v >= 0.0, &key(name), v, "a finite value >= 0")?;
    }
    check(p.alpha0.is_finite(), &key("alpha0"), p.alpha0, "a finite angle, rad")?;
    check(p.h < 2.0 * p.l, &key("h"), p.h, &format!("a base height below the arm's reach 2 l = {} m", 2.0 * p.l))?;
    p.validate().map_err(|e| ScenarioError::Parse(format!("scenario key `{prefix}`: {e}")))
}

/// Checks gains: each finite and >= 0, and finite in the firmware's f32 (at most
/// 3.4e38), named `key`.
fn validate_gains(key: &str, v: &[f64]) -> Result<(), ScenarioError> {
    let ok = v.iter().all(|g| g.is_finite() && *g >= 0.0 && (*g as f32).is_finite());
    let shown = if v.len() == 1 { v[0].to_string() } else { format!("[{}]", v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ")) };
    check(ok, key, shown, if v.len() == 1 { "a finite gain >= 0, at most 3.4e38" } else { "finite gains >= 0, at most 3.4e38" })
}

impl Scenario {
    /// Longest scenario name, characters (it names files and the rig's outputs).
    pub const MAX_NAME_CHARS: usize = 64;
    /// Most `[[faults]]` in one scenario.
    pub const MAX_FAULTS: usize = 1000;
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
        Self::from_toml_with(text, &[])
    }

    /// Parses a scenario, applies `overrides` to its TOML document (each
    /// `--set KEY=VALUE` replaces or adds the value at its dotted key path), then
    /// reads and validates it. The old key `controller.hybrid_ki` is read as
    /// `controller.hybrid.ki`.
    ///
    /// # Errors
    /// As [`Self::from_toml`]; an error caused by an override names it
    /// ([`ScenarioError::Override`], or the key and value of the bad key).
    pub fn from_toml_with(text: &str, overrides: &[Override]) -> Result<Self, ScenarioError> {
        let mut doc: toml::Table = toml::from_str(text).map_err(|e| toml_error(&e))?;
        // The file's old key first (an override of `controller.hybrid.ki` then
        // wins over it), then an override's.
        let mut migrated = migrate_legacy(&mut doc)?;
        overrides::apply(&mut doc, overrides)?;
        migrated |= migrate_legacy(&mut doc)?;
        let s: Scenario = if overrides.is_empty() && !migrated {
            // The text itself: the TOML errors give the line.
            let de = toml::de::Deserializer::parse(text).map_err(|e| toml_error(&e))?;
            read(de, &[])?
        } else {
            read(toml::Value::Table(doc), overrides)?
        };
        s.validate()?;
        Ok(s)
    }

    /// The scenario as a TOML table (for [`overrides::apply`]).
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] if it cannot be written as TOML.
    pub fn to_table(&self) -> Result<toml::Table, ScenarioError> {
        toml::Table::try_from(self).map_err(|e| ScenarioError::Parse(format!("cannot write the scenario as TOML: {e}")))
    }

    /// This scenario with `overrides` applied, validated.
    ///
    /// # Errors
    /// As [`Self::from_toml_with`].
    pub fn with_overrides(&self, overrides: &[Override]) -> Result<Self, ScenarioError> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let mut doc = self.to_table()?;
        overrides::apply(&mut doc, overrides)?;
        migrate_legacy(&mut doc)?;
        let s: Scenario = read(toml::Value::Table(doc), overrides)?;
        s.validate()?;
        Ok(s)
    }

    /// Checks ranges.
    ///
    /// # Errors
    /// [`ScenarioError::OutOfRange`] naming the first bad key.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let finite = |x: f64| x.is_finite();
        check(
            !self.name.is_empty() && self.name.chars().count() <= Self::MAX_NAME_CHARS && !self.name.chars().any(char::is_control),
            "name",
            // Debug-quoted: a control character shows as an escape, never reaches the terminal raw.
            format!("{:?}", self.name.chars().take(40).collect::<String>()),
            "1 to 64 characters, none a control character (it titles figures and terminal lines)",
        )?;
        check(self.faults.len() <= Self::MAX_FAULTS, "faults", self.faults.len(), "at most 1000 [[faults]]")?;
        let p = &self.plant;
        check(finite(p.mu) && (0.0..=10.0).contains(&p.mu), "plant.mu", p.mu, "a value in [0, 10]")?;
        check(finite(p.v_belt) && p.v_belt.abs() <= 5.0, "plant.v_belt", p.v_belt, "a finite speed within +-5 m/s")?;
        validate_arm("plant", &p.params())?;
        check(finite(p.e_n) && (0.0..=1.0).contains(&p.e_n), "plant.e_n", p.e_n, "a value in [0, 1]")?;
        for (key, v) in [("plant.rtol", p.rtol), ("plant.atol", p.atol)] {
            check(finite(v) && (1e-14..=0.1).contains(&v), key, v, "a value in [1e-14, 0.1]")?;
        }
        let c = &self.controller;
        let reach = 2.0 * p.l;
        check(
            finite(c.target_z_t) && c.target_z_t.abs() < reach,
            "controller.target_z_t",
            c.target_z_t,
            &format!("a finite position within the arm's reach (|z_t*| < 2 l = {reach} m)"),
        )?;
        check(
            finite(c.move_time_s) && c.move_time_s > 0.0 && c.move_time_s <= 1e5,
            "controller.move_time_s",
            c.move_time_s,
            "a value in (0, 1e5] s",
        )?;
        check(
            finite(c.f_n_ref) && (0.0..=25.0).contains(&c.f_n_ref),
            "controller.f_n_ref",
            c.f_n_ref,
            "a value in [0, 25] N (the load cell's range)",
        )?;
        check(finite(c.mu_hat) && (0.0..=10.0).contains(&c.mu_hat), "controller.mu_hat", c.mu_hat, "a value in [0, 10]")?;
        validate_gains("controller.pid.kp", &c.pid.kp)?;
        validate_gains("controller.pid.ki", &c.pid.ki)?;
        validate_gains("controller.pid.kd", &c.pid.kd)?;
        validate_gains("controller.hybrid.kp", &[c.hybrid.kp])?;
        validate_gains("controller.hybrid.kd", &[c.hybrid.kd])?;
        if let Some(ki) = c.hybrid.ki {
            validate_gains("controller.hybrid.ki", &[ki])?;
        }
        if let Some(model) = &c.model {
            let m = model.over(p.params());
            validate_arm("controller.model", &m)?;
            check(
                c.target_z_t.abs() < 2.0 * m.l,
                "controller.target_z_t",
                c.target_z_t,
                &format!("a position within the modelled arm's reach (|z_t*| < 2 controller.model.l = {} m)", 2.0 * m.l),
            )?;
        }
        // The firmware reads its model, the reference and the gains in f32
        // (crate::setup::firmware_config): they must hold there too, or a run would
        // stop at the firmware's configuration (found by the `scenario` fuzzing
        // harness, docs/fuzzing.md): beyond 3.4e38 is infinite in f32, a positive
        // value below 1.4e-45 is 0, and `h` or `z_t*` just under `2 l` round onto it.
        let model_section = c.model.unwrap_or_default();
        let model = model_section.over(p.params());
        let fw: Params<f32> = Params { mu: c.mu_hat, ..model }.cast();
        if let Err(e) = fw.validate() {
            let name = match e {
                ParamError::NonFinite { name, .. } | ParamError::NotPositive { name, .. } | ParamError::Negative { name, .. } => name,
                ParamError::TooLarge { name, .. } => name.trim_matches('|'),
                ParamError::BeltOutOfReach { .. } => "h",
            };
            let at = ARM_KEYS.iter().position(|k| *k == name);
            let from_model = at.is_some_and(|i| model_section.values()[i].is_some());
            let key = match (name, from_model) {
                ("mu", _) => "controller.mu_hat".to_string(),
                (_, true) => format!("controller.model.{name}"),
                (_, false) => format!("plant.{name}"),
            };
            let all = [model.m, model.l, model.sigma, model.k, model.h, model.alpha0, model.g];
            check(false, &key, at.map_or(c.mu_hat, |i| all[i]), &format!("a value the firmware's f32 model holds ({e})"))?;
        }
        check(
            (c.target_z_t as f32).abs() < 2.0 * fw.l,
            "controller.target_z_t",
            c.target_z_t,
            "a position within the reach in the firmware's f32 (|z_t*| < 2 l)",
        )?;
        check((c.move_time_s as f32) > 0.0, "controller.move_time_s", c.move_time_s, "a value the firmware's f32 holds (>= 1.4e-45 s)")?;
        let t = &self.timing;
        let (lo, hi) = TimingSection::RATE_RANGE_HZ;
        check(finite(t.rate_hz) && (lo..=hi).contains(&t.rate_hz), "timing.rate_hz", t.rate_hz, "250 to 10000 Hz (docs/hardware.md)")?;
        check(
            finite(t.delta_s) && t.delta_s >= 0.0 && t.delta_s < t.period().as_secs_f64(),
            "timing.delta_s",
            t.delta_s,
            "a value in [0, one period)",
        )?;
        check(
            finite(t.duration_s) && t.duration_s > 0.0 && t.duration_s <= 1e5,
            "timing.duration_s",
            t.duration_s,
            "a value in (0, 1e5] s",
        )?;
        let noise = self.sensors.load_noise_n;
        check(finite(noise) && (0.0..=25.0).contains(&noise), "sensors.load_noise_n", noise, "a value in [0, 25] N rms")?;
        let bits = self.sensors.encoder_bits;
        let (lo, hi) = shared::wire::ENCODER_BITS_RANGE;
        check((lo..=hi).contains(&bits), "sensors.encoder_bits", f64::from(bits), "10 to 16 bits")?;
        let r = &self.rig;
        check(
            finite(r.connect_timeout_s) && r.connect_timeout_s > 0.0 && r.connect_timeout_s <= 600.0,
            "rig.connect_timeout_s",
            r.connect_timeout_s,
            "a value in (0, 600] s",
        )?;
        check(
            finite(r.command_timeout_s) && r.command_timeout_s > 0.0 && r.command_timeout_s <= 60.0,
            "rig.command_timeout_s",
            r.command_timeout_s,
            "a value in (0, 60] s",
        )?;
        check(finite(r.spin_us) && (0.0..=1e6).contains(&r.spin_us), "rig.spin_us", r.spin_us, "a value in [0, 1e6] us")?;
        check(
            finite(r.peer_check_s) && r.peer_check_s > 0.0 && r.peer_check_s <= 60.0,
            "rig.peer_check_s",
            r.peer_check_s,
            "a value in (0, 60] s",
        )?;
        check(r.max_consecutive_timeouts >= 1, "rig.max_consecutive_timeouts", r.max_consecutive_timeouts, ">= 1")?;
        if let Err(want) = r.realtime_pin() {
            check(false, "rig.realtime_cpu", format!("{:?}", r.realtime_cpu), want)?;
        }
        check(r.realtime_fifo_priority <= 99, "rig.realtime_fifo_priority", r.realtime_fifo_priority, "0 (normal scheduler) or 1 to 99")?;
        for (i, f) in self.faults.iter().enumerate() {
            if let Err(what) = f.check() {
                return Err(ScenarioError::Fault { index: i, what });
            }
            // The rule the run applies (Fault::periods): a fault whose first period
            // is past the run's last never acts, even one within the run's last half
            // period in seconds.
            let (first, periods) = (f.periods(t.period()).start, t.periods());
            if first >= periods {
                let what = format!(
                    "at_s = {} acts from period {first} (t = {} s, the first sample time at or after at_s), but the run's last \
                     period is {} (t = {} s): it would never act",
                    f.at_s,
                    t.period().sample(first).as_secs_f64(),
                    periods.saturating_sub(1),
                    t.period().sample(periods.saturating_sub(1)).as_secs_f64()
                );
                return Err(ScenarioError::Fault { index: i, what });
            }
        }
        self.board.check().map_err(ScenarioError::Board)?;
        self.calibration.check().map_err(ScenarioError::Board)?;
        Ok(())
    }
}

/// A TOML syntax error as a scenario error. The reader's errors give the line and
/// column, except its nesting limit's (keys, tables or arrays 80 levels deep), which
/// says only "recursion limit": that one is said here (found by the `scenario`
/// fuzzing harness, docs/fuzzing.md).
fn toml_error(e: &toml::de::Error) -> ScenarioError {
    let msg = e.to_string();
    if e.span().is_some() {
        return ScenarioError::Parse(msg);
    }
    let why = if msg.trim() == "recursion limit" {
        "keys, tables or arrays nested 80 levels deep or more (scenario keys are at most 3 deep)".to_string()
    } else {
        msg.trim().to_string()
    };
    ScenarioError::Parse(format!("the scenario is not valid TOML: {why}"))
}

/// Reads the old key `controller.hybrid_ki` as `controller.hybrid.ki` (scenario
/// files written before the gains were opened). Returns whether it did.
///
/// # Errors
/// [`ScenarioError::Parse`] when both are given.
fn migrate_legacy(doc: &mut toml::Table) -> Result<bool, ScenarioError> {
    let Some(toml::Value::Table(controller)) = doc.get_mut("controller") else {
        return Ok(false);
    };
    let Some(ki) = controller.remove("hybrid_ki") else {
        return Ok(false);
    };
    let hybrid = controller.entry("hybrid").or_insert_with(|| toml::Value::Table(toml::Table::new()));
    match hybrid {
        toml::Value::Table(h) if !h.contains_key("ki") => {
            h.insert("ki".into(), ki);
            Ok(true)
        }
        _ => Err(ScenarioError::Parse(
            "scenario keys `controller.hybrid_ki` and `controller.hybrid.ki` are the same gain K'_I: give one (controller.hybrid.ki)"
                .into(),
        )),
    }
}

/// Deserialises a scenario; the error names the key path (`controller.kind`) and,
/// when an override touched that key, the override.
fn read<'de, D: serde::Deserializer<'de>>(de: D, overrides: &[Override]) -> Result<Scenario, ScenarioError>
where
    D::Error: std::fmt::Display,
{
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // Errors from a document (not a text) repeat the key on a line of their own.
        let inner = if overrides.is_empty() { inner.as_str() } else { inner.lines().next().unwrap_or_default() };
        let msg = if path == "." { inner.to_string() } else { format!("scenario key `{path}`: {inner}") };
        match overrides::culprit(overrides, &path) {
            Some(o) => ScenarioError::Parse(format!("{msg} (from --set {o})")),
            None => ScenarioError::Parse(msg),
        }
    })
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

    /// Issue 27: a NUL or ESC in the name made `trace.svg` ill-formed XML and reached
    /// the terminal raw. Refused, and the refusal shows it escaped.
    #[test]
    fn control_characters_in_the_name_are_refused_and_shown_escaped() {
        for bad in ["a\u{0}b", "run\u{1b}[2J", "tab\there", "line\nbreak", "del\u{7f}"] {
            let toml = DEFAULT_TOML.replacen("name = \"hybrid-x0d\"", &format!("name = {}", toml::Value::from(bad)), 1);
            assert_ne!(toml, DEFAULT_TOML, "the default scenario names itself `hybrid-x0d`");
            let e = Scenario::from_toml(&toml).unwrap_err().to_string();
            assert!(e.contains("name") && e.contains("control character"), "{e}");
            assert!(!e.chars().any(char::is_control), "the message carries no control character: {e:?}");
        }
        let fine = DEFAULT_TOML.replacen("name = \"hybrid-x0d\"", "name = \"Zürich run — 2\"", 1);
        assert_eq!(Scenario::from_toml(&fine).unwrap().name, "Zürich run — 2");
    }

    fn set(arg: &str) -> Override {
        arg.parse().unwrap()
    }

    /// Issue 27: a fault in the run's last half period was accepted and never acted.
    /// The load applies the run's own rule (`Fault::periods`).
    #[test]
    fn a_fault_that_cannot_act_is_refused_at_load() {
        let fault = |at_s: f64| format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"drop_command\"\nat_s = {at_s}\n");
        // The default runs 10 s at 1 kHz: periods 0 to 9999, the last at 9.999 s.
        assert!(Scenario::from_toml(&fault(9.999)).is_ok());
        for never in [9.9993, 9.9995, 10.0, 11.0] {
            let e = Scenario::from_toml(&fault(never)).unwrap_err().to_string();
            assert!(e.contains("faults[0]") && e.contains("never act") && e.contains("last period is 9999"), "{never}: {e}");
        }
    }

    /// docs/rig.md "Overrides": `--set faults=[...]` replaces the file's faults and
    /// is validated as in a file.
    #[test]
    fn faults_can_be_set_and_are_validated() {
        let s = Scenario::from_toml_with(DEFAULT_TOML, &[set("faults=[{kind=\"stall\",at_s=0.5,duration_s=0.05}]")]).unwrap();
        assert_eq!(s.faults.len(), 1);
        let with_two = format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"stall\"\nat_s = 1.0\n[[faults]]\nkind = \"stall\"\nat_s = 2.0\n");
        assert_eq!(Scenario::from_toml_with(&with_two, &[set("faults=[]")]).unwrap().faults.len(), 0);
        let e = Scenario::from_toml_with(DEFAULT_TOML, &[set("faults=[{kind=\"gremlin\",at_s=0.5}]")]).unwrap_err().to_string();
        assert!(e.contains("faults[0].kind") && e.contains("gremlin") && e.contains("--set"), "{e}");
    }

    #[test]
    fn overrides_reach_the_scenario_and_errors_name_the_key() {
        let s = Scenario::from_toml_with(DEFAULT_TOML, &[set("plant.m=0.24"), set("controller.pid.kp=[150,1]")]).unwrap();
        assert_eq!((s.plant.m, s.controller.pid.kp), (0.24, [150.0, 1.0]));
        assert_eq!(s, Scenario::default_scenario().with_overrides(&[set("plant.m=0.24"), set("controller.pid.kp=[150,1]")]).unwrap());
        let err = |args: &[&str]| {
            let o: Vec<Override> = args.iter().map(|a| set(a)).collect();
            Scenario::from_toml_with(DEFAULT_TOML, &o).unwrap_err().to_string()
        };
        let e = err(&["plant.m=-1"]);
        assert!(e.contains("`plant.m` = -1") && e.contains("> 0"), "{e}");
        let e = err(&["plant.m=nan"]);
        assert!(e.contains("`plant.m` = NaN"), "{e}");
        let e = err(&["plant.mass=1"]);
        assert!(e.contains("mass") && e.contains("plant.mass=1"), "{e}");
        let e = err(&["controller.pid.kp=[1]"]);
        assert!(e.contains("controller.pid.kp"), "{e}");
        let e = err(&["controller.hybrid.kd=-3"]);
        assert!(e.contains("controller.hybrid.kd") && e.contains("-3"), "{e}");
        let e = err(&["plant.m=1", "plant.m=2"]);
        assert!(e.contains("twice"), "{e}");
        let e = err(&["plant.m.x=1"]);
        assert!(e.contains("`plant.m` is not a table"), "{e}");
        let e = err(&["controller.model.l=0.1"]);
        assert!(e.contains("controller.model.h"), "{e}");
    }

    /// Regression (the `scenario` fuzzing harness, docs/fuzzing.md): values the
    /// firmware's f32 cannot hold were accepted, then refused by the firmware at the
    /// start of a run (or of every zmax and sweep trial); they are refused here,
    /// naming the key. Accepted values give a configuration the firmware accepts.
    #[test]
    fn values_beyond_the_firmwares_f32_are_refused_naming_the_key() {
        let h_onto_2l = format!("plant.h={:?}", (2.0f64 * 0.21).next_down());
        let z_onto_2l = format!("controller.target_z_t={:?}", (2.0f64 * 0.21).next_down());
        for (arg, key) in [
            ("controller.hybrid.kp=1e39", "controller.hybrid.kp"),
            ("controller.pid.ki=[1e39, 0]", "controller.pid.ki"),
            ("plant.m=1e-50", "plant.m"),
            ("plant.alpha0=-1e39", "plant.alpha0"),
            ("controller.model.g=1e-46", "controller.model.g"),
            ("controller.move_time_s=1e-300", "controller.move_time_s"),
            (h_onto_2l.as_str(), "plant.h"),
            (z_onto_2l.as_str(), "controller.target_z_t"),
        ] {
            let e = Scenario::from_toml_with(DEFAULT_TOML, &[set(arg)]).unwrap_err().to_string();
            assert!(e.contains(&format!("`{key}`")), "{arg}: {e}");
        }
        for arg in ["controller.hybrid.kp=3.4e38", "plant.m=1e-44", "controller.move_time_s=1e-44", "controller.model.l=0.19"] {
            let s = Scenario::from_toml_with(DEFAULT_TOML, &[set(arg)]).unwrap_or_else(|e| panic!("{arg}: {e}"));
            firmware::Firmware::new(crate::setup::firmware_config(&s)).unwrap_or_else(|e| panic!("{arg}: {e}"));
        }
    }

    /// Regression (the `scenario` fuzzing harness): the TOML reader's nesting limit
    /// said only "recursion limit", neither where nor what; the error says what.
    #[test]
    fn nesting_beyond_the_toml_readers_limit_is_said() {
        let deep = format!("{}\n[zz{}]\na = 1\n", DEFAULT_TOML, ".x".repeat(90));
        let e = Scenario::from_toml(&deep).unwrap_err().to_string();
        assert!(e.starts_with("the scenario is not valid TOML: keys, tables or arrays nested 80 levels"), "{e}");
    }

    #[test]
    fn the_legacy_hybrid_ki_key_is_read_as_hybrid_ki() {
        let old = DEFAULT_TOML.replace("[controller]\n", "[controller]\nhybrid_ki = 321.0\n");
        assert_eq!(Scenario::from_toml(&old).unwrap().controller.hybrid.ki, Some(321.0));
        let both = old.replace("kd = 900.0 ", "ki = 1.0\nkd = 900.0 ");
        assert!(Scenario::from_toml(&both).is_err());
        // An override of the new key wins over the file's old one.
        assert_eq!(Scenario::from_toml_with(&old, &[set("controller.hybrid.ki=5")]).unwrap().controller.hybrid.ki, Some(5.0));
        assert_eq!(Scenario::from_toml_with(DEFAULT_TOML, &[set("controller.hybrid_ki=7")]).unwrap().controller.hybrid.ki, Some(7.0));
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
