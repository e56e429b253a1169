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

use nalgebra::{Matrix2, Vector2};
use shared::SlipDirection;

/// The impact law, a first-class scenario parameter (`plant.impact_law`) and
/// command-line option (`--impact-law newton|poisson|energetic`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ImpactLaw {
    /// Restitution of the normal velocity (`e` is Newton's coefficient `e_n`);
    /// falls back to [`ImpactLaw::Energetic`] where it would create energy.
    Newton,
    /// Restitution of the normal impulse via Darboux-Keller (`e` is Poisson's
    /// coefficient); falls back to [`ImpactLaw::Energetic`] where it would create energy.
    Poisson,
    /// Stronge's energetic restitution via Darboux-Keller (`e` is the energetic
    /// coefficient `e_*`): never creates energy.
    Energetic,
}

impl ImpactLaw {
    /// Every law, in documentation order.
    pub const ALL: [ImpactLaw; 3] = [Self::Newton, Self::Poisson, Self::Energetic];

    /// Lower-case name (`newton`, `poisson`, `energetic`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Newton => "newton",
            Self::Poisson => "poisson",
            Self::Energetic => "energetic",
        }
    }
}

impl std::fmt::Display for ImpactLaw {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What the impact without collision leaves behind (scenario `plant.iwc`,
/// command-line `--iwc restitution|plastic`; module documentation).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum IwcRule {
    /// The impact law's restitution acts on the compression the tangential impact
    /// creates: the tip leaves the belt (`v_n = -e v_n,min > 0` for Newton), as the
    /// paper's "z_n_dot turns from zero to positive" describes.
    #[default]
    Restitution,
    /// The tip is left stuck tangentially with `v_n = 0` (Newton's law applied to the
    /// zero approach velocity; Moreau-Jean time-steppers).
    Plastic,
}

impl IwcRule {
    /// Both rules.
    pub const ALL: [IwcRule; 2] = [Self::Restitution, Self::Plastic];

    /// Lower-case name (`restitution`, `plastic`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Restitution => "restitution",
            Self::Plastic => "plastic",
        }
    }
}

impl std::fmt::Display for IwcRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How an impulse was obtained (for event logs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Resolution {
    /// Newton's law with the sticking impulse inside the cone.
    NewtonSticking,
    /// Newton's law with the impulse on the cone's edge.
    NewtonSliding,
    /// Newton's law, impulse from the Darboux-Keller process (edge impulse impossible, `p <= 0`).
    NewtonDarbouxKeller,
    /// Poisson's law by Darboux-Keller shock dynamics.
    PoissonDarbouxKeller,
    /// Stronge's energetic law by Darboux-Keller shock dynamics.
    EnergeticDarbouxKeller,
    /// Newton's impulse would have created energy: resolved by the energetic law.
    NewtonFallback,
    /// Poisson's impulse would have created energy: resolved by the energetic law.
    PoissonFallback,
    /// An impact without collision under [`IwcRule::Plastic`]: the sticking impulse.
    PlasticIwc,
    /// The tangential impact that resolves a dynamic jam ([`jam`]).
    TangentialImpact,
}

impl Resolution {
    /// Whether the law's own impulse would have created energy and the energetic
    /// law was used instead.
    pub fn is_fallback(self) -> bool {
        matches!(self, Self::NewtonFallback | Self::PoissonFallback)
    }
}

/// The result of an impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impulse {
    /// Impulse on the tip `[P_t, P_n]`, N s.
    pub p: Vector2<f64>,
    /// Tip velocity change `Q P`, `[dv_t, dv_n]`, m/s.
    pub dv: Vector2<f64>,
    /// Deepest normal velocity reached during compression (m/s; `<= 0`).
    pub v_n_min: f64,
    /// Work of the impulse on the relative motion, `W = int v_rel . dP` (J): minus the
    /// energy the contact dissipates. An admissible impact has `W <= 0`. The belt is
    /// an infinite mass moving at constant speed, so it may feed the arm's kinetic
    /// energy (by `v_belt P_t`); only the contact itself must not create energy
    /// (Stronge 2000, sec. 4.4). For a one-phase impulse `W = P . (v- + v+)/2`;
    /// Darboux-Keller sums it phase by phase.
    pub contact_work: f64,
    /// Which branch of the law produced it.
    pub resolution: Resolution,
}

/// Why an impact could not be resolved.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ImpactError {
    /// Compression never ends: slip continues with `p <= 0` and friction cannot stop it.
    #[error("impact jam: compression does not end (p = {p}, slip cannot be stopped)")]
    Jam {
        /// `p` of the slip phase that never ends, 1/kg.
        p: f64,
    },
    /// A velocity or `Q` entry is not finite.
    #[error("impact with non-finite input")]
    NonFinite,
}

/// Relative slip speed below which the tip counts as not slipping during an impact, m/s.
const V_EPS: f64 = 1e-12;

/// How the Darboux-Keller process ends its restitution phase.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Termination {
    /// Poisson: at the normal impulse `(1 + e) P_c`.
    Poisson(f64),
    /// Stronge: when the normal work reaches `(1 - e^2) W_n(P_c)`.
    Energetic(f64),
}

/// Largest contact work (J) counted as rounding for an impact with relative
/// velocity `[v_r, v_n]` (m/s) and tip inverse inertia `qm` (1/kg): `1e-12` of the
/// kinetic-energy scale `(v_r^2 + v_n^2) / (2 |Q|)`, `|Q|` the Frobenius norm.
/// A larger positive [`Impulse::contact_work`] is an energy-creating impact.
pub fn work_tolerance(qm: &Matrix2<f64>, v_r: f64, v_n: f64) -> f64 {
    let q = qm.norm();
    if q > 0.0 { 0.5e-12 * (v_r * v_r + v_n * v_n) / q } else { 0.0 }
}

/// Darboux-Keller shock dynamics (Poisson restitution `e`) for a tip with relative
/// tangential velocity `v_r` and normal velocity `v_n` (m/s), friction `mu`, tip
/// inverse inertia `qm` (1/kg, symmetric positive definite).
///
/// Returns the impulse; zero if the tip is not approaching (`v_n >= 0` and the
/// normal reaction would separate it). Errors: [`ImpactError`].
pub fn darboux_keller(qm: &Matrix2<f64>, mu: f64, v_r: f64, v_n: f64, e: f64) -> Result<Impulse, ImpactError> {
    shock(qm, mu, v_r, v_n, Termination::Poisson(e))
}

/// Darboux-Keller shock dynamics ended by Stronge's energetic restitution `e`
/// (module documentation); arguments, result and errors as [`darboux_keller`].
/// The contact work is `<= 0` up to rounding for any `Q`, `mu` and slip process.
pub fn energetic(qm: &Matrix2<f64>, mu: f64, v_r: f64, v_n: f64, e: f64) -> Result<Impulse, ImpactError> {
    let mut imp = shock(qm, mu, v_r, v_n, Termination::Energetic(e))?;
    imp.resolution = Resolution::EnergeticDarbouxKeller;
    Ok(imp)
}

/// Normal impulse (N s) after which the normal work `v P + dv P^2 / 2` of a phase
/// starting at normal velocity `v >= 0` with slope `dv` reaches `r >= 0` (J); where
/// the phase cannot deliver it (`dv < 0`), the impulse at which `v_n` reaches 0.
fn energetic_step(v: f64, dv: f64, r: f64) -> f64 {
    if r <= 0.0 {
        return 0.0;
    }
    let disc = v * v + 2.0 * dv * r;
    if disc < 0.0 {
        return (-v / dv).max(0.0);
    }
    // The root of dv x^2 / 2 + v x - r = 0 in its cancellation-free form.
    let den = v + disc.sqrt();
    if den > 0.0 { 2.0 * r / den } else { f64::INFINITY }
}

/// The Darboux-Keller process (module documentation) ended by `term`.
fn shock(qm: &Matrix2<f64>, mu: f64, v_r: f64, v_n: f64, term: Termination) -> Result<Impulse, ImpactError> {
    if !(v_r.is_finite() && v_n.is_finite() && qm.iter().all(|x| x.is_finite())) {
        return Err(ImpactError::NonFinite);
    }
    let (q11, q12, q22) = (qm[(0, 0)], qm[(0, 1)], qm[(1, 1)]);
    let det = q11 * q22 - q12 * q12;
    let can_stick = q12.abs() <= mu * q11;
    // Phase slopes per unit normal impulse: (d v_r, d v_n, d P_t).
    let slope = |slip: Option<f64>| match slip {
        Some(s) => (q12 - mu * s * q11, q22 - mu * s * q12, -mu * s),
        None => (0.0, det / q11, -q12 / q11),
    };
    let start_phase = |v_r: f64| -> Option<f64> {
        if v_r.abs() > V_EPS {
            Some(v_r.signum())
        } else if can_stick {
            None
        } else {
            Some(q12.signum())
        }
    };
    let (mut vr, mut vn, mut pn, mut pt) = (v_r, v_n, 0.0_f64, 0.0_f64);
    let mut phase = start_phase(vr);
    let mut v_n_min = vn.min(0.0);
    // Not approaching and the first phase would separate: no impact.
    if vn >= 0.0 && slope(phase).1 >= 0.0 {
        return Ok(Impulse {
            p: Vector2::zeros(),
            dv: Vector2::zeros(),
            v_n_min: 0.0,
            contact_work: 0.0,
            resolution: Resolution::PoissonDarbouxKeller,
        });
    }
    let mut compression = true;
    let mut pn_end = f64::INFINITY;
    // Normal work int v_n dP_n so far, and its target at the end (energetic law).
    let (mut w_n, mut w_n_end) = (0.0_f64, 0.0_f64);
    let mut work = 0.0;
    // Each phase ends slip or compression or the impact, so a few phases suffice.
    for _ in 0..8 {
        let (dvr, dvn, dpt) = slope(phase);
        let to_stop = match phase {
            Some(s) if s * dvr < 0.0 => -vr / dvr,
            _ => f64::INFINITY,
        };
        let to_compressed = if compression && dvn > 0.0 { (-vn / dvn).max(0.0) } else { f64::INFINITY };
        let to_end = match (compression, term) {
            (true, _) => f64::INFINITY,
            (false, Termination::Poisson(_)) => (pn_end - pn).max(0.0),
            (false, Termination::Energetic(_)) => energetic_step(vn, dvn, w_n_end - w_n),
        };
        let step = to_stop.min(to_compressed).min(to_end);
        if !step.is_finite() {
            return Err(ImpactError::Jam { p: dvn });
        }
        // Velocities are linear in P_n within the phase: trapezoid is exact.
        work += step * (dpt * (vr + 0.5 * dvr * step) + (vn + 0.5 * dvn * step));
        w_n += step * (vn + 0.5 * dvn * step);
        vr += dvr * step;
        vn += dvn * step;
        pn += step;
        pt += dpt * step;
        v_n_min = v_n_min.min(vn);
        if step == to_end {
            break;
        }
        if step == to_compressed {
            vn = 0.0;
            compression = false;
            let e = match term {
                Termination::Poisson(e) => {
                    pn_end = (1.0 + e) * pn;
                    e
                }
                Termination::Energetic(e) => {
                    w_n_end = (1.0 - e * e) * w_n;
                    e
                }
            };
            if e <= 0.0 {
                break;
            }
            continue;
        }
        // Slip stopped: stick if the cone allows, otherwise slip the other way.
        vr = 0.0;
        phase = start_phase(0.0);
    }
    let p = Vector2::new(pt, pn);
    Ok(Impulse { p, dv: qm * p, v_n_min, contact_work: work, resolution: Resolution::PoissonDarbouxKeller })
}

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

/// A one-phase impulse `p` applied to relative velocity `v = [v_r, v_n]`.
fn one_phase(qm: &Matrix2<f64>, p: Vector2<f64>, v: Vector2<f64>, v_n_min: f64, resolution: Resolution) -> Impulse {
    let dv = qm * p;
    Impulse { p, dv, v_n_min, contact_work: p.dot(&(v + v + dv)) * 0.5, resolution }
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
                one_phase(qm, p, Vector2::new(v_r, 0.0), compression.v_n_min, Resolution::NewtonDarbouxKeller)
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
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Kinetic energy change of a one-phase impact seen from a frame moving with
    /// the belt: `dT = P . (v- + v+) / 2` (exact for an impulse at fixed configuration).
    fn energy_change(imp: &Impulse, v: Vector2<f64>) -> f64 {
        imp.p.dot(&(v + v + imp.dv)) * 0.5
    }

    fn spd(a: f64, b: f64, c: f64) -> Matrix2<f64> {
        // Q = L L^T with L lower-triangular, positive diagonal.
        let l = Matrix2::new(a, 0.0, b, c);
        l * l.transpose()
    }

    #[test]
    fn frictionless_poisson_equals_newton() {
        let qm = spd(3.0, 1.0, 2.0);
        let n = touchdown(&qm, 0.0, 0.3, -0.5, ImpactLaw::Newton, 0.5).unwrap();
        let p = touchdown(&qm, 0.0, 0.3, -0.5, ImpactLaw::Poisson, 0.5).unwrap();
        assert!((n.p - p.p).norm() < 1e-12);
        assert!((n.dv[1] - 0.75).abs() < 1e-12); // v_n+ = -e v_n- = 0.25
    }

    #[test]
    fn head_on_sticking_impact_is_newton_exact() {
        // Diagonal Q with enough friction: the tip sticks, v_n+ = -e v_n-.
        let qm = Matrix2::new(2.0, 0.0, 0.0, 1.0);
        for law in [ImpactLaw::Newton, ImpactLaw::Poisson] {
            let imp = touchdown(&qm, 1.0, 0.1, -1.0, law, 0.3).unwrap();
            assert!((0.1 + imp.dv[0]).abs() < 1e-12, "{law:?} slip stopped");
            assert!((-1.0 + imp.dv[1] - 0.3).abs() < 1e-12, "{law:?}: v_n+ = 0.3");
        }
    }

    #[test]
    fn iwc_stops_the_slip_and_lifts_the_tip_off() {
        // A Q with strong coupling so that p(+) < 0 at mu = 0.8.
        let qm = spd(2.0, 0.5, 0.1);
        let s = SlipDirection::Positive;
        let mu = 0.8;
        assert!(shared::contact::p_of(&qm, mu, s) < 0.0);
        for law in ImpactLaw::ALL {
            let imp = without_collision(&qm, mu, 0.4, law, 0.5, IwcRule::Restitution).unwrap();
            assert!((0.4 + imp.dv[0]).abs() < 1e-12, "{law:?}: slip stopped");
            assert!(imp.dv[1] > 0.0, "{law:?}: lifts off");
            assert!(imp.v_n_min < 0.0, "{law:?}: compression");
            assert!(imp.contact_work <= 1e-12, "{law:?}: work {}", imp.contact_work);
            let with_zero = without_collision(&qm, mu, 0.4, law, 0.0, IwcRule::Restitution).unwrap();
            assert!(with_zero.dv[1].abs() < 1e-12, "{law:?}: e = 0 leaves the tip on the belt");
            // The plastic rule: stuck tangentially, v_n = 0, whatever the law and e.
            for e in [0.0, 0.5, 1.0] {
                let plastic = without_collision(&qm, mu, 0.4, law, e, IwcRule::Plastic).unwrap();
                assert_eq!(plastic.resolution, Resolution::PlasticIwc);
                assert!((0.4 + plastic.dv[0]).abs() < 1e-12 && plastic.dv[1].abs() < 1e-12, "{law:?} e {e}: {:?}", plastic.dv);
                assert!(plastic.contact_work < 0.0 && in_cone(&plastic.p, mu));
                assert!((plastic.p - with_zero.p).norm() < 1e-12, "the e = 0 restitution result");
            }
        }
    }

    #[test]
    fn without_friction_the_three_laws_agree() {
        // mu = 0: one phase, and Stronge's, Poisson's and Newton's coefficients coincide.
        let qm = spd(1.5, -0.7, 0.9);
        for e in [0.0, 0.3, 1.0] {
            let v: Vec<Impulse> = ImpactLaw::ALL.iter().map(|&law| touchdown(&qm, 0.0, 0.2, -0.8, law, e).unwrap()).collect();
            for imp in &v {
                assert!((-0.8 + imp.dv[1] - 0.8 * e).abs() < 1e-12, "v_n+ = -e v_n-: {imp:?}");
                assert!((imp.p - v[0].p).norm() < 1e-12);
            }
            assert_eq!(v[2].resolution, Resolution::EnergeticDarbouxKeller);
        }
    }

    #[test]
    fn energetic_work_is_the_restitution_fraction_of_compression() {
        // A slip that does not stop: the normal work in restitution is e^2 of
        // compression's, W_n = (1 - e^2) W_c, checked against P_n and v_n directly.
        let qm = spd(1.0, 0.3, 1.2);
        let (mu, v_r, v_n, e) = (0.2, 2.0, -0.5, 0.6);
        let imp = energetic(&qm, mu, v_r, v_n, e).unwrap();
        let s = 1.0;
        let dvn = qm[(1, 1)] - mu * s * qm[(1, 0)];
        // One phase: v_n(P) = v_n + dvn P; W_n(P) = v_n P + dvn P^2 / 2.
        let w = |p: f64| v_n * p + 0.5 * dvn * p * p;
        let p_c = -v_n / dvn;
        assert!(v_r + (qm[(0, 1)] - mu * s * qm[(0, 0)]) * imp.p[1] > 0.0, "still slipping");
        assert!((w(imp.p[1]) - (1.0 - e * e) * w(p_c)).abs() < 1e-12, "{} vs {}", w(imp.p[1]), (1.0 - e * e) * w(p_c));
        // Its final normal velocity: v_n+^2 = e^2 v_n-^2 for a single phase.
        assert!(((v_n + imp.dv[1]) - e * v_n.abs()).abs() < 1e-12);
    }

    proptest! {
        /// No law does positive work at a touchdown or an impact without collision
        /// (after the fallback), every impulse lies in the cone and pushes, and the
        /// tip leaves the impact not approaching the belt.
        #[test]
        fn no_impact_creates_energy(
            a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.05f64..3.0,
            mu in 0.0f64..1.5, v_r in -1.0f64..1.0, v_n in -1.0f64..0.0, e in 0.0f64..=1.0,
        ) {
            let qm = spd(a, b, c);
            for law in ImpactLaw::ALL {
                let imp = touchdown(&qm, mu, v_r, v_n, law, e);
                prop_assert!(imp.is_ok(), "{:?}", imp);
                let imp = imp.unwrap();
                prop_assert!(imp.contact_work <= work_tolerance(&qm, v_r, v_n), "{law:?}: work {} ({:?})", imp.contact_work, imp.resolution);
                prop_assert!(imp.p[1] >= 0.0);
                prop_assert!(imp.p[0].abs() <= mu * imp.p[1] * (1.0 + 1e-9) + 1e-12);
                prop_assert!(v_n + imp.dv[1] >= -1e-12, "{law:?} separates: {}", v_n + imp.dv[1]);
                if law == ImpactLaw::Energetic {
                    prop_assert_eq!(imp.resolution, Resolution::EnergeticDarbouxKeller);
                }
                // The impact without collision, where the state is inconsistent.
                if shared::contact::p_of(&qm, mu, SlipDirection::of(v_r)) < 0.0 && v_r.abs() > 1e-6 {
                    for rule in IwcRule::ALL {
                        let iwc = without_collision(&qm, mu, v_r, law, e, rule);
                        prop_assert!(iwc.is_ok(), "{:?}", iwc);
                        let iwc = iwc.unwrap();
                        prop_assert!(iwc.contact_work <= work_tolerance(&qm, v_r, 0.0), "{law:?}/{rule:?}: work {}", iwc.contact_work);
                        prop_assert!(iwc.dv[1] >= -1e-12);
                    }
                }
            }
        }

        #[test]
        fn poisson_never_gains_energy_and_respects_the_cone(
            a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.3f64..3.0,
            mu in 0.0f64..1.2, v_r in -1.0f64..1.0, v_n in -1.0f64..-0.01, e in 0.0f64..1.0,
        ) {
            let qm = spd(a, b, c);
            // With Q symmetric positive definite, compression always ends: no jam.
            let imp = darboux_keller(&qm, mu, v_r, v_n, e);
            prop_assert!(imp.is_ok(), "{:?}", imp);
            if let Ok(imp) = imp {
                prop_assert!(imp.p[1] >= 0.0);
                prop_assert!(imp.p[0].abs() <= mu * imp.p[1] * (1.0 + 1e-9) + 1e-12);
                let v_after_n = v_n + imp.dv[1];
                prop_assert!(v_after_n >= -1e-12, "separates: {}", v_after_n);
                // Poisson with Coulomb friction can create energy only with slip reversal
                // (Stronge 2000); the plant reports it. Without reversal it must not.
                let vr_after = v_r + imp.dv[0];
                let scale = 1e-9 * (v_r * v_r + v_n * v_n) / qm.norm();
                if vr_after * v_r >= 0.0 {
                    prop_assert!(imp.contact_work <= scale, "work {}", imp.contact_work);
                }
                // With one phase, the phase-wise work equals P . (v- + v+)/2.
                if mu == 0.0 {
                    prop_assert!((imp.contact_work - energy_change(&imp, Vector2::new(v_r, v_n))).abs() <= scale.max(1e-12));
                }
            }
        }

        /// Newton-Coulomb at the impulse level (module documentation, "Newton"):
        /// the impulse sticks the tip inside the cone, or lies on the cone's edge
        /// whose friction opposes the slip the impact leaves; the edge always exists
        /// for an approaching tip (`p(s) > 0` on the side the sticking impulse
        /// leaves by), so Darboux-Keller is never needed at a touchdown. Only an
        /// impact that would create energy (a slip reversed by friction itself,
        /// Kane and Levinson 1985) falls back to the energetic law.
        #[test]
        fn newton_friction_never_points_along_the_slip_it_leaves(
            a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.05f64..3.0,
            mu in 0.0f64..1.5, v_r in -1.0f64..1.0, v_n in -1.0f64..-1e-3, e in 0.0f64..=1.0,
        ) {
            let qm = spd(a, b, c);
            let imp = newton_touchdown(&qm, mu, v_r, v_n, e).unwrap();
            let v_r_after = v_r + imp.dv[0];
            let scale = v_r.abs().max(v_n.abs());
            match imp.resolution {
                Resolution::NewtonSticking => prop_assert!(v_r_after.abs() <= 1e-9 * scale, "sticks: v_r+ {}", v_r_after),
                Resolution::NewtonSliding => {
                    prop_assert!(imp.p[0] * v_r_after <= 0.0, "P_t {} along v_r+ {}", imp.p[0], v_r_after);
                    prop_assert!((imp.p[0].abs() - mu * imp.p[1]).abs() <= 1e-9 * mu * imp.p[1] + 1e-15, "on the edge");
                }
                other => prop_assert!(false, "{:?} at a touchdown", other),
            }
            let used = touchdown(&qm, mu, v_r, v_n, ImpactLaw::Newton, e).unwrap();
            if used.resolution != Resolution::NewtonFallback {
                prop_assert_eq!(used, imp);
            } else {
                prop_assert!(imp.contact_work > work_tolerance(&qm, v_r, v_n));
            }
        }

        #[test]
        fn newton_sticking_and_edge_impulses_restore_normal_velocity(
            a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.3f64..3.0,
            mu in 0.0f64..1.2, v_r in -1.0f64..1.0, v_n in -1.0f64..-0.01, e in 0.0f64..1.0,
        ) {
            let qm = spd(a, b, c);
            let imp = touchdown(&qm, mu, v_r, v_n, ImpactLaw::Newton, e);
            prop_assert!(imp.is_ok(), "{:?}", imp);
            let imp = imp.unwrap();
            if matches!(imp.resolution, Resolution::NewtonSticking | Resolution::NewtonSliding) {
                prop_assert!((v_n + imp.dv[1] + e * v_n).abs() < 1e-9);
                prop_assert!(imp.p[1] >= 0.0);
                prop_assert!(imp.p[0].abs() <= mu * imp.p[1] * (1.0 + 1e-9) + 1e-12);
            }
        }
    }
}

#[cfg(test)]
mod kane {
    use super::*;

    /// Kane's classic observation (Kane and Levinson, "Dynamics Online", 1985; Stronge
    /// 2000, sec. 5.4): Newton's restitution with Coulomb friction can create energy
    /// when the slip reverses during the impact. Newton's own impulse shows it; the
    /// law then falls back to the energetic one, and Poisson's does not create it here.
    #[test]
    fn newton_with_friction_can_create_energy_and_falls_back() {
        let mut found = None;
        'search: for a in [0.5, 1.0, 2.0] {
            for b in [-1.5, -1.0, -0.5, 0.5, 1.0, 1.5] {
                for c in [0.2, 0.5, 1.0] {
                    let l = Matrix2::new(a, 0.0, b, c);
                    let qm = l * l.transpose();
                    for mu in [0.2, 0.5, 0.8] {
                        for v_r in [-0.5, -0.1, 0.1, 0.5] {
                            let imp = newton_touchdown(&qm, mu, v_r, -1.0, 0.9).unwrap();
                            if imp.contact_work > 1e-6 {
                                found = Some((qm, mu, v_r, imp));
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        let (qm, mu, v_r, imp) = found.expect("a Newton impact that creates energy");
        assert_eq!(imp.resolution, Resolution::NewtonSliding);
        let dk = darboux_keller(&qm, mu, v_r, -1.0, 0.9).unwrap();
        assert!(dk.contact_work <= 1e-12, "Poisson dissipates at the same impact: {}", dk.contact_work);
        let used = touchdown(&qm, mu, v_r, -1.0, ImpactLaw::Newton, 0.9).unwrap();
        assert_eq!(used.resolution, Resolution::NewtonFallback);
        assert_eq!(used.p, energetic(&qm, mu, v_r, -1.0, 0.9).unwrap().p);
        assert!(used.contact_work <= 0.0, "{}", used.contact_work);
    }
}
