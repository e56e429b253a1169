//! Contact modes of the tip on the belt (docs/model.md "Contact modes"; paper eqs. 5 to 7).
//!
//! While the tip touches the belt (`z_n = -H`, `z_n_dot = 0`), its normal
//! acceleration is `z_n_ddot = b + p f_n` (paper eq. 5). Sliding needs `f_n = -b/p >= 0`
//! with `z_n_ddot = 0`; flight needs `f_n = 0` with `z_n_ddot = b >= 0`. The signs of
//! `b` and `p` decide which of these exist; with `p < 0` and `b < 0` neither does:
//! the Painlevé paradox.

use nalgebra::Vector2;

pub use crate::slip::{SlipDirection, p_of};
use crate::{Real, model::TipDynamics};

/// Contact mode of the tip (docs/model.md "Contact modes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum ContactMode {
    /// On the belt, slipping: `p > 0`, `b < 0`, `f_n = -b/p`.
    Sliding,
    /// On the belt, carried by it (`z_r_dot = 0`) with `|f_t| <= mu f_n`.
    Sticking,
    /// Off the belt (or leaving it): `f = 0`.
    Flight,
    /// `p < 0`, `b > 0`: both sliding and flight solve the contact problem (resolved as flight).
    Indeterminate,
    /// `p < 0`, `b < 0`: no contact force solves it (the Painlevé paradox; resolved by an impact without collision).
    Inconsistent,
}

impl ContactMode {
    /// Lower-case name, as written in traces (`sliding`, `sticking`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Self::Sliding => "sliding",
            Self::Sticking => "sticking",
            Self::Flight => "flight",
            Self::Indeterminate => "indeterminate",
            Self::Inconsistent => "inconsistent",
        }
    }

    /// A small integer code for plots and compact traces: flight 0, sliding 1,
    /// sticking 2, indeterminate 3, inconsistent 4.
    pub fn code(self) -> u8 {
        match self {
            Self::Flight => 0,
            Self::Sliding => 1,
            Self::Sticking => 2,
            Self::Indeterminate => 3,
            Self::Inconsistent => 4,
        }
    }
}

/// The contact mode of a slipping tip from the signs of `b` (m/s^2) and `p`
/// (1/kg), docs/model.md's table. Boundaries: `b = 0` counts as flight (the reaction
/// has vanished: lift-off), `p = 0` with `b < 0` as inconsistent (`f_n` unbounded).
#[inline]
pub fn classify_slipping<T: Real>(b: T, p: T) -> ContactMode {
    let zero = T::zero();
    match (p > zero, b < zero) {
        (true, true) => ContactMode::Sliding,
        (true, false) => ContactMode::Flight,
        (false, false) => ContactMode::Indeterminate,
        (false, true) => ContactMode::Inconsistent,
    }
}

/// Contact force `f = [f_t, f_n]` (N) that keeps a slipping tip on the belt:
/// `f_n = -b/p`, `f_t = -mu sign(z_r_dot) f_n` (paper eqs. 5 to 7). Meaningful in
/// sliding (`p > 0`, `b < 0`); otherwise `f_n` may be negative or infinite.
#[inline]
pub fn sliding_force<T: Real>(td: &TipDynamics<T>, mu: T, dir: SlipDirection) -> Vector2<T> {
    let f_n = -td.b() / td.p(mu, dir);
    Vector2::new(-mu * dir.sign::<T>() * f_n, f_n)
}

/// Contact force `f = [f_t, f_n]` (N) that keeps the tip stuck to a belt moving at
/// constant speed (`z_ddot = 0`): `f = -Q^-1 a_free`. Sticking is consistent when
/// `f_n >= 0` and `|f_t| <= mu f_n` (see [`sticking_is_consistent`]).
#[inline]
pub fn sticking_force<T: Real>(td: &TipDynamics<T>) -> Vector2<T> {
    let q = &td.qmat;
    let det = q[(0, 0)] * q[(1, 1)] - q[(0, 1)] * q[(1, 0)];
    let a = &td.a_free;
    -Vector2::new(q[(1, 1)] * a[0] - q[(0, 1)] * a[1], -q[(1, 0)] * a[0] + q[(0, 0)] * a[1]) / det
}

/// Whether a sticking force lies in the friction cone: `f_n >= 0` and `|f_t| <= mu f_n`.
#[inline]
pub fn sticking_is_consistent<T: Real>(f: &Vector2<T>, mu: T) -> bool {
    f[1] >= T::zero() && f[0].abs() <= mu * f[1]
}

/// Full classification of a tip on the belt with `z_n_dot = 0`: sticking when the
/// relative velocity `|z_r_dot| <= v_stick` (m/s) and the sticking force is in the
/// cone, otherwise the slipping classification of [`classify_slipping`] in the
/// direction of `z_r_dot` (or, at rest relative to the belt, the direction the
/// sticking force would make the tip slip: `-sign f_t`).
pub fn classify<T: Real>(td: &TipDynamics<T>, mu: T, z_r_dot: T, v_stick: T) -> ContactMode {
    let dir = if z_r_dot.abs() <= v_stick {
        let f = sticking_force(td);
        if sticking_is_consistent(&f, mu) {
            return ContactMode::Sticking;
        }
        SlipDirection::of(-f[0])
    } else {
        SlipDirection::of(z_r_dot)
    };
    classify_slipping(td.b(), td.p(mu, dir))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Arm, ElbowBranch, Params, kinematics::inverse_kinematics};

    #[test]
    fn table_of_modes() {
        assert_eq!(classify_slipping(-1.0, 1.0), ContactMode::Sliding);
        assert_eq!(classify_slipping(1.0, 1.0), ContactMode::Flight);
        assert_eq!(classify_slipping(1.0, -1.0), ContactMode::Indeterminate);
        assert_eq!(classify_slipping(-1.0, -1.0), ContactMode::Inconsistent);
    }

    #[test]
    fn sliding_force_cancels_normal_acceleration_and_sticking_force_all_of_it() {
        let arm = Arm::new(Params::<f64>::paper());
        let z = Vector2::new(-0.16, -arm.params.h);
        let q = inverse_kinematics(arm.params.l, &z, ElbowBranch::Down).unwrap();
        let qd = Vector2::new(0.5, -0.2);
        let td = arm.tip_dynamics(&q, &qd, &Vector2::zeros());
        for dir in [SlipDirection::Positive, SlipDirection::Negative] {
            let f = sliding_force(&td, 0.6, dir);
            let acc = td.a_free + td.qmat * f;
            assert!(acc[1].abs() < 1e-9);
            assert!((f[0] + 0.6 * dir.sign::<f64>() * f[1]).abs() < 1e-12);
        }
        let f = sticking_force(&td);
        assert!((td.a_free + td.qmat * f).norm() < 1e-9);
    }
}
