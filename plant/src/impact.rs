//! Impact laws: the impulse at touchdown and the impact without collision (IWC).
//!
//! Everything here happens at a fixed configuration, so the tip-space inverse
//! inertia `Q = J M^-1 J^T` (paper eq. 3) is constant during the impact and an
//! impulse `P = [P_t, P_n]` (N s) changes the tip velocity by `Q P`. Velocities are
//! `v_r = z_t_dot - v_belt` (relative tangential) and `v_n = z_n_dot`, in m/s.
//!
//! Laws (the scenario's `impact_law`, coefficient `e` in [0, 1]):
//! - **Newton** (restitution of the normal velocity, `v_n+ = -e v_n-`), with
//!   Coulomb's law at the impulse level, a complementarity problem in the
//!   post-impact velocity (Moreau 1988; Glocker and Pfeiffer 1995; Glocker 2001;
//!   Brogliato, "Nonsmooth Mechanics", 3rd ed., 2016, ch. 4): `P_n >= 0` with
//!   `v_n+ = -e v_n-`, and `P_t` in the cone `|P_t| <= mu P_n`, opposing the slip
//!   *after* the impact, `P_t = -mu sign(v_r+) P_n` when `v_r+ != 0`. Its solution is
//!   the sticking impulse `P = Q^-1 [-v_r, -(1 + e) v_n]` if that lies in the cone,
//!   otherwise the impulse on the edge the sticking impulse leaves the cone by,
//!   `P_t = -mu s P_n`, `P_n = -(1 + e) v_n / p(s)` with `s = -sign P_t,stick` and
//!   `p(s) = Q_22 - mu s Q_21` (paper eq. 7). It exists and is unique for one
//!   contact with `Q` positive definite: on the line of impulses with
//!   `v_n+ = -e v_n-`, which passes through the cone's interior at `P_t = 0`, `v_r+`
//!   grows with `P_t` at the rate `det Q / Q_22 > 0`, so the edge crossed on the way
//!   to the sticking impulse has `p(s) > 0` and leaves `sign v_r+ = s`. Taking `s`
//!   from the slip *before* the impact instead is wrong exactly when the normal
//!   impulse reverses the slip through `Q_12`: friction then points along the slip
//!   it leaves. (Darboux-Keller with `e` as Poisson's coefficient remains as a
//!   guard for `p(s) <= 0`, which rounding alone could produce.)
//! - **Poisson** (restitution of the normal impulse, `P_n = (1 + e) P_c`, where
//!   `P_c` ends compression), integrated by Darboux-Keller shock dynamics
//!   (Keller 1986; Stronge, "Impact Mechanics", 2000, ch. 5): `P_n` is the time-like
//!   variable, friction stays on the cone's edge while the tip slips and inside it
//!   while it sticks, and slip stops, sticks or reverses as the velocity demands.
//!   With `Q` constant the velocities are piecewise linear in `P_n`; this module
//!   integrates them exactly, phase by phase.
//! - **Energetic** (Stronge's energetic restitution, "Impact Mechanics", 2000,
//!   sec. 5.3 and ch. 5; Stronge 1990): the same Darboux-Keller process, ended when
//!   the work of the normal impulse in restitution equals `e^2` times its work in
//!   compression (`W_n(P_f) = (1 - e^2) W_n(P_c)`). The normal work then never
//!   exceeds zero and friction on the cone's edge opposes the slip, so the contact
//!   does no positive work whatever the slip does (Stronge 2000, sec. 5.3): the one
//!   law that is energetically consistent by construction.
//!
//! **Fallback.** Newton's law with friction can create energy on a multibody
//! system (Kane and Levinson 1985; Stronge 2000, sec. 5.4), and Poisson's can when
//! the slip stops or reverses in restitution (Stronge 1991). Where either law's
//! impulse would do positive work on the relative motion ([`work_tolerance`]), the
//! impact is resolved by the energetic law with the same coefficient instead and
//! marked ([`Resolution::NewtonFallback`], [`Resolution::PoissonFallback`]); the
//! plant counts these. Where the law is consistent its own definition is kept.
//! For a frictionless impact, or one that sticks throughout, the three
//! coefficients coincide (Stronge 2000, sec. 5.3), so the fallback changes the
//! coefficient's meaning least where it is needed.
//!
//! The IWC (Génot and Brogliato 1998; Zhao et al. 2008): a tip sliding in an
//! inconsistent state (`p < 0`, `b < 0`) with `v_n = 0`. Darboux-Keller resolves it
//! with no extra assumption: because `p(s) < 0`, the normal impulse first drives
//! the tip *into* the belt (compression with `v_n` decreasing from 0) while friction
//! stops the slip (a tangential impact of maximum dissipation, as Zhao et al.
//! observed); once the tip sticks, `d v_n / d P_n = det Q / Q_11 > 0` ends the
//! compression, and restitution throws the tip off the belt. Poisson uses exactly
//! this. Newton, whose approach velocity is zero here, is applied to the compression
//! the tangential impact itself creates: after it the tip sticks tangentially with
//! `v_n+ = -e v_n,min`, `v_n,min` being the deepest normal velocity of the
//! Darboux-Keller compression (if that sticking impulse leaves the cone, Poisson's
//! result is used). With `e = 0` both laws leave the tip on the belt, stuck.
//! This is the *restitution* IWC rule ([`IwcRule::Restitution`], the default).
//! The *plastic* rule ([`IwcRule::Plastic`]; Moreau-Jean time-steppers with
//! Newton's law, and event-driven codes that apply Newton's law to the zero
//! approach velocity, e.g. Acary and Brogliato 2008, ch. 10) leaves the tip stuck
//! tangentially with `v_n = 0` whatever the law and `e`: the sticking impulse
//! `P = Q^-1 [-v_r, 0]`, which lies in the cone exactly when `p(s) <= 0`.

mod impulse;
mod law;
mod prescription;
mod shock;

use nalgebra::{Matrix2, Vector2};
use shared::SlipDirection;

pub use impulse::{Compression, ImpactError, Impulse, Resolution, work_tolerance};
pub use law::{ImpactLaw, IwcRule};
pub use prescription::{Breach, LAW_TOLERANCE, breach};
pub use shock::{darboux_keller, energetic};

use impulse::one_phase;
use shock::{Termination, V_EPS, shock};

/// The tangential impact that resolves a dynamic jam (docs/plant.md "The jam
/// corner"): a tip sliding with relative velocity `v_r` (m/s) whose `p` has fallen
/// to 0+ with `b < 0`, so that `f_n = -b / p` grows without bound. In the limit the
/// normal force acts as an impulse at a fixed configuration that leaves `v_n`
/// unchanged (`d v_n / d P_n = p = 0`) while friction on the cone's edge stops the
/// slip (Génot and Brogliato 1999; Zhao et al. 2008 measured such a tangential
/// impact on this arm; Or and Rimon 2012): `P_t = -mu s P_n`,
/// `P_n = -v_r / (Q_12 - mu s Q_11)`, `s = sign v_r`. The plant applies it when
/// `f_n` reaches `jam_load m g`, where it changes `v_n` by `p P_n >= 0` (which
/// vanishes as `jam_load` grows).
///
/// Errors: [`ImpactError::NonFinite`]; [`ImpactError::Jam`] when friction on the
/// cone's edge cannot stop the slip (`s (Q_12 - mu s Q_11) >= 0`: the slip would
/// grow under the normal impulse, and no impulse ends the jam).
pub fn jam(qm: &Matrix2<f64>, mu: f64, v_r: f64) -> Result<Impulse, ImpactError> {
    if !(v_r.is_finite() && qm.iter().all(|x| x.is_finite())) {
        return Err(ImpactError::NonFinite);
    }
    let (q11, q12, q22) = (qm[(0, 0)], qm[(0, 1)], qm[(1, 1)]);
    if v_r.abs() <= V_EPS {
        return Ok(one_phase(qm, Vector2::zeros(), Vector2::new(v_r, 0.0), 0.0, Resolution::TangentialImpact));
    }
    let s = v_r.signum();
    let dvr = q12 - mu * s * q11;
    if s * dvr >= 0.0 {
        return Err(ImpactError::Jam { p: q22 - mu * s * q12 });
    }
    let pn = -v_r / dvr;
    let p = Vector2::new(-mu * s * pn, pn);
    Ok(one_phase(qm, p, Vector2::new(v_r, 0.0), 0.0, Resolution::TangentialImpact))
}

/// The impact without collision at the singular point, where a slide reaches
/// `p = 0` with `b = 0` and a finite normal force (docs/plant.md "The singular
/// point", issue 67): at `p = 0` a normal impulse leaves `v_n` unchanged
/// (`d v_n / d P_n = p`), so there is no compression to restitute and every IWC
/// rule ends with the same impulse, on the cone's edge, that stops the slip:
/// `P_t = -mu s P_n`, `P_n = -v_r / (Q_12 - mu s Q_11)`, `s = sign v_r` (the
/// jam's impulse, [`jam`], reached with a finite force). Taken in closed form, so
/// that the crossing gives the same impulse, to the bit, whether the locator met
/// `p = 0` or `b = 0` first (at `p` of either sign within the crossing's
/// resolution, where the Darboux-Keller process of [`without_collision`] would
/// separate at once for `p > 0` and slide on the edge for `p < 0`).
///
/// Errors: as [`jam`] ([`ImpactError::Jam`] where friction on the edge cannot
/// stop the slip; the caller then takes [`without_collision`]).
pub fn at_p_zero(qm: &Matrix2<f64>, mu: f64, v_r: f64) -> Result<Impulse, ImpactError> {
    let imp = jam(qm, mu, v_r)?;
    Ok(Impulse { resolution: Resolution::IwcAtPZero, ..imp })
}

/// Whether impulse `p = [P_t, P_n]` lies in the friction cone (with a relative slack for rounding).
fn in_cone(p: &Vector2<f64>, mu: f64) -> bool {
    p[1] >= 0.0 && p[0].abs() <= mu * p[1] * (1.0 + 1e-12)
}

/// `imp` if it does no positive work on the relative motion `[v_r, v_n]`;
/// otherwise the energetic law's impulse with the same `e`, marked `fallback`.
fn consistent_or_energetic(
    imp: Impulse,
    qm: &Matrix2<f64>,
    mu: f64,
    v_r: f64,
    v_n: f64,
    e: f64,
    fallback: Resolution,
) -> Result<Impulse, ImpactError> {
    if imp.contact_work <= work_tolerance(qm, v_r, v_n) {
        return Ok(imp);
    }
    let mut en = shock(qm, mu, v_r, v_n, Termination::Energetic(e))?;
    en.resolution = fallback;
    Ok(en)
}

/// Newton's impulse at touchdown (module documentation), before the energy check.
fn newton_touchdown(qm: &Matrix2<f64>, mu: f64, v_r: f64, v_n: f64, e: f64) -> Result<Impulse, ImpactError> {
    if !(v_r.is_finite() && v_n.is_finite()) {
        return Err(ImpactError::NonFinite);
    }
    let inv = qm.try_inverse().ok_or(ImpactError::NonFinite)?;
    let p = inv * Vector2::new(-v_r, -(1.0 + e) * v_n);
    if in_cone(&p, mu) {
        return Ok(one_phase(qm, p, Vector2::new(v_r, v_n), v_n.min(0.0), Resolution::NewtonSticking));
    }
    // The slip after the impact: the side of the cone the sticking impulse leaves
    // by (module documentation, "Newton"). Along the line of impulses that give
    // `v_n+ = -e v_n-`, `v_r+` grows with `P_t` (slope `det Q / Q_22 > 0`) and is 0 at
    // the sticking impulse, so the edge it crosses to leave the cone is the one
    // whose friction opposes the slip it leaves behind; the edge opposing the slip
    // *before* the impact would, when the normal impulse reverses the slip
    // (through `Q_12`), push along the slip after it.
    let s = SlipDirection::of(-p[0]);
    let ps = shared::contact::p_of(qm, mu, s);
    if ps > 0.0 {
        let pn = -(1.0 + e) * v_n / ps;
        let p = Vector2::new(-mu * s.sign::<f64>() * pn, pn);
        Ok(one_phase(qm, p, Vector2::new(v_r, v_n), v_n.min(0.0), Resolution::NewtonSliding))
    } else {
        let mut dk = darboux_keller(qm, mu, v_r, v_n, e)?;
        dk.resolution = Resolution::NewtonDarbouxKeller;
        Ok(dk)
    }
}

/// The impulse at touchdown for a tip arriving with `v_n < 0` (m/s) and relative
/// tangential velocity `v_r` (m/s), under `law` with coefficient `e` in [0, 1].
/// Newton's and Poisson's impulses that would create energy are replaced by the
/// energetic law's (module documentation, "Fallback").
///
/// Errors: [`ImpactError`] (non-finite input, or a Darboux-Keller jam).
pub fn touchdown(qm: &Matrix2<f64>, mu: f64, v_r: f64, v_n: f64, law: ImpactLaw, e: f64) -> Result<Impulse, ImpactError> {
    match law {
        ImpactLaw::Poisson => {
            let imp = darboux_keller(qm, mu, v_r, v_n, e)?;
            consistent_or_energetic(imp, qm, mu, v_r, v_n, e, Resolution::PoissonFallback)
        }
        ImpactLaw::Newton => {
            let imp = newton_touchdown(qm, mu, v_r, v_n, e)?;
            consistent_or_energetic(imp, qm, mu, v_r, v_n, e, Resolution::NewtonFallback)
        }
        ImpactLaw::Energetic => energetic(qm, mu, v_r, v_n, e),
    }
}

/// The impact without collision for a tip sliding at relative velocity `v_r`
/// (m/s, nonzero) with `v_n = 0` in an inconsistent state (`p(sign v_r) < 0`),
/// under `law` with coefficient `e` and the IWC rule `rule`. See the module
/// documentation for how each law and rule resolves it.
///
/// Errors: [`ImpactError`].
pub fn without_collision(qm: &Matrix2<f64>, mu: f64, v_r: f64, law: ImpactLaw, e: f64, rule: IwcRule) -> Result<Impulse, ImpactError> {
    if rule == IwcRule::Plastic {
        // The compression the tangential impact creates, for v_n,min; its e = 0 end
        // state is the same stuck tip whenever compression ends after the slip stops.
        let compression = darboux_keller(qm, mu, v_r, 0.0, 0.0)?;
        let inv = qm.try_inverse().ok_or(ImpactError::NonFinite)?;
        let p = inv * Vector2::new(-v_r, 0.0);
        if in_cone(&p, mu) {
            return Ok(one_phase(qm, p, Vector2::new(v_r, 0.0), compression.v_n_min, Resolution::PlasticIwc));
        }
        return Ok(Impulse { resolution: Resolution::PlasticIwc, ..compression });
    }
    match law {
        ImpactLaw::Poisson => {
            let imp = darboux_keller(qm, mu, v_r, 0.0, e)?;
            consistent_or_energetic(imp, qm, mu, v_r, 0.0, e, Resolution::PoissonFallback)
        }
        ImpactLaw::Energetic => energetic(qm, mu, v_r, 0.0, e),
        ImpactLaw::Newton => {
            let compression = darboux_keller(qm, mu, v_r, 0.0, 0.0)?;
            let inv = qm.try_inverse().ok_or(ImpactError::NonFinite)?;
            let p = inv * Vector2::new(-v_r, -e * compression.v_n_min);
            let imp = if in_cone(&p, mu) {
                one_phase(qm, p, Vector2::new(v_r, 0.0), compression.v_n_min, Resolution::NewtonSticking)
            } else {
                let mut dk = darboux_keller(qm, mu, v_r, 0.0, e)?;
                dk.resolution = Resolution::NewtonDarbouxKeller;
                dk
            };
            consistent_or_energetic(imp, qm, mu, v_r, 0.0, e, Resolution::NewtonFallback)
        }
    }
}

#[cfg(test)]
#[path = "impact_tests.rs"]
mod tests;
