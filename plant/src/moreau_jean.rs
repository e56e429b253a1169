//! Moreau-Jean time-stepping for the one frictional contact of the arm on the belt:
//! the scheme the plant bridges a collapsed event-driven step with
//! (docs/plant.md "The bridge"), and the rule at the singular point `p = b = 0`
//! ([`SingularRule`]).
//!
//! The scheme is the one of Moreau (1988, "Unilateral contact and dry friction in
//! finite freedom dynamics") and Jean (1999, "The non-smooth contact dynamics
//! method", Comput. Methods Appl. Mech. Engrg. 177), as Siconos implements it
//! (Acary and Brogliato, "Numerical Methods for Nonsmooth Dynamical Systems",
//! Springer 2008, ch. 7, the `MoreauJeanOSI`), linearised at the start of each
//! step of length `h`:
//!
//! - `M(q_k) (v_k+1 - v_k) = h (u - w - c)(t_k, q_k, v_k) + J(q_k)^T P_k+1` (paper eq. 1,
//!   the smooth forces explicit at the start of the step, the contact impulse `P`
//!   implicit);
//! - `q_k+1 = q_k + h ((1 - theta) v_k + theta v_k+1)`, `theta = 1/2`;
//! - the contact is active when the gap predicted half a step ahead,
//!   `z_n + H + (h / 2) v_n,k`, is at most 1 nm (Acary and Brogliato 2008,
//!   sec. 7.2.2, with a tolerance for the scheme's second-order drift);
//! - an active contact obeys Newton's law at the velocity level with Coulomb
//!   friction (Moreau's sweeping process with friction):
//!   `0 <= P_n  _|_  v_n,k+1 + e v_n,k^- >= 0`, `|P_t| <= mu P_n`, and
//!   `P_t = -mu sign(v_r,k+1) P_n` when the tip slips at the end of the step
//!   ([`contact_impulse`]).
//!
//! It is first order, with no event location: velocities may jump in any step, so
//! it crosses the corners where an event-driven integrator's step collapses
//! (Acary and Brogliato 2008, ch. 1 and 7; Brogliato, "Nonsmooth Mechanics",
//! 3rd ed., 2016, ch. 4). The one contact problem per step is solved exactly
//! (below), with the singular rule choosing between its solutions where the
//! Painlevé indeterminacy gives two.

use nalgebra::{Matrix2, Vector2};
use shared::SlipDirection;

/// What the plant does where a slide reaches the singular point `p = 0, b = 0`
/// with a finite normal force and enters the indeterminate region `p < 0, b > 0`,
/// where both sliding (`f_n = -b/p > 0`) and flight solve the contact problem
/// (Génot and Brogliato 1999, "New results on Painlevé paradoxes", Eur. J. Mech.
/// A/Solids 18, sec. 4; docs/plant.md "The singular point"). Scenario key
/// `plant.singular`, command-line `--singular leave|slide`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum SingularRule {
    /// The tip leaves the belt: the flight solution of the indeterminate region,
    /// which Moreau-Jean time-steppers take (their contact problem prefers `P = 0`
    /// where it is a solution) and the independent references of issue 40 took.
    #[default]
    Leave,
    /// The tip keeps sliding through the singular point: the sliding solution of
    /// the indeterminate region, as long as the bridge across it lasts.
    Slide,
}

impl SingularRule {
    /// Both rules.
    pub const ALL: [SingularRule; 2] = [Self::Leave, Self::Slide];

    /// Lower-case name (`leave`, `slide`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Leave => "leave",
            Self::Slide => "slide",
        }
    }
}

impl std::fmt::Display for SingularRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which solution of the one-contact problem a step took.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactSolution {
    /// The contact was not active (gap open half a step ahead).
    Inactive,
    /// Active, with `P = 0`: the tip separates (`v_n,k+1 >= -e v_n,k`).
    Separation,
    /// The tip sticks at the end of the step (`v_r,k+1 = 0`), the impulse inside the cone.
    Sticking,
    /// The tip slips in this direction at the end of the step, the impulse on the cone's edge.
    Sliding(SlipDirection),
}

impl ContactSolution {
    /// Whether the tip is held on the belt at the end of the step (sticking or sliding).
    pub fn in_contact(self) -> bool {
        matches!(self, Self::Sticking | Self::Sliding(_))
    }
}

/// The impulse of one active contact in one step: `P = [P_t, P_n]` (N s) such
/// that the relative tip velocity after it, `v+ = v_free + W P` (m/s; `v_free =
/// [v_r, v_n]` before it, `W = J M^-1 J^T` the Delassus operator, 1/kg, symmetric
/// positive definite), satisfies `0 <= P_n _|_ v_n+ - v_n_target >= 0` and
/// Coulomb's law `|P_t| <= mu P_n`, `P_t = -mu sign(v_r+) P_n` if `v_r+ != 0`
/// (Moreau 1988; Acary and Brogliato 2008, sec. 7.2). `v_n_target >= 0` (m/s) is
/// Newton's `-e v_n,k` for an approaching tip, else 0.
///
/// The candidates are separation (`P = 0`, a solution when `v_n >= v_n_target`),
/// sticking (`P = W^-1 [-v_r, v_n_target - v_n]` in the cone) and sliding in
/// either direction `s` (`P_t = -mu s P_n`, `P_n = (v_n_target - v_n) / p(s)`,
/// `p(s) = W_22 - mu s W_21`, the paper's eq. 7, with `P_n >= 0` and
/// `s v_r+ > 0`), tried in the order: sliding on in the slip's direction,
/// sticking, sliding the other way. When the tip would penetrate (`v_n < v_n_target`) exactly one of
/// sticking and sliding solves it: on the line of impulses that give `v_n+ =
/// v_n_target`, `v_r+` grows with `P_t` at the rate `det W / W_22 > 0`, and the cone
/// cuts that line in a segment or a ray (one `p(s) > 0` at least, since `p(+) +
/// p(-) = 2 W_22`). When it would not, separation is a solution, and a contact
/// solution may be one too where `p(s) < 0` (the indeterminate case): `rule`
/// chooses ([`SingularRule::Leave`] takes separation, [`SingularRule::Slide`] the
/// contact solution).
///
/// Returns the impulse and the solution taken; `None` only if an input is not
/// finite or `W` is singular (never for an arm: `W` is positive definite).
pub fn contact_impulse(
    w: &Matrix2<f64>,
    mu: f64,
    v_free: Vector2<f64>,
    v_n_target: f64,
    rule: SingularRule,
) -> Option<(Vector2<f64>, ContactSolution)> {
    if !(v_free.iter().all(|v| v.is_finite()) && w.iter().all(|v| v.is_finite()) && v_n_target.is_finite()) {
        return None;
    }
    let separates = v_free[1] >= v_n_target;
    if separates && rule == SingularRule::Leave {
        return Some((Vector2::zeros(), ContactSolution::Separation));
    }
    let dn = v_n_target - v_free[1];
    // Sticking: v+ = [0, v_n_target].
    let det = w[(0, 0)] * w[(1, 1)] - w[(0, 1)] * w[(1, 0)];
    if !(det.is_finite() && det > 0.0) {
        return None;
    }
    let stick = Vector2::new((w[(1, 1)] * -v_free[0] - w[(0, 1)] * dn) / det, (-w[(1, 0)] * -v_free[0] + w[(0, 0)] * dn) / det);
    let slide = |s: SlipDirection| {
        let sign = s.sign::<f64>();
        let p = w[(1, 1)] - mu * sign * w[(1, 0)];
        let pn = dn / p;
        let v_r_after = v_free[0] + (w[(0, 1)] - mu * sign * w[(0, 0)]) * pn;
        (p != 0.0 && pn >= 0.0 && sign * v_r_after > 0.0).then(|| (Vector2::new(-mu * sign * pn, pn), ContactSolution::Sliding(s)))
    };
    // Where the tip would penetrate exactly one of these solves it, so the order
    // matters only in the indeterminate case, where `Slide` keeps the slip it has.
    let ahead = SlipDirection::of(v_free[0]);
    if let Some(found) = slide(ahead) {
        return Some(found);
    }
    if stick[1] >= 0.0 && stick[0].abs() <= mu * stick[1] {
        return Some((stick, ContactSolution::Sticking));
    }
    if let Some(found) = slide(ahead.reversed()) {
        return Some(found);
    }
    // No contact solution: separation is the one (the tip does not penetrate), or
    // rounding at the cone's edge between sticking and sliding.
    if separates {
        return Some((Vector2::zeros(), ContactSolution::Separation));
    }
    // On the edge to rounding: the sticking impulse, projected onto the cone.
    let pn = stick[1].max(0.0);
    Some((Vector2::new(stick[0].clamp(-mu * pn, mu * pn), pn), ContactSolution::Sticking))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn spd(a: f64, b: f64, c: f64) -> Matrix2<f64> {
        let l = Matrix2::new(a, 0.0, b, c);
        l * l.transpose()
    }

    proptest! {
        /// Every solution satisfies the complementarity conditions it claims.
        #[test]
        fn the_contact_impulse_satisfies_coulomb_and_signorini(
            a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.05f64..3.0, mu in 0.0f64..1.5,
            v_r in -1.0f64..1.0, v_n in -1.0f64..1.0, target in 0.0f64..0.5, slide in any::<bool>(),
        ) {
            let w = spd(a, b, c);
            let rule = if slide { SingularRule::Slide } else { SingularRule::Leave };
            let (p, sol) = contact_impulse(&w, mu, Vector2::new(v_r, v_n), target, rule).unwrap();
            let after = Vector2::new(v_r, v_n) + w * p;
            let scale = 1e-9 * (1.0 + v_r.abs() + v_n.abs());
            prop_assert!(p[1] >= 0.0);
            prop_assert!(p[0].abs() <= mu * p[1] * (1.0 + 1e-12) + 1e-15);
            prop_assert!(after[1] >= target - scale, "penetrates: {after:?} {sol:?}");
            match sol {
                ContactSolution::Separation => prop_assert_eq!(p, Vector2::zeros()),
                ContactSolution::Sticking => prop_assert!(after[0].abs() <= scale && (after[1] - target).abs() <= scale),
                ContactSolution::Sliding(s) => {
                    prop_assert!(s.sign::<f64>() * after[0] > 0.0);
                    prop_assert!((after[1] - target).abs() <= scale);
                    prop_assert!((p[0] + mu * s.sign::<f64>() * p[1]).abs() <= scale);
                }
                ContactSolution::Inactive => prop_assert!(false),
            }
            // A tip that would penetrate has one solution, whatever the rule.
            if v_n < target {
                let other = if slide { SingularRule::Leave } else { SingularRule::Slide };
                prop_assert_eq!(contact_impulse(&w, mu, Vector2::new(v_r, v_n), target, other), Some((p, sol)));
            }
        }
    }

    /// The Painlevé indeterminacy at the impulse level: `p(+) < 0` and a tip that
    /// would separate; `Leave` separates, `Slide` keeps it sliding on the belt.
    #[test]
    fn the_rule_chooses_between_flight_and_sliding_where_both_solve() {
        // W with W_21 > W_22 / mu: p(+) = W22 - mu W21 < 0.
        let w = Matrix2::new(2.0, 1.5, 1.5, 1.2);
        let mu = 1.0;
        assert!(w[(1, 1)] - mu * w[(1, 0)] < 0.0);
        let v = Vector2::new(0.3, 0.01);
        let (p, sol) = contact_impulse(&w, mu, v, 0.0, SingularRule::Leave).unwrap();
        assert_eq!((p, sol), (Vector2::zeros(), ContactSolution::Separation));
        let (p, sol) = contact_impulse(&w, mu, v, 0.0, SingularRule::Slide).unwrap();
        assert_eq!(sol, ContactSolution::Sliding(SlipDirection::Positive));
        let after = v + w * p;
        assert!(after[1].abs() < 1e-15 && after[0] > 0.0 && p[1] > 0.0);
    }
}
