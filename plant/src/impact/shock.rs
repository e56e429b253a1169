//! Darboux-Keller shock dynamics ([`super`] documentation, "Poisson" and
//! "Energetic"): the impact integrated in the normal impulse, phase by phase,
//! ended by Poisson's restitution ([`darboux_keller`]) or Stronge's energetic one
//! ([`energetic`]).

use nalgebra::{Matrix2, Vector2};

use super::impulse::{Compression, ImpactError, Impulse, Resolution};

/// Relative slip speed below which the tip counts as not slipping during an impact, m/s.
pub(super) const V_EPS: f64 = 1e-12;

/// How the Darboux-Keller process ends its restitution phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Termination {
    /// Poisson: at the normal impulse `(1 + e) P_c`.
    Poisson(f64),
    /// Stronge: when the normal work reaches `(1 - e^2) W_n(P_c)`.
    Energetic(f64),
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
pub(super) fn shock(qm: &Matrix2<f64>, mu: f64, v_r: f64, v_n: f64, term: Termination) -> Result<Impulse, ImpactError> {
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
            compression: Compression::default(),
        });
    }
    let mut compression = true;
    let mut pn_end = f64::INFINITY;
    // Normal work int v_n dP_n so far, and its target at the end (energetic law).
    let (mut w_n, mut w_n_end) = (0.0_f64, 0.0_f64);
    let mut work = 0.0;
    // Where compression ended: the normal impulse and work then.
    let (mut p_c, mut w_c) = (0.0_f64, 0.0_f64);
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
            (p_c, w_c) = (pn, w_n);
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
    if compression {
        // The phases ran out within compression (never seen): recorded as it is, so
        // that the ledger's check of the law (`breach`) sees a restitution never made.
        (p_c, w_c) = (pn, w_n);
    }
    let p = Vector2::new(pt, pn);
    let phases = Compression { p_c, w_c, w_r: w_n - w_c };
    Ok(Impulse { p, dv: qm * p, v_n_min, contact_work: work, resolution: Resolution::PoissonDarbouxKeller, compression: phases })
}
