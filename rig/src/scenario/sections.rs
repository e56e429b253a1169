//! The scenario and its sections as types, one per table of the file
//! (`[plant]`, `[controller]` and its gains and model, `[timing]`, `[sensors]`,
//! `[rig]`), with the paper's values as the defaults of the optional keys.

use serde::{Deserialize, Serialize};

use firmware::{ControllerKind, config::FrictionCompensation};
use plant::{
    impact::{ImpactLaw, IwcRule},
    initial::PaperX0,
    moreau_jean::SingularRule,
};
use shared::{Params, Period};

use crate::faults::Fault;

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
    /// What a slide does at the singular point `p = b = 0` reached with a finite
    /// normal force: `leave` (default) or `slide` (docs/plant.md "The singular
    /// point"; optional, written only when not the default).
    #[serde(default, skip_serializing_if = "is_leave")]
    pub singular: SingularRule,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Integrator absolute tolerance.
    pub atol: f64,
    /// Largest integrator step, s (optional; none: the tolerances and the
    /// zero-order hold set the steps). `plant::SimConfig::max_step`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step: Option<f64>,
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

fn is_leave(rule: &SingularRule) -> bool {
    *rule == SingularRule::Leave
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

fn runaway_limits_on() -> bool {
    true
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if signature
fn is_on(b: &bool) -> bool {
    *b
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
    /// The firmware's torque limit per joint, N m, in (0, 5] (docs/hardware.md: the
    /// wire's and the drivers' full scale, 5 N m, when absent): commands beyond it are
    /// saturated and flagged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_limit_nm: Option<f64>,
    /// The firmware's runaway limits (a joint's speed past 20 rad/s, the load cell
    /// at full scale for 10 ms: `firmware::runaway`); true when absent. `false`
    /// lets a study see what the arm does without them (the paper's persistent
    /// bouncing beyond `Z_t,sliding`); never on a board.
    #[serde(default = "runaway_limits_on", skip_serializing_if = "is_on")]
    pub runaway_limits: bool,
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

    /// The longest command delay `delta_s` the firmware's protection takes, s,
    /// with `controller.runaway_limits` on (issue 80). The firmware's observers
    /// predict each interval with the torque it commanded held over all of it;
    /// a command that acts `delta` after the sample leaves the previous one on
    /// for that share of the interval, a model error its wiring and tracking
    /// checks cannot tell from a fault once it is large. Measured over the
    /// envelope (`board-link/tests/board/envelope.rs`: 2 000 runs at 250 Hz
    /// to 10 kHz, the delay at this bound or drawn up to it): no false alarm at
    /// 0.4 ms; the first, at 0.5 ms (a hybrid run at 338 Hz, `Tracking`), and
    /// from 1.1 ms at 250 to 640 Hz (`Miswired` within 5 periods of the
    /// start). The reference board's command leaves 15 to 20 us after its
    /// sample. With the protection off (the studies' runs) any delay within
    /// the period is taken.
    pub const MAX_PROTECTED_DELAY_S: f64 = 0.4e-3;

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
    /// Lockstep, in a period an injected fault touches (a stall, a dropped or late
    /// command): wall-clock time the plant waits for the command before it counts
    /// a deadline miss, s. Every other period waits for its answer whatever the
    /// host's load (up to `stall_limit_s`): in lockstep a slow host never misses.
    pub command_timeout_s: f64,
    /// Lockstep: wall-clock time without the period's answer, outside injected
    /// faults, after which the plant ends the run ("the firmware made no progress
    /// for N s"; exit 1, the trace kept), s (0 to 600). The firmware process is
    /// checked all along: dead, it ends the run at once.
    pub stall_limit_s: f64,
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
            stall_limit_s: 10.0,
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
    pub board: board_description::BoardDescription,
    /// The firmware's calibration of the board (`run --link twin`): the reference
    /// board's when absent (not written back then).
    #[serde(default, skip_serializing_if = "is_default")]
    pub calibration: crate::calibration::CalibrationSection,
    /// A law of one's own (`[law]`: its name and parameters, [`crate::law`]);
    /// absent for the paper's laws (and then not written back).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<crate::law::LawTable>,
}

impl Scenario {
    /// The control law this scenario runs, in words (issue 84: every view named
    /// each law "hybrid"): its `[law]` table's (`crate::law::LawTable::in_words`:
    /// ``law `impedance` (k_t = 2500, the rest at their defaults)``) or the paper's
    /// law by `controller.kind` (`hybrid`, `pid`). The trace page, the MCAP's
    /// `/log` and Python's `Result.law` say the same.
    #[must_use]
    pub fn law_in_words(&self) -> String {
        self.law.as_ref().map_or_else(|| self.controller.kind.to_string(), crate::law::LawTable::in_words)
    }
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}
