//! Forward and inverse kinematics of the tip (docs/model.md "Geometry and state").
//!
//! `z_t = l (sin theta1 + sin theta2)`, `z_n = -l (cos theta1 + cos theta2)`,
//! `J = dz/dq = [[l cos theta1, l cos theta2], [l sin theta1, l sin theta2]]`,
//! `s = J_dot q_dot` (paper eq. 4).

use nalgebra::{Matrix2, Vector2};

use crate::{Real, lit, params::to_f64, trig};

/// Elbow branch of a configuration, by the sign of the relative angle
/// `theta2 - theta1` (docs/model.md: "elbow up" means `theta2 - theta1 > 0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ElbowBranch {
    /// `theta2 - theta1 > 0` (e.g. the paper's `x0u`).
    Up,
    /// `theta2 - theta1 < 0` (e.g. the paper's `x0d`).
    Down,
}

impl ElbowBranch {
    /// The branch of configuration `q = [theta1, theta2]` (rad); a straight arm
    /// (`theta2 == theta1`) counts as `Down`.
    pub fn of<T: Real>(q: &Vector2<T>) -> Self {
        if q[1] - q[0] > T::zero() { Self::Up } else { Self::Down }
    }

    /// Lower-case name, as in scenario files and CLI flags (`up`, `down`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Up => "up",
            Self::Down => "down",
        }
    }
}

/// Why a tip position has no inverse kinematics.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum IkError {
    /// The target is NaN or infinite.
    #[error("tip target ({z_t}, {z_n}) m is not finite")]
    NonFinite {
        /// Requested `z_t`, m.
        z_t: f64,
        /// Requested `z_n`, m.
        z_n: f64,
    },
    /// The target is farther from the base than the arm's reach `2 l`.
    #[error("tip target ({z_t}, {z_n}) m is out of reach: distance {distance} m > 2 l = {reach} m")]
    OutOfReach {
        /// Requested `z_t`, m.
        z_t: f64,
        /// Requested `z_n`, m.
        z_n: f64,
        /// Distance of the target from the base joint, m.
        distance: f64,
        /// The arm's reach `2 l`, m.
        reach: f64,
    },
    /// The target is the base joint itself, where the direction is undefined.
    #[error("tip target is at the base joint: the arm's direction is undefined")]
    AtBase,
}

/// Sines and cosines of the joint angles `q = [theta1, theta2]`: all the
/// trigonometry of the model (those of `theta2 - theta1` follow from the
/// angle-difference identities).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointTrig<T> {
    /// `sin theta1`.
    pub s1: T,
    /// `cos theta1`.
    pub c1: T,
    /// `sin theta2`.
    pub s2: T,
    /// `cos theta2`.
    pub c2: T,
}

impl<T: Real> JointTrig<T> {
    /// The sines and cosines of `q = [theta1, theta2]` (rad): one `sin_cos` per angle.
    #[inline]
    pub fn new(q: &Vector2<T>) -> Self {
        let (s1, c1) = q[0].sin_cos_rad();
        let (s2, c2) = q[1].sin_cos_rad();
        Self { s1, c1, s2, c2 }
    }

    /// `cos(theta2 - theta1) = cos theta1 cos theta2 + sin theta1 sin theta2`.
    #[inline]
    pub fn c21(&self) -> T {
        self.c1 * self.c2 + self.s1 * self.s2
    }

    /// `sin(theta1 - theta2) = sin theta1 cos theta2 - cos theta1 sin theta2`.
    #[inline]
    pub fn s12(&self) -> T {
        self.s1 * self.c2 - self.c1 * self.s2
    }
}

impl JointTrig<f32> {
    /// [`JointTrig::new`]`(q)` (rad), the same bits, with the two angles' `sin_cos`
    /// as one run ([`trig::sin_cos2_f32`]: their constants loaded once) and inlined
    /// where it is called: the firmware's estimate, every control step.
    #[inline(always)]
    pub fn of(q: &Vector2<f32>) -> Self {
        let [(s1, c1), (s2, c2)] = trig::sin_cos2_f32(q[0], q[1]);
        Self { s1, c1, s2, c2 }
    }

    /// The sines and cosines at `q` (rad) from these, taken at `base` (rad), when
    /// `q` is within 1/16 rad of `base` in both angles ([`trig::rotate_f32`]: a
    /// dozen instructions per angle on the MCU against fifty), else
    /// [`JointTrig::new`]`(q)`. The firmware's raw angles against its estimate.
    #[inline]
    pub fn near(&self, base: &Vector2<f32>, q: &Vector2<f32>) -> Self {
        match (trig::rotate_f32(self.s1, self.c1, q[0] - base[0]), trig::rotate_f32(self.s2, self.c2, q[1] - base[1])) {
            (Some((s1, c1)), Some((s2, c2))) => Self { s1, c1, s2, c2 },
            _ => Self::new(q),
        }
    }

    /// The tip's normal coordinate `z_n = -l (cos theta1 + cos theta2)` (m, links of
    /// length `l` m) at `q` (rad) from these sines and cosines, taken at `base`
    /// (rad): each cosine by [`trig::cos_rotated_f32`] when `q` is within 1/16 rad of
    /// `base` in both angles (within `d^4 / 24` plus roundings: `z_n` within
    /// `l d^4 / 12`, 2.7e-7 m at `l = 0.21` m and `d = 1/16`), else from
    /// [`JointTrig::new`]`(q)`. The firmware's tip height from its raw angles,
    /// against the load cell (a check of millimetres), at about half the cost of
    /// [`JointTrig::near`].
    #[inline]
    pub fn tip_normal_near(&self, l: f32, base: &Vector2<f32>, q: &Vector2<f32>) -> f32 {
        match (trig::cos_rotated_f32(self.s1, self.c1, q[0] - base[0]), trig::cos_rotated_f32(self.s2, self.c2, q[1] - base[1])) {
            (Some(c1), Some(c2)) => -l * (c1 + c2),
            _ => tip_position_trig(l, &Self::new(q))[1],
        }
    }
}

/// Tip position `z = [z_t, z_n]` (m) from the sines and cosines of the angles,
/// links of length `l` (m): `[l (sin theta1 + sin theta2), -l (cos theta1 + cos theta2)]`.
#[inline]
pub fn tip_position_trig<T: Real>(l: T, t: &JointTrig<T>) -> Vector2<T> {
    Vector2::new(l * (t.s1 + t.s2), -l * (t.c1 + t.c2))
}

/// The elbow and the tip `[z_t, z_n]` (m, the base joint at the origin) of links of
/// length `l` (m) from the sines and cosines of the angles: the elbow `l [sin
/// theta1, -cos theta1]` ([`tip_position_trig`] with the second link's terms zero,
/// the same bits), the tip [`tip_position_trig`]. Every view of the arm draws its
/// joints from this (the trace page, the animations, the Foxglove scene).
#[inline]
pub fn joint_positions_trig<T: Real>(l: T, t: &JointTrig<T>) -> [Vector2<T>; 2] {
    let elbow = JointTrig { s1: t.s1, c1: t.c1, s2: T::zero(), c2: T::zero() };
    [tip_position_trig(l, &elbow), tip_position_trig(l, t)]
}

/// [`joint_positions_trig`] at the angles `q = [theta1, theta2]` (rad): the elbow
/// and the tip, m.
#[inline]
pub fn joint_positions<T: Real>(l: T, q: &Vector2<T>) -> [Vector2<T>; 2] {
    joint_positions_trig(l, &JointTrig::new(q))
}

/// Tip Jacobian `J = [[l cos theta1, l cos theta2], [l sin theta1, l sin theta2]]`
/// (m/rad) from the sines and cosines of the angles; paper eq. 1.
#[inline]
pub fn jacobian_trig<T: Real>(l: T, t: &JointTrig<T>) -> Matrix2<T> {
    Matrix2::new(l * t.c1, l * t.c2, l * t.s1, l * t.s2)
}

/// Tip position `z = [z_t, z_n]` (m) of configuration `q = [theta1, theta2]` (rad),
/// links of length `l` (m). docs/model.md, "Geometry and state".
#[inline]
pub fn tip_position<T: Real>(l: T, q: &Vector2<T>) -> Vector2<T> {
    tip_position_trig(l, &JointTrig::new(q))
}

/// Tip Jacobian `J(q) = dz/dq` (2x2, m/rad), rows `j1^T` (tangential) and
/// `j2^T` (normal); paper eq. 1.
#[inline]
pub fn jacobian<T: Real>(l: T, q: &Vector2<T>) -> Matrix2<T> {
    jacobian_trig(l, &JointTrig::new(q))
}

/// `s = J_dot(q, q_dot) q_dot` (m/s^2), the velocity-product part of the tip
/// acceleration; paper eq. 4:
/// `s = [-l (theta1_dot^2 sin theta1 + theta2_dot^2 sin theta2),
///        l (theta1_dot^2 cos theta1 + theta2_dot^2 cos theta2)]`.
#[inline]
pub fn jdot_qdot<T: Real>(l: T, q: &Vector2<T>, qd: &Vector2<T>) -> Vector2<T> {
    jdot_qdot_trig(l, &JointTrig::new(q), qd)
}

/// [`jdot_qdot`] (m/s^2) from the sines and cosines of the angles.
#[inline]
pub fn jdot_qdot_trig<T: Real>(l: T, t: &JointTrig<T>, qd: &Vector2<T>) -> Vector2<T> {
    let (w1, w2) = (qd[0] * qd[0], qd[1] * qd[1]);
    Vector2::new(-l * (w1 * t.s1 + w2 * t.s2), l * (w1 * t.c1 + w2 * t.c2))
}

/// Inverse kinematics: the configuration `q = [theta1, theta2]` (rad) that puts
/// the tip at `z = [z_t, z_n]` (m) on the given elbow branch.
///
/// For equal links the elbow angle is `delta = theta2 - theta1 = ±acos(|z|^2/(2 l^2) - 1)`
/// (sign from the branch) and the arm's direction `psi = atan2(z_t, -z_n)` bisects the
/// links: `theta1 = psi - delta/2`, `theta2 = psi + delta/2`. On the boundary of the
/// workspace (`|z| = 2 l`) both branches give the straight arm.
///
/// # Errors
/// [`IkError::NonFinite`], [`IkError::OutOfReach`] (`|z| > 2 l`, beyond a relative
/// rounding margin of `1e-6`), [`IkError::AtBase`] (`z = 0`).
pub fn inverse_kinematics<T: Real>(l: T, z: &Vector2<T>, branch: ElbowBranch) -> Result<Vector2<T>, IkError> {
    inverse_kinematics_trig(l, z, branch).map(|(q, _)| q)
}

/// [`inverse_kinematics`] (the same angles, to the bit) with their sines and
/// cosines, from the construction's own geometry rather than `sin_cos`: with
/// `sin psi = z_t / |z|`, `cos psi = -z_n / |z|`, `cos(delta/2) = |z| / 2l` and
/// `sin(delta/2) = sqrt((1 - cos)(1 + cos))`, the angle-sum identities for
/// `psi -+ delta/2`. Within a few roundings of `JointTrig::new` of the angles (test
/// below); the firmware's PID takes its reference Jacobian from them (two `sin_cos`
/// fewer a step on the MCU).
///
/// # Errors
/// As [`inverse_kinematics`].
pub fn inverse_kinematics_trig<T: Real>(l: T, z: &Vector2<T>, branch: ElbowBranch) -> Result<(Vector2<T>, JointTrig<T>), IkError> {
    if !(z[0].is_finite() && z[1].is_finite()) {
        return Err(IkError::NonFinite { z_t: to_f64(z[0]), z_n: to_f64(z[1]) });
    }
    // |z| with the scalar's own square root (nalgebra's `norm` would call libm's
    // `sqrtf` on the MCU: 150 instructions against one VSQRT.F32, the same bits).
    let r = (z[0] * z[0] + z[1] * z[1]).square_root();
    let reach = l + l;
    if r > reach * lit::<T>(1.0 + 1e-6) {
        return Err(IkError::OutOfReach { z_t: to_f64(z[0]), z_n: to_f64(z[1]), distance: to_f64(r), reach: to_f64(reach) });
    }
    if r <= l * lit::<T>(1e-9) {
        return Err(IkError::AtBase);
    }
    // cos(delta/2) = r / (2 l): better conditioned near the straight arm than acos of cos(delta).
    let c_half = (r / reach).min(T::one());
    let half = c_half.arc_cos();
    // The elbow's side: theta1 = psi - sign delta/2, theta2 = psi + sign delta/2.
    let sign = match branch {
        ElbowBranch::Up => T::one(),
        ElbowBranch::Down => -T::one(),
    };
    let delta = sign * (half + half);
    let psi = z[0].arc_tan2(-z[1]);
    let half_delta = delta * lit(0.5);
    let q = Vector2::new(psi - half_delta, psi + half_delta);
    let (s_psi, c_psi) = (z[0] / r, -z[1] / r);
    let s_half = sign * ((T::one() - c_half) * (T::one() + c_half)).square_root();
    let trig = JointTrig {
        s1: s_psi * c_half - c_psi * s_half,
        c1: c_psi * c_half + s_psi * s_half,
        s2: s_psi * c_half + c_psi * s_half,
        c2: c_psi * c_half - s_psi * s_half,
    };
    Ok((q, trig))
}

#[cfg(test)]
mod tests {
    use super::*;

    const L: f64 = 0.21;

    /// The joints every view draws: the elbow `l [sin theta1, -cos theta1]` and the
    /// plant's tip, bit for bit, over a grid of angles; the elbow is `l` from the base
    /// and the tip `l` from the elbow.
    #[test]
    fn the_joints_are_the_elbow_and_the_plants_tip() {
        for i in -12..=12 {
            for j in -12..=12 {
                let q = Vector2::new(f64::from(i) * 0.27, f64::from(j) * 0.31);
                let [elbow, tip] = joint_positions(L, &q);
                let (s1, c1) = q[0].sin_cos();
                assert_eq!((elbow[0].to_bits(), elbow[1].to_bits()), ((L * s1).to_bits(), (-L * c1).to_bits()), "{q:?}");
                assert_eq!(tip, tip_position(L, &q), "{q:?}");
                assert!((elbow.norm() - L).abs() < 1e-15 && ((tip - elbow).norm() - L).abs() < 1e-15, "{q:?}");
            }
        }
    }

    /// The geometry's sines and cosines are those of the angles, to a few roundings,
    /// on both branches over the workspace, in f32 and f64.
    #[test]
    fn inverse_kinematics_trig_gives_the_angles_sines_and_cosines() {
        let mut worst = (0.0f64, 0.0f64);
        for i in -20..=20 {
            for j in 1..=20 {
                let z = Vector2::new(0.02 * i as f64, -0.021 * j as f64);
                for branch in [ElbowBranch::Up, ElbowBranch::Down] {
                    let Ok((q, t)) = inverse_kinematics_trig(L, &z, branch) else { continue };
                    assert_eq!(q, inverse_kinematics(L, &z, branch).unwrap(), "the same angles");
                    let e = JointTrig::new(&q);
                    for (a, b) in [(t.s1, e.s1), (t.c1, e.c1), (t.s2, e.s2), (t.c2, e.c2)] {
                        worst.0 = worst.0.max((a - b).abs());
                    }
                    let zf = Vector2::new(z[0] as f32, z[1] as f32);
                    let (qf, tf) = inverse_kinematics_trig(L as f32, &zf, branch).unwrap();
                    let ef = JointTrig::new(&Vector2::new(qf[0] as f64, qf[1] as f64));
                    for (a, b) in [(tf.s1, ef.s1), (tf.c1, ef.c1), (tf.s2, ef.s2), (tf.c2, ef.c2)] {
                        worst.1 = worst.1.max((a as f64 - b).abs());
                    }
                }
            }
        }
        assert!(worst.0 < 1e-14 && worst.1 < 2e-6, "worst differences {worst:?}");
    }

    /// `of` (the two angles' `sin_cos` as one run) is `new`, bit for bit.
    #[test]
    fn of_is_new_bit_for_bit() {
        for i in -300..=300 {
            let q = Vector2::new(0.0213f32 * i as f32, 1.3 - 0.0171 * i as f32);
            let (a, b) = (JointTrig::of(&q), JointTrig::new(&q));
            assert_eq!([a.s1, a.c1, a.s2, a.c2].map(f32::to_bits), [b.s1, b.c1, b.s2, b.c2].map(f32::to_bits), "q = {q:?}");
        }
    }

    /// `near` gives the sines and cosines of `q` to a few f32 roundings from those
    /// of a base within 1/16 rad, and `new(q)` itself beyond it.
    #[test]
    fn near_rotates_small_steps_and_recomputes_large_ones() {
        let base = Vector2::new(-0.2f32, -0.61);
        let t = JointTrig::new(&base);
        for (d1, d2) in [(0.0f32, 0.0f32), (0.01, -0.003), (-0.0625, 0.0625), (0.03, 0.0)] {
            let q = Vector2::new(base[0] + d1, base[1] + d2);
            let n = t.near(&base, &q);
            let e = JointTrig::new(&Vector2::new(q[0] as f64, q[1] as f64));
            for (a, b) in [(n.s1, e.s1), (n.c1, e.c1), (n.s2, e.s2), (n.c2, e.c2)] {
                assert!((a as f64 - b).abs() <= 4e-7, "d = ({d1}, {d2}): {a} against {b}");
            }
        }
        let far = Vector2::new(base[0] + 0.07, base[1]);
        assert_eq!(t.near(&base, &far), JointTrig::new(&far));
    }

    /// `tip_normal_near` is the tip's `z_n` at `q` (f64) within `l (d1^4 + d2^4) / 24`
    /// (the series' remainders) plus 1e-7 m of roundings within 1/16 rad of the base,
    /// and `tip_position(q)`'s own beyond it.
    #[test]
    fn the_tip_normal_from_a_near_base_is_the_tip_normal() {
        let l = 0.21f32;
        for (b0, b1) in [(-0.2f32, -0.61f32), (0.9, -2.3), (3.0, 1.1)] {
            let base = Vector2::new(b0, b1);
            let t = JointTrig::new(&base);
            for (d1, d2) in [(0.0f32, 0.0f32), (0.01, -0.003), (-0.0625, 0.0625), (0.03, 0.0), (4e-4, -4e-4)] {
                let q = Vector2::new(base[0] + d1, base[1] + d2);
                let want = tip_position(l as f64, &Vector2::new(q[0] as f64, q[1] as f64))[1];
                let got = t.tip_normal_near(l, &base, &q) as f64;
                let bound = l as f64 * ((d1 as f64).powi(4) + (d2 as f64).powi(4)) / 24.0 + 1e-7;
                assert!((got - want).abs() <= bound, "base {base:?}, d = ({d1}, {d2}): {got} against {want}");
            }
            let far = Vector2::new(base[0] + 0.07, base[1]);
            assert_eq!(t.tip_normal_near(l, &base, &far), tip_position_trig(l, &JointTrig::new(&far))[1]);
        }
    }

    #[test]
    fn jacobian_matches_finite_differences_of_z() {
        let h = 1e-6;
        for i in -6..=6 {
            for j in -6..=6 {
                let q = Vector2::new(0.5 * i as f64, 0.45 * j as f64 + 0.1);
                let jac = jacobian(L, &q);
                for k in 0..2 {
                    let mut dq = Vector2::zeros();
                    dq[k] = h;
                    let fd = (tip_position(L, &(q + dq)) - tip_position(L, &(q - dq))) / (2.0 * h);
                    for r in 0..2 {
                        assert!((fd[r] - jac[(r, k)]).abs() < 1e-9, "q={q:?} row {r} col {k}");
                    }
                }
            }
        }
    }

    #[test]
    fn s_equals_jdot_qdot_by_finite_differences() {
        // d/dt (J(q(t)) q_dot) at constant q_dot equals J_dot q_dot.
        let h = 1e-6;
        for i in -4..=4 {
            let q = Vector2::new(0.4 * i as f64, -0.3 * i as f64 + 0.2);
            let qd = Vector2::new(1.3 - 0.2 * i as f64, -0.7 + 0.5 * i as f64);
            let jd = (jacobian(L, &(q + qd * h)) - jacobian(L, &(q - qd * h))) / (2.0 * h);
            let fd = jd * qd;
            let s = jdot_qdot(L, &q, &qd);
            assert!((fd - s).norm() < 1e-8, "q={q:?} qd={qd:?}: {fd:?} vs {s:?}");
        }
    }

    #[test]
    fn inverse_kinematics_round_trips_on_both_branches() {
        for i in 0..40 {
            for j in 0..40 {
                let z = Vector2::new(-0.38 + 0.019 * i as f64, -0.40 + 0.0199 * j as f64);
                if z.norm() > 2.0 * L || z.norm() < 1e-3 {
                    continue;
                }
                for branch in [ElbowBranch::Up, ElbowBranch::Down] {
                    let q = inverse_kinematics(L, &z, branch).unwrap();
                    assert!((tip_position(L, &q) - z).norm() < 1e-12);
                    let delta = q[1] - q[0];
                    if delta.abs() > 1e-9 {
                        assert_eq!(ElbowBranch::of(&q), branch);
                    }
                }
            }
        }
    }

    #[test]
    fn inverse_kinematics_recovers_the_paper_initial_conditions() {
        // x0d = [-11.4 deg, 0, -35.1 deg, 0] is elbow down; x0u its mirror, elbow up.
        let qd = Vector2::new((-11.4f64).to_radians(), (-35.1f64).to_radians());
        let q = inverse_kinematics(L, &tip_position(L, &qd), ElbowBranch::Down).unwrap();
        assert!((q - qd).norm() < 1e-12);
        let qu = Vector2::new((-35.1f64).to_radians(), (-11.4f64).to_radians());
        assert_eq!(ElbowBranch::of(&qu), ElbowBranch::Up);
        let q = inverse_kinematics(L, &tip_position(L, &qu), ElbowBranch::Up).unwrap();
        assert!((q - qu).norm() < 1e-12);
        // Both put the tip at z_t = -0.1624 m (docs/model.md experiment 5), to the paper's rounding.
        assert!((tip_position(L, &qd)[0] + 0.1624).abs() < 2e-4);
    }

    #[test]
    fn inverse_kinematics_errors() {
        assert!(matches!(inverse_kinematics(L, &Vector2::new(0.0, -0.5), ElbowBranch::Up), Err(IkError::OutOfReach { .. })));
        assert!(matches!(inverse_kinematics(L, &Vector2::new(f64::NAN, -0.3), ElbowBranch::Up), Err(IkError::NonFinite { .. })));
        assert_eq!(inverse_kinematics(L, &Vector2::new(0.0, 0.0), ElbowBranch::Up), Err(IkError::AtBase));
        // f32 works from the same code.
        let q = inverse_kinematics(0.21f32, &Vector2::new(-0.16f32, -0.3775), ElbowBranch::Down).unwrap();
        assert!((tip_position(0.21f32, &q) - Vector2::new(-0.16f32, -0.3775)).norm() < 1e-5);
    }
}
