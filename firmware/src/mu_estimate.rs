//! The online friction estimate of the hybrid law's robust variant
//! ([`FrictionCompensation::Estimated`](crate::config::FrictionCompensation::Estimated);
//! docs/controllers.md "Friction not known"): `mu` from the load cell's `f_t / f_n`
//! while the tip slides, low-pass filtered, bounded around `mu_hat`, and frozen
//! where the ratio cannot be trusted.
//!
//! While the tip slides, Coulomb's law gives `f_t = -mu s f_n` whatever the
//! torques, so `-s f_t / f_n` measures `mu` with no feedback through the estimate
//! (unlike feeding the measured `f_t` itself into the law, whose loop gain
//! `-mu s Q_21 / p` grows without bound as `p -> 0+`; config.rs). The estimate is a
//! first-order filter of that ratio with time constant [`TAU_S`] (Olsson, Åström,
//! Canudas de Wit, Gäfvert and Lischinsky, "Friction models and friction
//! compensation", Eur. J. Control 4, 1998, sec. 6: friction estimation from
//! measured forces, filtered), bounded to `mu_hat (1 +- BOUND)`, and frozen
//! (held) where the ratio is not a measure of `mu`:
//! - the measured `f_n` below [`F_N_MIN_FRACTION`] of `f_n*` (or below 0.5 N):
//!   lift-off, flight, or a ratio of small, noisy forces;
//! - the slip speed `|z_r_dot|` below [`V_R_MIN`], or its sign changed since the
//!   last period: sticking or slip reversal, where `|f_t| <= mu f_n` is a
//!   constraint force, not Coulomb's;
//! - `p / Q_22` below [`P_MIN`] (near the Painlevé boundary `p -> 0+`), where the
//!   slide is about to jam or leave and the forces move faster than a period.
//!
//! The estimate is held as the correction `mu_est - mu_hat` (0 at the start), so
//! that the law's state starts from zeros.

/// Time constant of the estimate's low-pass filter, s: 20 periods at 1 kHz, 5 at
/// 250 Hz, 200 at 10 kHz.
pub const TAU_S: f32 = 0.02;

/// Bound of the estimate around `mu_hat`, as a fraction of it: `mu_hat (1 +- 0.5)`.
pub const BOUND: f32 = 0.5;

/// Smallest measured `f_n` for an update, as a fraction of `f_n*` (and at least 0.5 N).
pub const F_N_MIN_FRACTION: f32 = 0.3;

/// Smallest slip speed `|z_r_dot|` for an update, m/s.
pub const V_R_MIN: f32 = 0.01;

/// Smallest `p / Q_22` for an update (dimensionless).
pub const P_MIN: f32 = 0.2;

/// The estimate's state: the correction `mu_est - mu_hat` and the last slip
/// direction (`+-1`; 0 before the first update).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MuEstimate {
    /// `mu_est - mu_hat` (dimensionless).
    pub correction: f32,
    /// `sign(z_r_dot)` at the last period (0: none yet).
    pub last_slip: f32,
}

/// What one period measured, for [`MuEstimate::update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionSample {
    /// Measured `f_t`, N.
    pub f_t: f32,
    /// Measured `f_n`, N.
    pub f_n: f32,
    /// The normal force reference `f_n*`, N.
    pub f_n_ref: f32,
    /// Estimated slip speed `z_r_dot = z_t_dot - v_belt`, m/s.
    pub v_r: f32,
    /// `p / Q_22` with the current estimate (dimensionless).
    pub p_over_q22: f32,
}

impl MuEstimate {
    /// The estimate `mu_hat + correction` (dimensionless).
    pub fn mu(&self, mu_hat: f32) -> f32 {
        mu_hat + self.correction
    }

    /// One period of `dt` s: updates the estimate from `sample` if it can be
    /// trusted (module docs), else holds it. Returns whether it updated. A
    /// non-finite sample is never used.
    pub fn update(&mut self, mu_hat: f32, sample: &FrictionSample, dt: f32) -> bool {
        let s = if sample.v_r < 0.0 { -1.0 } else { 1.0 };
        let same_slip = self.last_slip == s;
        self.last_slip = if sample.v_r.abs() >= V_R_MIN { s } else { 0.0 };
        let f_min = if F_N_MIN_FRACTION * sample.f_n_ref > 0.5 { F_N_MIN_FRACTION * sample.f_n_ref } else { 0.5 };
        let trusted = sample.f_n > f_min && sample.v_r.abs() >= V_R_MIN && same_slip && sample.p_over_q22 > P_MIN;
        let ratio = -s * sample.f_t / sample.f_n;
        if !(trusted && ratio.is_finite() && dt.is_finite() && dt > 0.0) {
            return false;
        }
        let bound = BOUND * mu_hat;
        let target = clamp(ratio - mu_hat, -bound, bound);
        let alpha = if dt < TAU_S { dt / TAU_S } else { 1.0 };
        self.correction += alpha * (target - self.correction);
        true
    }
}

/// `x` clamped to `[lo, hi]` by comparisons (core's `f32::clamp` calls `fminf`/`fmaxf` on the MCU).
fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}
