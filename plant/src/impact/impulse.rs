//! What an impact returns ([`super`] documentation): the impulse with its velocity
//! change, its contact work and how it was obtained ([`Impulse`], [`Resolution`]),
//! why an impact could not be resolved ([`ImpactError`]), and the work counted as
//! rounding ([`work_tolerance`]), and the Darboux-Keller process's two phases
//! ([`Compression`]).

use nalgebra::{Matrix2, Vector2};

/// How an impulse was obtained (for event logs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Resolution {
    /// Newton's law with the sticking impulse inside the cone (at a touchdown, or at
    /// an impact without collision with `v_n+ = -e v_n,min`).
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
    /// An impact without collision under [`IwcRule::Plastic`](super::IwcRule::Plastic): the sticking impulse.
    PlasticIwc,
    /// The tangential impact that resolves a dynamic jam ([`jam`](super::jam)).
    TangentialImpact,
    /// A velocity projection onto the contact constraint at an event (the Zeno
    /// rule's removal of a normal velocity residue, a small slip stopped at rest):
    /// the smallest kinetic-energy correction, an impulse at the tip (issue 67).
    Projection,
    /// The impact without collision at the singular point `p = b = 0`
    /// ([`at_p_zero`](super::at_p_zero)): the edge impulse that stops the slip with
    /// `v_n` unchanged, the limit of both IWC rules there.
    IwcAtPZero,
    /// A bridge step's Moreau-Jean contact impulse, booked as an impulse
    /// ([`crate::EventKind::BridgeImpulse`]): the solution of the step's one-contact
    /// problem ([`crate::moreau_jean::contact_impulse`]), in the cone by construction.
    BridgeStep,
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
    /// The normal impulse and work of the Darboux-Keller process's compression and
    /// restitution (all zero for an impulse not obtained by that process).
    pub compression: Compression,
}

/// The two phases of a Darboux-Keller impact in the normal impulse `P_n`
/// (Stronge 2000, ch. 5): what Poisson's law ends restitution by (`P_n = (1 + e)
/// P_c`) and what the energetic law does (`W_r = -e^2 W_c`). The ledger holds an
/// impulse to them ([`breach`](super::breach)).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Compression {
    /// The normal impulse at the end of compression, `P_c` (N s, `>= 0`).
    pub p_c: f64,
    /// The normal work in compression, `W_c = int_0^P_c v_n dP_n` (J, `<= 0`).
    pub w_c: f64,
    /// The normal work in restitution, `W_r = int_P_c^P_n v_n dP_n` (J, `>= 0`).
    pub w_r: f64,
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

/// Largest contact work (J) counted as rounding for an impact with relative
/// velocity `[v_r, v_n]` (m/s) and tip inverse inertia `qm` (1/kg): `1e-12` of the
/// kinetic-energy scale `(v_r^2 + v_n^2) / (2 |Q|)`, `|Q|` the Frobenius norm.
/// A larger positive [`Impulse::contact_work`] is an energy-creating impact.
pub fn work_tolerance(qm: &Matrix2<f64>, v_r: f64, v_n: f64) -> f64 {
    let q = qm.norm();
    if q > 0.0 { 0.5e-12 * (v_r * v_r + v_n * v_n) / q } else { 0.0 }
}

/// A one-phase impulse `p` applied to relative velocity `v = [v_r, v_n]`.
pub(super) fn one_phase(qm: &Matrix2<f64>, p: Vector2<f64>, v: Vector2<f64>, v_n_min: f64, resolution: Resolution) -> Impulse {
    let dv = qm * p;
    Impulse { p, dv, v_n_min, contact_work: p.dot(&(v + v + dv)) * 0.5, resolution, compression: Compression::default() }
}
