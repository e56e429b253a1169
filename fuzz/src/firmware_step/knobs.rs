//! The configuration of a case: a base (the default, or a scenario file's
//! firmware configuration) with some settings redrawn within their ranges.

use std::sync::OnceLock;

use firmware::{
    Config, ControllerKind,
    config::{FrictionCompensation, HybridGains, PidGains},
};
use shared::{ElbowBranch, Period};

/// The scenarios whose firmware configurations the cases start from (besides the default).
const SCENARIOS: [&str; 5] = [
    include_str!("../../../scenarios/default.toml"),
    include_str!("../../../scenarios/hybrid-x0d.toml"),
    include_str!("../../../scenarios/hybrid-x0u.toml"),
    include_str!("../../../scenarios/pid-x0d.toml"),
    include_str!("../../../scenarios/pid-x0u.toml"),
];

/// `Config::default()`, then the configurations of [`SCENARIOS`] (parsed once).
fn base_configs() -> &'static [Config] {
    static CONFIGS: OnceLock<Vec<Config>> = OnceLock::new();
    CONFIGS.get_or_init(|| {
        let from_file = SCENARIOS.iter().map(|text| {
            // The files are the repository's own: a parse failure is a build defect.
            let s = rig::scenario::Scenario::from_toml(text).unwrap_or_else(|e| panic!("scenarios/*.toml: {e}"));
            rig::setup::firmware_config(&s)
        });
        std::iter::once(Config::default()).chain(from_file).collect()
    })
}

/// Settings redrawn over a base configuration; `None` keeps the base's.
#[derive(Debug, Clone)]
pub struct Knobs {
    /// 0: `Config::default()`; 1 to 5: `firmware_config` of a scenario file.
    pub base: usize,
    /// The law.
    pub controller: Option<ControllerKind>,
    /// Period, us (100 to 4000).
    pub period_us: Option<u32>,
    /// Torque limit, N m ((0, 5]).
    pub torque_limit: Option<f32>,
    /// Consecutive deadline misses that latch the safe state.
    pub deadline_miss_limit: Option<u16>,
    /// Consecutive bad frames that latch the safe state.
    pub bad_frame_limit: Option<u16>,
    /// Encoder resolution, bits (10 to 16).
    pub encoder_bits: Option<u8>,
    /// Elbow branch of the PID.
    pub branch: Option<Option<ElbowBranch>>,
    /// The hybrid law's friction term.
    pub friction: Option<FrictionCompensation>,
    /// Tangential target as a fraction of the reach `2 l` (|.| < 1).
    pub target_fraction: Option<f32>,
    /// Move time, s.
    pub move_time_s: Option<f32>,
    /// Normal force reference, N.
    pub f_n_ref: Option<f32>,
    /// Force ramp, s.
    pub force_ramp_s: Option<f32>,
    /// Every gain multiplied by this.
    pub gain_scale: Option<f32>,
    /// Observer bandwidth as a fraction of its largest value `3/Ts`.
    pub observer_fraction: Option<f32>,
    /// The runaway limits and wiring checks off (`Config::runaway_limits`), as the
    /// studies run: the law's own failures (`NonFinite`, `Singular`) are reached
    /// there, where the checks would stop a wild case first.
    pub protection_off: bool,
}

impl Knobs {
    /// The configuration: the base with the knobs applied. Valid by construction
    /// ([`check`](super::check) fails otherwise: a generator defect).
    pub fn config(&self) -> Config {
        let mut c = base_configs()[self.base % (SCENARIOS.len() + 1)];
        if let Some(k) = self.controller {
            c.controller = k;
        }
        if let Some(us) = self.period_us {
            c.period = Period::from_us(us).unwrap_or(Period::MILLISECOND);
        }
        if let Some(t) = self.torque_limit {
            c.torque_limit = t;
        }
        if let Some(n) = self.deadline_miss_limit {
            c.deadline_miss_limit = n;
        }
        if let Some(n) = self.bad_frame_limit {
            c.bad_frame_limit = n;
        }
        if let Some(b) = self.encoder_bits {
            c.encoder_bits = b;
        }
        if let Some(b) = self.branch {
            c.branch = b;
        }
        if let Some(f) = self.friction {
            c.friction = f;
        }
        if let Some(x) = self.target_fraction {
            c.target_z_t = x * 2.0 * c.params.l;
        }
        if let Some(t) = self.move_time_s {
            c.move_time_s = t;
        }
        if let Some(f) = self.f_n_ref {
            c.f_n_ref = f;
        }
        if let Some(t) = self.force_ramp_s {
            c.force_ramp_s = t;
        }
        if let Some(s) = self.gain_scale {
            let g = c.pid;
            c.pid = PidGains { kp: g.kp.map(|x| x * s), ki: g.ki.map(|x| x * s), kd: g.kd.map(|x| x * s) };
            let h = c.hybrid;
            c.hybrid = HybridGains { kp: h.kp * s, kd: h.kd * s, ki: h.ki * s };
        }
        // Within (0, 3/Ts] at the (possibly new) period.
        let frac = self.observer_fraction.unwrap_or(0.2);
        c.observer_bandwidth = c.observer_bandwidth.min(frac * 3.0 / c.period.as_secs_f32());
        c.runaway_limits = !self.protection_off;
        c
    }
}
