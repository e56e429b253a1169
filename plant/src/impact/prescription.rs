//! What each impact law prescribes for its own impulse, stated so that the energy
//! ledger can hold an impulse to its law from the impulse, `Q` and the relative
//! velocity before it (issue 67; docs/plant.md "The energy ledger").
//!
//! The friction cone and the belt-frame dissipation (`contact work <= 0`) hold for
//! every law and are checked by the plant. Each law also states its own relation,
//! and its own bound on what the contact dissipates:
//! - **Newton** (`newton_sticking`, `newton_sliding`): the normal velocity after is
//!   `v_n+ = -e v_n,ref` (`v_n,ref` the approach velocity, or for the impact without
//!   collision the deepest normal velocity of the compression it creates,
//!   [`Impulse::v_n_min`]); sticking leaves `v_r+ = 0`; sliding has its impulse on
//!   the cone's edge with friction opposing the slip *after* the impact
//!   (`P_t v_r+ <= 0`). Moreau 1988; Glocker 2001; Brogliato 2016, ch. 4.
//! - **Poisson** (`poisson_darboux_keller`, `newton_darboux_keller`): the normal
//!   impulse is `P_n = (1 + e) P_c`, `P_c` the impulse that ends compression
//!   ([`Compression::p_c`]). Stronge 2000, ch. 5.
//! - **Energetic** (`energetic_darboux_keller` and the two fallbacks): the normal
//!   work in restitution is `e^2` times the work absorbed in compression,
//!   `W_r = -e^2 W_c` ([`Compression`]), so the contact dissipates at least
//!   `(1 - e^2) |W_c|`. Stronge 2000, sec. 5.3.
//! - Every Darboux-Keller impulse (the three above): friction on the cone's edge
//!   opposes the slip throughout the process, so its work
//!   `W_t = W - W_c - W_r <= 0` (Coulomb's maximum dissipation; Stronge 2000,
//!   sec. 4.4).
//! - **Plastic IWC** (`plastic_iwc`): the tip is left on the belt, `v_n+ = 0`, and
//!   stuck (`v_r+ = 0`; or, where that impulse would leave the cone, by Poisson's
//!   process with `e = 0`, `P_n = P_c`).
//! - **The edge impulse that stops a slip** (`tangential_impact`, the jam;
//!   `iwc_at_p_zero`, the singular point): `v_r+ = 0`, the impulse on the cone's
//!   edge with friction opposing the slip before it (`P_t v_r- <= 0`).
//!
//! - Every Darboux-Keller impulse's record of its compression (`P_c`, `W_c`, which the
//!   relations above read) equals the compression recomputed here from the velocity
//!   before it, `Q` and `mu` alone ([`compression_of`], issue 81): the process's phases in
//!   closed form (a slip on the cone's edge, then sticking or a reversed slip once the slip
//!   stops), written apart from the laws' own solver, so that a record that agrees with a
//!   wrong impulse cannot pass.
//!
//! A velocity projection (`projection`) is held to the drift it removes instead
//! ([`Plant::check_projection`](crate::Plant::check_projection)).

use nalgebra::{Matrix2, Vector2};

use super::impulse::{Impulse, Resolution, work_tolerance};

/// Relative tolerance of each relation (rounding of the laws' closed forms and of
/// the Darboux-Keller sums over at most eight phases).
pub const LAW_TOLERANCE: f64 = 1e-9;

/// The relation of its own law an impulse breaks (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Breach {
    /// Newton: `v_n+ != -e v_n,ref`, or the plastic IWC: `v_n+ != 0`.
    NormalVelocity,
    /// A sticking impulse (Newton's), or one that stops a slip, leaves `v_r+ != 0`.
    SlipLeft,
    /// An edge impulse off the cone's edge (`|P_t| != mu P_n`), or with friction
    /// along the slip it acts on.
    Edge,
    /// Poisson: `P_n != (1 + e) P_c`.
    NormalImpulse,
    /// Energetic: `W_r != -e^2 W_c`.
    NormalWork,
    /// A Darboux-Keller impulse whose friction did positive work (`W_t > 0`).
    FrictionWork,
    /// A Darboux-Keller impulse whose record of its compression (`P_c`, `W_c`) is not
    /// the compression recomputed from the velocity before it ([`compression_of`]).
    Compression,
}

impl Breach {
    /// What was broken, for reports.
    pub fn describe(self) -> &'static str {
        match self {
            Self::NormalVelocity => "the normal velocity after the impact is not the law's",
            Self::SlipLeft => "a sticking impulse left the tip slipping",
            Self::Edge => "an edge impulse is off the cone's edge or pushes along the slip",
            Self::NormalImpulse => "Poisson's normal impulse is not (1 + e) P_c",
            Self::NormalWork => "the energetic law's restitution work is not e^2 of the compression's",
            Self::FrictionWork => "friction did positive work during the impact",
            Self::Compression => "the impulse's compression is not the one recomputed from the velocity before it",
        }
    }
}

/// The compression of the Darboux-Keller process from the relative velocity `before =
/// [v_r, v_n]` (m/s) with inverse inertia `qm` (1/kg) and friction `mu`: `(P_c, W_c)`, the
/// normal impulse (N s) at which `v_n` returns to 0 and the normal work `int_0^P_c v_n
/// dP_n` (J), recomputed in closed form (Stronge 2000, ch. 4 and 5; Brogliato 2016, ch. 4).
/// With the normal impulse `P` as the process's parameter the velocity is affine in it
/// within each phase: slipping in direction `s`, `dv/dP = Q [-mu s, 1]`, so `dv_n/dP =
/// p(s)` (paper eq. 7); stuck, `dP_t/dP = -Q_12/Q_11` keeps `v_r = 0`, possible while
/// `|Q_12| <= mu Q_11`, with `dv_n/dP = det Q / Q_11 > 0`; else the slip reverses to `s' =
/// sign Q_12`. A tip with `v_n = 0` before (an impact without collision) is compressed by
/// its own friction (`p(s) < 0`) until the slip stops. `None` where compression never
/// ends (an impact jam) or an input is not finite.
pub fn compression_of(qm: &Matrix2<f64>, mu: f64, before: Vector2<f64>) -> Option<(f64, f64)> {
    if !(qm.iter().all(|v| v.is_finite()) && before.iter().all(|v| v.is_finite())) {
        return None;
    }
    let (q11, q12, q22) = (qm[(0, 0)], qm[(0, 1)], qm[(1, 1)]);
    // One phase of constant rates from normal velocity `v_n` over `dp` (dp infinite:
    // until `v_n` returns to 0): the impulse and work it adds, and `v_n` at its end.
    let phase = |v_n: f64, rate: f64, dp: f64| -> Option<(f64, f64, f64)> {
        let to_zero = if rate > 0.0 && v_n < 0.0 { -v_n / rate } else { f64::INFINITY };
        let d = dp.min(to_zero);
        if !d.is_finite() {
            return None;
        }
        Some((d, v_n * d + 0.5 * rate * d * d, if d == to_zero { 0.0 } else { v_n + rate * d }))
    };
    let (mut p_c, mut w_c, mut v_n) = (0.0, 0.0, before[1]);
    if before[0] != 0.0 {
        let s = before[0].signum();
        let p_s = q22 - mu * s * q12;
        if v_n >= 0.0 && p_s >= 0.0 {
            // Nothing to compress: the tip does not approach and its friction does not press it.
            return Some((0.0, 0.0));
        }
        // Slipping: v_r changes at `q12 - mu s q11` per newton second (towards 0 when its
        // sign is opposite to the slip's).
        let a = q12 - mu * s * q11;
        let stops = if a * s < 0.0 { -before[0] / a } else { f64::INFINITY };
        let (d, w, v) = phase(v_n, p_s, stops)?;
        (p_c, w_c, v_n) = (d, w, v);
        if d < stops || v_n >= 0.0 {
            return Some((p_c, w_c));
        }
    }
    // The slip is stopped: stuck inside the cone, or slipping again the other way.
    let rate = if q12.abs() <= mu * q11 { (q11 * q22 - q12 * q12) / q11 } else { q22 - mu * q12.signum() * q12 };
    let (d, w, _) = phase(v_n, rate, f64::INFINITY)?;
    Some((p_c + d, w_c + w))
}

/// Whether `a` equals `b` to [`LAW_TOLERANCE`] of `scale` (plus `floor`).
fn near(a: f64, b: f64, scale: f64, floor: f64) -> bool {
    (a - b).abs() <= LAW_TOLERANCE * scale + floor
}

/// The first relation of its own law (module documentation) that impulse `imp`
/// breaks, for a tip with relative velocity `before = [v_r, v_n]` (m/s) and
/// inverse inertia `qm` (1/kg), friction `mu` and restitution coefficient `e` (the
/// scenario's `e_n`); `None` if it keeps them all, or if it is a projection. The
/// velocity after is `before + Q P`, computed here from the impulse `P`, never
/// taken from the impulse's own `dv`.
pub fn breach(imp: &Impulse, qm: &Matrix2<f64>, mu: f64, e: f64, before: Vector2<f64>) -> Option<Breach> {
    let p = imp.p;
    let dv = qm * p;
    let after = before + dv;
    let v_scale = before.abs().sum() + dv.abs().sum();
    let v_floor = 1e-15;
    let on_edge = near(p[0].abs(), mu * p[1], p.norm(), 0.0);
    let c = &imp.compression;
    let dk_friction =
        || imp.contact_work - c.w_c - c.w_r <= work_tolerance(qm, before[0], before[1]) + LAW_TOLERANCE * (c.w_c.abs() + c.w_r.abs());
    // The record against the compression recomputed from the velocity before (issue 81).
    let record_is_recomputed = || {
        compression_of(qm, mu, before).is_some_and(|(p_c, w_c)| {
            near(c.p_c, p_c, p_c.abs(), 0.0) && near(c.w_c, w_c, w_c.abs(), work_tolerance(qm, before[0], before[1]))
        })
    };
    use Resolution as R;
    match imp.resolution {
        R::NewtonSticking | R::NewtonSliding if !near(after[1], -e * imp.v_n_min, v_scale, v_floor) => Some(Breach::NormalVelocity),
        R::NewtonSticking if !near(after[0], 0.0, v_scale, v_floor) => Some(Breach::SlipLeft),
        R::NewtonSliding if !on_edge || p[0] * after[0] > 0.0 => Some(Breach::Edge),
        R::PoissonDarbouxKeller | R::NewtonDarbouxKeller if !near(p[1], (1.0 + e) * c.p_c, p[1].abs(), 0.0) => Some(Breach::NormalImpulse),
        R::EnergeticDarbouxKeller | R::NewtonFallback | R::PoissonFallback
            if !near(c.w_r, -e * e * c.w_c, c.w_c.abs(), work_tolerance(qm, before[0], before[1])) =>
        {
            Some(Breach::NormalWork)
        }
        R::PoissonDarbouxKeller | R::NewtonDarbouxKeller | R::EnergeticDarbouxKeller | R::NewtonFallback | R::PoissonFallback
            if !dk_friction() =>
        {
            Some(Breach::FrictionWork)
        }
        R::PoissonDarbouxKeller | R::NewtonDarbouxKeller | R::EnergeticDarbouxKeller | R::NewtonFallback | R::PoissonFallback
            if !record_is_recomputed() =>
        {
            Some(Breach::Compression)
        }
        R::PlasticIwc if c.p_c != 0.0 && !record_is_recomputed() => Some(Breach::Compression),
        R::PlasticIwc if !near(after[1], 0.0, v_scale, v_floor) => Some(Breach::NormalVelocity),
        // Its sticking impulse (one phase, no compression record) stops the slip; its
        // Darboux-Keller form (where that impulse leaves the cone) is Poisson's with e = 0.
        R::PlasticIwc if c.p_c == 0.0 && !near(after[0], 0.0, v_scale, v_floor) => Some(Breach::SlipLeft),
        R::PlasticIwc if c.p_c != 0.0 && !near(p[1], c.p_c, p[1].abs(), 0.0) => Some(Breach::NormalImpulse),
        R::PlasticIwc if c.p_c != 0.0 && !dk_friction() => Some(Breach::FrictionWork),
        R::TangentialImpact | R::IwcAtPZero if !near(after[0], 0.0, v_scale, v_floor) => Some(Breach::SlipLeft),
        R::TangentialImpact | R::IwcAtPZero if !on_edge || p[0] * before[0] > 0.0 => Some(Breach::Edge),
        _ => None,
    }
}

#[cfg(test)]
#[path = "prescription_tests.rs"]
mod tests;
