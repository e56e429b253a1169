//! The simulator's numerical and modelling settings ([`SimConfig`], a scenario's
//! `[plant]` settings besides the physical parameters), with their ranges.

use serde::Serialize;

use crate::{
    error::SimError,
    impact::{ImpactLaw, IwcRule},
    moreau_jean::SingularRule,
};

/// Numerical and modelling settings of the simulator (scenario parameters).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Relative tolerance of the integrator (DOP853, [`dop853::Dop853::rtol`](crate::dop853::Dop853::rtol)).
    pub rtol: f64,
    /// Absolute tolerance of the integrator (rad, rad/s; [`dop853::Dop853::atol`](crate::dop853::Dop853::atol)).
    pub atol: f64,
    /// Impact law at touchdown and for impacts without collision.
    pub impact_law: ImpactLaw,
    /// Restitution coefficient `e_n` in [0, 1] (Newton's, Poisson's or Stronge's energetic
    /// coefficient, per `impact_law`).
    pub e_n: f64,
    /// What an impact without collision leaves behind ([`impact::IwcRule`](crate::impact::IwcRule)).
    pub iwc: IwcRule,
    /// Relative tangential speed (m/s) below which the tip counts as at rest on the belt.
    pub v_stick: f64,
    /// Zeno rule: a bounce whose normal velocity after impact is below this (m/s)
    /// ends the bounce sequence; the tip stays in contact.
    pub zeno_velocity: f64,
    /// Baumgarte stabilisation rate of the contact constraint in sliding and
    /// sticking, rad/s (Baumgarte 1972; 0 disables it). The correction vanishes on
    /// the constraint, so it changes the contact force only by the drift it removes.
    pub baumgarte: f64,
    /// Events allowed in one `advance` before it fails with [`SimError::EventStorm`]
    /// (a guard against a hang; never reached in normal runs).
    pub max_events_per_advance: usize,
    /// Integrator steps allowed in one smooth segment.
    pub max_steps: usize,
    /// The dynamic jam (docs/plant.md "The jam corner"): a slide whose normal force
    /// `f_n = -b / p` grows to this many times `m g` as `p -> 0+` (dimensionless, in
    /// [1e3, 1e12]) is resolved by a tangential impact before it outgrows what the
    /// integrator can follow. Written in summaries only when it is not the default.
    #[serde(skip_serializing_if = "SimConfig::is_default_jam_load")]
    pub jam_load: f64,
    /// Largest integrator step, s (none: no cap; DOP853's `h_max`, Hairer, Nørsett
    /// and Wanner's `HMAX`). The tolerances set the steps; a cap makes a run take
    /// steps that neither the samples nor the zero-order hold impose, as the
    /// accuracy contract's reference runs do (docs/architecture.md). Written in
    /// summaries only when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_step: Option<f64>,
    /// What a slide does at the singular point `p = 0, b = 0` reached with a finite
    /// normal force ([`SingularRule`]; docs/plant.md "The singular point"): leave
    /// the belt (the default) or slide on through it. Written in summaries only
    /// when it is not the default.
    #[serde(skip_serializing_if = "SimConfig::is_default_singular")]
    pub singular: SingularRule,
    /// Step of the Moreau-Jean bridge across a collapsed event-driven step, s (in
    /// [1e-8, 1e-4]; docs/plant.md "The bridge"); the bridge halves it until its
    /// result agrees with the half-step one. Written in summaries only when it is
    /// not the default.
    #[serde(skip_serializing_if = "SimConfig::is_default_bridge_step")]
    pub bridge_step: f64,
    /// Length of one Moreau-Jean bridge, s (in [1e-5, 0.1], at least 10 bridge
    /// steps; cut at the end of the `advance` interval). Written in summaries only
    /// when it is not the default.
    #[serde(skip_serializing_if = "SimConfig::is_default_bridge_length")]
    pub bridge_length: f64,
}

/// The default [`SimConfig::bridge_step`], s.
pub const BRIDGE_STEP: f64 = 1e-5;

/// The default [`SimConfig::bridge_length`], s.
pub const BRIDGE_LENGTH: f64 = 1e-3;

/// The default [`SimConfig::jam_load`]: large enough that the outcome no longer
/// moves with it (`plant::tests::the_jam_outcome_converges_as_its_threshold_grows`).
pub const JAM_LOAD: f64 = 1e7;

/// The allowed [`SimConfig::max_step`], s: from 1e7 steps per simulated second to
/// one step per 1000 s (the scenario's `plant.max_step` is checked against it too).
pub const MAX_STEP_RANGE: std::ops::RangeInclusive<f64> = 1e-7..=1e3;

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            rtol: 1e-9,
            atol: 1e-11,
            impact_law: ImpactLaw::Newton,
            e_n: 0.2,
            iwc: IwcRule::Restitution,
            v_stick: 1e-9,
            zeno_velocity: 1e-4,
            baumgarte: 50.0,
            max_events_per_advance: 100_000,
            max_steps: 100_000_000,
            jam_load: JAM_LOAD,
            max_step: None,
            singular: SingularRule::Leave,
            bridge_step: BRIDGE_STEP,
            bridge_length: BRIDGE_LENGTH,
        }
    }
}

impl SimConfig {
    fn is_default_jam_load(v: &f64) -> bool {
        v.to_bits() == JAM_LOAD.to_bits()
    }

    fn is_default_singular(v: &SingularRule) -> bool {
        *v == SingularRule::Leave
    }

    fn is_default_bridge_step(v: &f64) -> bool {
        v.to_bits() == BRIDGE_STEP.to_bits()
    }

    fn is_default_bridge_length(v: &f64) -> bool {
        v.to_bits() == BRIDGE_LENGTH.to_bits()
    }

    /// Checks ranges: tolerances finite and in (0, 0.1]; `e_n` in [0, 1];
    /// `v_stick`, `zeno_velocity` finite and >= 0; limits > 0; `max_step`, when set,
    /// in [1e-7, 1e3] s; `bridge_step` in [1e-8, 1e-4] s and `bridge_length` in
    /// [1e-5, 0.1] s, at least 10 bridge steps.
    ///
    /// # Errors
    /// [`SimError::BadConfig`] naming the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |name: &'static str, value: f64, expected: &'static str| Err(SimError::BadConfig { name, value, expected });
        for (name, v) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(v.is_finite() && (1e-14..=0.1).contains(&v)) {
                return bad(name, v, "a value in [1e-14, 0.1] (below 1e-14 a step cannot meet it in f64)");
            }
        }
        if !(self.e_n.is_finite() && (0.0..=1.0).contains(&self.e_n)) {
            return bad("e_n", self.e_n, "a value in [0, 1]");
        }
        for (name, v) in [("v_stick", self.v_stick), ("zeno_velocity", self.zeno_velocity), ("baumgarte", self.baumgarte)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "a finite value >= 0");
            }
        }
        if !(self.jam_load.is_finite() && (1e3..=1e12).contains(&self.jam_load)) {
            return bad("jam_load", self.jam_load, "a value in [1e3, 1e12]");
        }
        if let Some(h) = self.max_step
            && !(h.is_finite() && MAX_STEP_RANGE.contains(&h))
        {
            return bad("max_step", h, "a step in [1e-7, 1e3] s");
        }
        if !(self.bridge_step.is_finite() && (1e-8..=1e-4).contains(&self.bridge_step)) {
            return bad("bridge_step", self.bridge_step, "a step in [1e-8, 1e-4] s");
        }
        if !(self.bridge_length.is_finite() && (1e-5..=0.1).contains(&self.bridge_length) && self.bridge_length >= 10.0 * self.bridge_step)
        {
            return bad("bridge_length", self.bridge_length, "a length in [1e-5, 0.1] s and at least 10 bridge steps");
        }
        if self.max_events_per_advance == 0 || self.max_steps == 0 {
            return bad("max_events_per_advance/max_steps", 0.0, "a positive count");
        }
        Ok(())
    }
}
