//! The open choices of the sensitivity study: the knobs every choice sets, the
//! dimensions they vary, and the list of choices, each dimension with its
//! default among them.

use firmware::{ControllerKind, config::FrictionCompensation};
use plant::{
    impact::{ImpactLaw, IwcRule},
    moreau_jean::SingularRule,
};
use rig::scenario::Scenario;
use serde::Serialize;

/// Every open choice at one value: the defaults (the paper's set-up and ours,
/// docs/model.md and docs/hardware.md) or one of them changed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Knobs {
    /// Impact law.
    pub impact_law: ImpactLaw,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Impact-without-collision rule.
    pub iwc: IwcRule,
    /// The singular-point rule.
    pub singular: SingularRule,
    /// The hybrid law's friction term (sampled firmware).
    pub friction: FrictionCompensation,
    /// Duration of the reference's move, s.
    pub move_time_s: f64,
    /// Lift-off criterion: 0 for any departure, else the gap the tip must exceed, m.
    pub lift_off_gap_m: f64,
    /// Control rate of the sampled firmware, Hz.
    pub rate_hz: f64,
    /// Joint encoder resolution, bits per revolution.
    pub encoder_bits: u8,
    /// Load-cell white noise, N rms.
    pub load_noise_n: f64,
    /// Relative error of the firmware's friction estimate: `mu_hat = (1 + m) mu`.
    pub mu_hat_mismatch: f64,
    /// The firmware's torque limit per joint, N m (`None`: the base scenario's, 5 N m
    /// by default).
    pub torque_limit_nm: Option<f64>,
    /// Delay from sampling to the command taking effect, s (`None`: the base
    /// scenario's, the same fraction of the period at every rate).
    pub delay_s: Option<f64>,
}

impl Default for Knobs {
    fn default() -> Self {
        Self {
            impact_law: ImpactLaw::Newton,
            e_n: 0.2,
            iwc: IwcRule::Restitution,
            singular: SingularRule::Leave,
            friction: FrictionCompensation::ModelCommandedNormal,
            move_time_s: 2.0,
            lift_off_gap_m: 0.0,
            rate_hz: 1000.0,
            encoder_bits: 14,
            load_noise_n: 0.02,
            mu_hat_mismatch: 0.0,
            torque_limit_nm: None,
            delay_s: None,
        }
    }
}

impl Knobs {
    /// `base` with these knobs: the plant's impact law, `e_n` and IWC rule, the
    /// controller's friction term, move time, `mu_hat` and torque limit, the rate
    /// (the delay from sampling to the command, `delta_s`, kept the same fraction of
    /// the period unless `delay_s` sets it; beyond 0.4 ms the run is without the
    /// firmware's protection, `controller.runaway_limits = false`, which the
    /// validator asks there), the encoders and the load-cell noise.
    pub fn scenario(&self, base: &Scenario) -> Scenario {
        let mut s = base.clone();
        s.plant.impact_law = self.impact_law;
        s.plant.e_n = self.e_n;
        s.plant.iwc = self.iwc;
        s.plant.singular = self.singular;
        s.controller.friction = self.friction;
        s.controller.move_time_s = self.move_time_s;
        s.controller.mu_hat = base.plant.mu * (1.0 + self.mu_hat_mismatch);
        s.timing.delta_s = self.delay_s.unwrap_or(base.timing.delta_s * base.timing.rate_hz / self.rate_hz);
        // A delay beyond what the firmware's protection takes (issue 80,
        // `TimingSection::MAX_PROTECTED_DELAY_S`) is studied without it: the
        // study varies the model, and the protection would stop healthy arms there.
        if s.timing.delta_s > rig::scenario::TimingSection::MAX_PROTECTED_DELAY_S {
            s.controller.runaway_limits = false;
        }
        if let Some(limit) = self.torque_limit_nm {
            s.controller.torque_limit_nm = Some(limit);
        }
        s.timing.rate_hz = self.rate_hz;
        s.sensors.encoder_bits = self.encoder_bits;
        s.sensors.load_noise_n = self.load_noise_n;
        s
    }
}

/// Which open choice a [`Choice`] varies (the study's dimensions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Dimension {
    /// Impact law and `e_n`.
    ImpactLaw,
    /// The IWC rule.
    Iwc,
    /// The singular-point rule.
    Singular,
    /// The hybrid law's friction compensation.
    Friction,
    /// The reference's move time.
    MoveTime,
    /// The lift-off criterion.
    LiftOff,
    /// The sampled firmware's rate.
    Rate,
    /// Encoder resolution.
    EncoderBits,
    /// Load-cell noise.
    LoadNoise,
    /// `mu_hat` mismatch, under the paper's friction term and the estimated one.
    MuHat,
    /// The firmware's torque limit.
    TorqueLimit,
    /// Delay from sampling to the command.
    Delay,
}

impl Dimension {
    /// Every dimension, in the study's order.
    pub const ALL: [Dimension; 12] = [
        Self::ImpactLaw,
        Self::Iwc,
        Self::Singular,
        Self::Friction,
        Self::MoveTime,
        Self::LiftOff,
        Self::Rate,
        Self::EncoderBits,
        Self::LoadNoise,
        Self::MuHat,
        Self::TorqueLimit,
        Self::Delay,
    ];

    /// A label for tables and figures.
    pub fn label(self) -> &'static str {
        match self {
            Self::ImpactLaw => "impact law, e_n",
            Self::Iwc => "IWC rule",
            Self::Singular => "singular-point rule",
            Self::Friction => "hybrid friction term",
            Self::MoveTime => "move time (s)",
            Self::LiftOff => "lift-off criterion",
            Self::Rate => "control rate (Hz)",
            Self::EncoderBits => "encoder bits",
            Self::LoadNoise => "load-cell noise (N rms)",
            Self::MuHat => "mu_hat mismatch",
            Self::TorqueLimit => "torque limit (N m)",
            Self::Delay => "delay (ms)",
        }
    }

    /// Whether the choice enters the open-loop results (no controller).
    pub fn in_open_loop(self) -> bool {
        matches!(self, Self::ImpactLaw | Self::Iwc | Self::Singular | Self::LiftOff)
    }

    /// Whether the choice enters the ideal (continuous-time, exact) controllers.
    pub fn in_ideal(self) -> bool {
        matches!(self, Self::ImpactLaw | Self::Iwc | Self::Singular | Self::MoveTime | Self::LiftOff)
    }

    /// Whether the choice enters the controller `kind` (the friction term is the hybrid law's).
    pub fn in_controller(self, kind: ControllerKind) -> bool {
        self != Self::Friction || kind == ControllerKind::Hybrid
    }
}

/// One value of one open choice (the others at their defaults).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Choice {
    /// The dimension varied.
    pub dimension: Dimension,
    /// The value, as text (`poisson, e_n = 0.5`, `plastic`, `0.5`, ...).
    pub value: String,
    /// The value as a number where it is one (for figures), else the index in its dimension.
    pub x: f64,
    /// Whether this is the default value.
    pub is_default: bool,
    /// All knobs.
    pub knobs: Knobs,
}

/// The choices of the study from `base` (the defaults' torque limit and delay are
/// its), dimension by dimension, each with its default among them.
pub fn choices(base: &Scenario) -> Vec<Choice> {
    let d = Knobs::default();
    let mut v = Vec::new();
    let mut push = |dimension, value: String, x: f64, knobs: Knobs| {
        v.push(Choice { dimension, value, x, is_default: knobs == d, knobs });
    };
    let mut i = 0.0;
    for law in ImpactLaw::ALL {
        for e_n in [0.0, 0.2, 0.5] {
            push(Dimension::ImpactLaw, format!("{law}, e_n = {e_n}"), i, Knobs { impact_law: law, e_n, ..d });
            i += 1.0;
        }
    }
    for (k, iwc) in IwcRule::ALL.into_iter().enumerate() {
        push(Dimension::Iwc, iwc.to_string(), k as f64, Knobs { iwc, ..d });
    }
    for (k, singular) in SingularRule::ALL.into_iter().enumerate() {
        push(Dimension::Singular, singular.to_string(), k as f64, Knobs { singular, ..d });
    }
    let frictions = [
        (FrictionCompensation::ModelCommandedNormal, "commanded"),
        (FrictionCompensation::ModelMeasuredNormal, "measured_normal"),
        (FrictionCompensation::Measured, "measured"),
        (FrictionCompensation::None, "none"),
        (FrictionCompensation::Estimated, "estimated"),
    ];
    for (k, (friction, name)) in frictions.into_iter().enumerate() {
        push(Dimension::Friction, name.into(), k as f64, Knobs { friction, ..d });
    }
    for t in [0.1, 0.25, 0.5, 1.0, 2.0] {
        push(Dimension::MoveTime, format!("{t}"), t, Knobs { move_time_s: t, ..d });
    }
    for (gap, name) in [(0.0, "any departure"), (1e-6, "gap > 1 um"), (1e-4, "gap > 0.1 mm")] {
        push(Dimension::LiftOff, name.into(), gap, Knobs { lift_off_gap_m: gap, ..d });
    }
    for r in [250.0, 500.0, 1000.0, 2000.0, 5000.0, 10_000.0] {
        push(Dimension::Rate, format!("{r}"), r, Knobs { rate_hz: r, ..d });
    }
    for b in 12..=16u8 {
        push(Dimension::EncoderBits, format!("{b}"), f64::from(b), Knobs { encoder_bits: b, ..d });
    }
    for n in [0.0, 0.01, 0.02, 0.05, 0.1] {
        push(Dimension::LoadNoise, format!("{n}"), n, Knobs { load_noise_n: n, ..d });
    }
    // The paper's friction term, then the robust variant's (issue 41) beside it.
    for m in [-0.2, -0.1, 0.0, 0.1, 0.2] {
        push(Dimension::MuHat, format!("{:+}%", (m * 100.0f64).round()), m, Knobs { mu_hat_mismatch: m, ..d });
    }
    for m in [-0.2, -0.1, 0.0, 0.1, 0.2] {
        let knobs = Knobs { mu_hat_mismatch: m, friction: FrictionCompensation::Estimated, ..d };
        push(Dimension::MuHat, format!("{:+}%, estimated", (m * 100.0f64).round()), m, knobs);
    }
    // Below the default's 5 N m only: the wire and the drivers stop there.
    for t in [2.0, 3.0, 4.0] {
        push(Dimension::TorqueLimit, format!("{t}"), t, Knobs { torque_limit_nm: Some(t), ..d });
    }
    let limit = base.controller.torque_limit_nm.unwrap_or(f64::from(shared::wire::TORQUE_FULL_SCALE_NM));
    push(Dimension::TorqueLimit, format!("{limit}"), limit, d);
    // The scenario's (0.2 ms by default) among others below the 1 ms period.
    let mut delays: Vec<f64> = [0.0, 0.5e-3, 0.9e-3].into_iter().filter(|&x| x < base.timing.period().as_secs_f64()).collect();
    delays.push(base.timing.delta_s);
    delays.sort_by(f64::total_cmp);
    delays.dedup();
    for delay in delays {
        let knobs = if delay == base.timing.delta_s { d } else { Knobs { delay_s: Some(delay), ..d } };
        let ms = (delay * 1e6).round() / 1e3;
        push(Dimension::Delay, format!("{ms}"), ms, knobs);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_dimension_has_its_default_once_and_only_one_knob_changes() {
        let all = choices(&Scenario::default_scenario());
        let d = Knobs::default();
        for dim in Dimension::ALL {
            let of: Vec<&Choice> = all.iter().filter(|c| c.dimension == dim).collect();
            assert!(of.len() >= 2, "{dim:?}");
            assert_eq!(of.iter().filter(|c| c.is_default).count(), 1, "{dim:?}: one default");
        }
        // Each choice differs from the defaults in at most one knob (the impact
        // dimension moves the law and e_n together, the mu_hat dimension the
        // mismatch and the friction term).
        for c in &all {
            let k = c.knobs;
            let changed = [
                k.impact_law != d.impact_law || k.e_n != d.e_n,
                k.iwc != d.iwc,
                k.singular != d.singular,
                k.friction != d.friction && c.dimension != Dimension::MuHat,
                k.move_time_s != d.move_time_s,
                k.lift_off_gap_m != d.lift_off_gap_m,
                k.rate_hz != d.rate_hz,
                k.encoder_bits != d.encoder_bits,
                k.load_noise_n != d.load_noise_n,
                k.mu_hat_mismatch != d.mu_hat_mismatch,
                k.torque_limit_nm != d.torque_limit_nm,
                k.delay_s != d.delay_s,
            ];
            assert!(changed.iter().filter(|x| **x).count() <= 1, "{c:?}");
        }
    }

    #[test]
    fn the_default_knobs_are_the_default_scenario() {
        let base = Scenario::default_scenario();
        let s = Knobs::default().scenario(&base);
        assert_eq!(s, base, "the defaults reproduce the embedded scenario");
    }
}
