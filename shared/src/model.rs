//! Equations of motion of the arm (paper eq. 1) and their tip-space form
//! (paper eqs. 2 to 7).
//!
//! `M(q) q_ddot = -w(q, q_dot) - c(q, q_dot) + J^T f + u`, with the torque vector
//! `u = [u1 - u2, u2]` from the motor torques `u1` (base joint) and `u2` (elbow).

use nalgebra::{Matrix2, Vector2};

use crate::{
    Real,
    kinematics::{JointTrig, jacobian},
    lit,
    params::Params,
    slip::{SlipDirection, p_of},
};

/// The arm: its parameters and the model evaluated from them.
///
/// Shapes: `q`, `q_dot`, torques and forces are `Vector2`; `M`, `J`, `Q` are
/// `Matrix2`. Units SI, angles in radians. The parameters are assumed valid
/// ([`Params::validate`]); no method panics on any finite or non-finite input
/// (non-finite inputs give non-finite outputs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arm<T> {
    /// The parameters (docs/model.md Table I).
    pub params: Params<T>,
}

/// Tip-space quantities at one state, computed together because they share
/// `M^-1` and `J` (paper eqs. 2 to 7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipDynamics<T> {
    /// Tip position `z = [z_t, z_n]`, m.
    pub z: Vector2<T>,
    /// Tip velocity `z_dot = J q_dot`, m/s.
    pub z_dot: Vector2<T>,
    /// Jacobian `J`, m/rad.
    pub jac: Matrix2<T>,
    /// Inverse mass matrix `M^-1`, 1/(kg m^2).
    pub m_inv: Matrix2<T>,
    /// `Q = J M^-1 J^T` (paper eq. 3), 1/kg: tip acceleration per unit tip force. Symmetric positive definite.
    pub qmat: Matrix2<T>,
    /// Free tip acceleration `a = -J M^-1 (w + c - u) + s` (m/s^2), the tip's
    /// acceleration with no contact force; `a[1]` is the paper's `b` (eq. 6).
    pub a_free: Vector2<T>,
    /// Joint acceleration with no contact force `M^-1 (u - w - c)`, rad/s^2.
    pub qdd_free: Vector2<T>,
}

impl<T: Real> TipDynamics<T> {
    /// The paper's `b` (eq. 6): free normal acceleration of the tip, m/s^2.
    #[inline]
    pub fn b(&self) -> T {
        self.a_free[1]
    }

    /// The paper's `p` (eq. 7), 1/kg: normal tip acceleration per newton of normal
    /// reaction when sliding in `dir` with Coulomb friction `f_t = -mu sign(z_r_dot) f_n`:
    /// `p = Q_22 - mu sign(z_r_dot) Q_21`.
    #[inline]
    pub fn p(&self, mu: T, dir: SlipDirection) -> T {
        p_of(&self.qmat, mu, dir)
    }

    /// Joint acceleration (rad/s^2) under tip force `f = [f_t, f_n]` (N):
    /// `q_ddot = qdd_free + M^-1 J^T f` (paper eq. 1).
    #[inline]
    pub fn qdd_with_force(&self, f: &Vector2<T>) -> Vector2<T> {
        let (j, mi) = (&self.jac, &self.m_inv);
        // J^T f, then M^-1 (J^T f), written out (the 2x2 products of nalgebra's generic code do not inline fully).
        let jt0 = j[(0, 0)] * f[0] + j[(1, 0)] * f[1];
        let jt1 = j[(0, 1)] * f[0] + j[(1, 1)] * f[1];
        Vector2::new(self.qdd_free[0] + (mi[(0, 0)] * jt0 + mi[(0, 1)] * jt1), self.qdd_free[1] + (mi[(1, 0)] * jt0 + mi[(1, 1)] * jt1))
    }
}

impl<T: Real> Arm<T> {
    /// An arm with the given parameters (not re-validated here).
    pub fn new(params: Params<T>) -> Self {
        Self { params }
    }

    /// Mass matrix `M(q)` (kg m^2), paper eq. 1:
    /// `[[4/3 m l^2, m l^2/2 cos(theta2 - theta1)], [m l^2/2 cos(theta2 - theta1), m l^2/3]]`.
    #[inline]
    pub fn mass_matrix(&self, q: &Vector2<T>) -> Matrix2<T> {
        self.mass_matrix_cos((q[1] - q[0]).cos_rad())
    }

    /// [`Arm::mass_matrix`] from `c21 = cos(theta2 - theta1)` (kg m^2): a caller
    /// that has the cosine saves a sine and cosine; the same value for the same cosine.
    #[inline]
    pub fn mass_matrix_cos(&self, c21: T) -> Matrix2<T> {
        let ml2 = self.params.m * self.params.l * self.params.l;
        let off = ml2 * lit::<T>(0.5) * c21;
        Matrix2::new(ml2 * lit::<T>(4.0 / 3.0), off, off, ml2 * lit::<T>(1.0 / 3.0))
    }

    /// Inverse of the mass matrix, in closed form (always invertible: `det M >= 7/36 m^2 l^4`).
    #[inline]
    pub fn mass_matrix_inverse(&self, q: &Vector2<T>) -> Matrix2<T> {
        let m = self.mass_matrix(q);
        let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
        Matrix2::new(m[(1, 1)], -m[(0, 1)], -m[(1, 0)], m[(0, 0)]) / det
    }

    /// [`Arm::mass_matrix_inverse`] from the sines and cosines of the angles
    /// (`cos(theta2 - theta1)` by the angle-difference identity), 1/(kg m^2).
    #[inline]
    pub fn mass_matrix_inverse_trig(&self, trig: &JointTrig<T>) -> Matrix2<T> {
        let ml2 = self.params.m * self.params.l * self.params.l;
        let (m11, m12, m22) = (ml2 * lit::<T>(4.0 / 3.0), ml2 * lit::<T>(0.5) * trig.c21(), ml2 * lit::<T>(1.0 / 3.0));
        let det = m11 * m22 - m12 * m12;
        let i12 = -m12 / det;
        Matrix2::new(m22 / det, i12, i12, m11 / det)
    }

    /// Gravity, spring and damping torques `w(q, q_dot)` (N m), paper eq. 1:
    /// `[3 m g l/2 sin theta1 - k (theta2 - theta1 + alpha0) - sigma (theta2_dot - 2 theta1_dot),
    ///   m g l/2 sin theta2 + k (theta2 - theta1 + alpha0) + sigma (theta2_dot - theta1_dot)]`.
    #[inline]
    pub fn w(&self, q: &Vector2<T>, qd: &Vector2<T>) -> Vector2<T> {
        self.w_sin(q[0].sin_rad(), q[1].sin_rad(), q, qd)
    }

    /// [`Arm::w`] (N m) with `s1 = sin theta1` and `s2 = sin theta2` given (those
    /// of `q`, e.g. from a [`JointTrig`]); the same value for the same sines.
    #[inline]
    pub fn w_sin(&self, s1: T, s2: T, q: &Vector2<T>, qd: &Vector2<T>) -> Vector2<T> {
        let p = &self.params;
        let mgl2 = p.m * p.g * p.l * lit::<T>(0.5);
        let spring = p.k * (q[1] - q[0] + p.alpha0);
        Vector2::new(mgl2 * lit::<T>(3.0) * s1 - spring - p.sigma * (qd[1] - qd[0] - qd[0]), mgl2 * s2 + spring + p.sigma * (qd[1] - qd[0]))
    }

    /// Centripetal torques `c(q, q_dot)` (N m), paper eq. 1:
    /// `[m l^2/2 theta2_dot^2 sin(theta1 - theta2), m l^2/2 theta1_dot^2 sin(theta2 - theta1)]`.
    #[inline]
    pub fn c(&self, q: &Vector2<T>, qd: &Vector2<T>) -> Vector2<T> {
        self.c_sin((q[0] - q[1]).sin_rad(), qd)
    }

    /// [`Arm::c`] (N m) from `s12 = sin(theta1 - theta2)`; the same value for the same sine.
    #[inline]
    pub fn c_sin(&self, s12: T, qd: &Vector2<T>) -> Vector2<T> {
        let half_ml2 = self.params.m * self.params.l * self.params.l * lit::<T>(0.5);
        Vector2::new(half_ml2 * qd[1] * qd[1] * s12, -half_ml2 * qd[0] * qd[0] * s12)
    }

    /// Generalised torque `u = [u1 - u2, u2]` (N m) from the motor torques
    /// `[u1, u2]` at the base joint and the elbow (docs/model.md, paper eq. 1).
    #[inline]
    pub fn generalised_torque(motor: &Vector2<T>) -> Vector2<T> {
        Vector2::new(motor[0] - motor[1], motor[1])
    }

    /// `Q = J M^-1 J^T` (1/kg), paper eq. 3.
    #[inline]
    pub fn q_matrix(&self, q: &Vector2<T>) -> Matrix2<T> {
        let j = jacobian(self.params.l, q);
        j * self.mass_matrix_inverse(q) * j.transpose()
    }

    /// Free normal acceleration of the tip `b(q, q_dot, u)` (m/s^2), paper eq. 6,
    /// with `u` the generalised torque (see [`Arm::generalised_torque`]).
    #[inline]
    pub fn b(&self, q: &Vector2<T>, qd: &Vector2<T>, u: &Vector2<T>) -> T {
        self.tip_dynamics(q, qd, u).b()
    }

    /// `p(q, mu, sign z_r_dot)` (1/kg), paper eq. 7, with `mu` from the parameters.
    #[inline]
    pub fn p(&self, q: &Vector2<T>, dir: SlipDirection) -> T {
        p_of(&self.q_matrix(q), self.params.mu, dir)
    }

    /// Everything tip-space at state `(q, q_dot)` under generalised torque `u`
    /// (paper eqs. 2 to 7), sharing one `M^-1`.
    ///
    /// This is the hot path of the plant and the firmware, so it evaluates one
    /// `sin_cos` per angle and derives `cos(theta2 - theta1)` and
    /// `sin(theta1 - theta2)` from them; the tests check it against the
    /// one-term-at-a-time functions ([`Arm::mass_matrix`], [`Arm::w`], [`Arm::c`],
    /// `kinematics::*`).
    #[inline]
    pub fn tip_dynamics(&self, q: &Vector2<T>, qd: &Vector2<T>, u: &Vector2<T>) -> TipDynamics<T> {
        self.tip_dynamics_trig(&JointTrig::new(q), q, qd, u)
    }

    /// [`Arm::tip_dynamics`] with the sines and cosines of `q` given (`trig` must be
    /// those of `q`; a caller that already has them saves the two `sin_cos`).
    /// The same value as [`ArmTerms::tip_dynamics_trig`] on [`Arm::terms`], which
    /// a caller evaluating many states of one arm keeps instead of refolding them.
    #[inline(always)]
    pub fn tip_dynamics_trig(&self, trig: &JointTrig<T>, q: &Vector2<T>, qd: &Vector2<T>, u: &Vector2<T>) -> TipDynamics<T> {
        self.terms().tip_dynamics_trig(trig, q, qd, u)
    }

    /// The arm's constant factors of the equations of motion, folded once
    /// ([`ArmTerms`]).
    #[inline(always)]
    pub fn terms(&self) -> ArmTerms<T> {
        ArmTerms::of(&self.params)
    }

    /// Kinetic energy `T = 1/2 q_dot^T M q_dot` (J).
    #[inline]
    pub fn kinetic_energy(&self, q: &Vector2<T>, qd: &Vector2<T>) -> T {
        (qd.transpose() * self.mass_matrix(q) * qd)[(0, 0)] * lit::<T>(0.5)
    }

    /// Potential energy (J) of gravity and the spring, whose gradient is the
    /// conservative part of `w`: `-m g l (3/2 cos theta1 + 1/2 cos theta2) + k/2 (theta2 - theta1 + alpha0)^2`.
    #[inline]
    pub fn potential_energy(&self, q: &Vector2<T>) -> T {
        let p = &self.params;
        let half = lit::<T>(0.5);
        let spring = q[1] - q[0] + p.alpha0;
        -p.m * p.g * p.l * (lit::<T>(1.5) * q[0].cos_rad() + half * q[1].cos_rad()) + half * p.k * spring * spring
    }
}

/// The constant factors of the arm's equations of motion (paper eq. 1), folded
/// from [`Params`] once: the plant evaluates the model about 17 times a control
/// period and each evaluation refolded about a dozen products of `m`, `l` and `g`.
/// Each factor is computed in the same order as the unfolded expression, so
/// [`ArmTerms::tip_dynamics_trig`] gives the same bits as the formulas written
/// out. Units as in [`Params`]; a copy, so it does not follow later changes of
/// the parameters it was folded from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmTerms<T> {
    /// Link length `l`, m.
    pub l: T,
    /// `M_11 = 4/3 m l^2`, kg m^2.
    pub m11: T,
    /// `m l^2 / 2` (kg m^2): `M_12 = m l^2/2 cos(theta2 - theta1)` and the centripetal factor.
    pub half_ml2: T,
    /// `M_22 = m l^2 / 3`, kg m^2.
    pub m22: T,
    /// `M_11 M_22`, kg^2 m^4 (the constant part of `det M`).
    pub m11_m22: T,
    /// `m g l / 2`, N m: the elbow link's gravity torque factor.
    pub mgl2: T,
    /// `3 m g l / 2`, N m: the base link's gravity torque factor.
    pub mgl2_3: T,
    /// Spring stiffness `k`, N m/rad.
    pub k: T,
    /// Spring rest angle `alpha0`, rad.
    pub alpha0: T,
    /// Joint damping `sigma`, N m s/rad.
    pub sigma: T,
}

impl<T: Real> ArmTerms<T> {
    /// The folded factors of `p` (not validated here; see [`Params::validate`]).
    #[inline(always)]
    pub fn of(p: &Params<T>) -> Self {
        let (l, half) = (p.l, lit::<T>(0.5));
        let ml2 = p.m * l * l;
        let (m11, m22) = (ml2 * lit::<T>(4.0 / 3.0), ml2 * lit::<T>(1.0 / 3.0));
        let mgl2 = p.m * p.g * l * half;
        Self {
            l,
            m11,
            half_ml2: ml2 * half,
            m22,
            m11_m22: m11 * m22,
            mgl2,
            mgl2_3: mgl2 * lit::<T>(3.0),
            k: p.k,
            alpha0: p.alpha0,
            sigma: p.sigma,
        }
    }

    /// Everything tip-space at `(q, q_dot)` under generalised torque `u` (paper eqs.
    /// 1 to 7), with `trig` the sines and cosines of `q`: shapes and units as
    /// [`TipDynamics`]; the same value as [`Arm::tip_dynamics`] of the arm these
    /// terms were folded from.
    ///
    /// Written out in scalars: the 2x2 products of nalgebra's generic code do not
    /// inline fully, and this is evaluated about 17 times per control period.
    #[inline(always)]
    pub fn tip_dynamics_trig(&self, trig: &JointTrig<T>, q: &Vector2<T>, qd: &Vector2<T>, u: &Vector2<T>) -> TipDynamics<T> {
        let l = self.l;
        let JointTrig { s1, c1, s2, c2 } = *trig;
        let s12 = trig.s12(); // sin(theta1 - theta2)
        // M^-1 (closed form; det M >= 7/36 m^2 l^4).
        let (m11, m12, m22) = (self.m11, self.half_ml2 * trig.c21(), self.m22);
        let det = self.m11_m22 - m12 * m12;
        let (i11, i12, i22) = (m22 / det, -m12 / det, m11 / det);
        // w + c (paper eq. 1).
        let spring = self.k * (q[1] - q[0] + self.alpha0);
        let (w1, w2) = (qd[0] * qd[0], qd[1] * qd[1]);
        let wc0 = self.mgl2_3 * s1 - spring - self.sigma * (qd[1] - qd[0] - qd[0]) + self.half_ml2 * w2 * s12;
        let wc1 = self.mgl2 * s2 + spring + self.sigma * (qd[1] - qd[0]) - self.half_ml2 * w1 * s12;
        let (v0, v1) = (u[0] - wc0, u[1] - wc1);
        let (qdd0, qdd1) = (i11 * v0 + i12 * v1, i12 * v0 + i22 * v1);
        // J = [[l c1, l c2], [l s1, l s2]] (paper eq. 1), s = J_dot q_dot (eq. 4).
        let (j11, j12, j21, j22) = (l * c1, l * c2, l * s1, l * s2);
        let s_t = -l * (w1 * s1 + w2 * s2);
        let s_n = l * (w1 * c1 + w2 * c2);
        // J M^-1, then Q = (J M^-1) J^T (eq. 3).
        let (a11, a12) = (j11 * i11 + j12 * i12, j11 * i12 + j12 * i22);
        let (a21, a22) = (j21 * i11 + j22 * i12, j21 * i12 + j22 * i22);
        let (q11, q12) = (a11 * j11 + a12 * j12, a11 * j21 + a12 * j22);
        let (q21, q22) = (a21 * j11 + a22 * j12, a21 * j21 + a22 * j22);
        TipDynamics {
            z: Vector2::new(l * (s1 + s2), -l * (c1 + c2)),
            z_dot: Vector2::new(j11 * qd[0] + j12 * qd[1], j21 * qd[0] + j22 * qd[1]),
            jac: Matrix2::new(j11, j12, j21, j22),
            m_inv: Matrix2::new(i11, i12, i12, i22),
            qmat: Matrix2::new(q11, q12, q21, q22),
            a_free: Vector2::new(j11 * qdd0 + j12 * qdd1 + s_t, j21 * qdd0 + j22 * qdd1 + s_n),
            qdd_free: Vector2::new(qdd0, qdd1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::SlipDirection;
    use crate::kinematics::{jacobian, jdot_qdot, tip_position};

    fn arm() -> Arm<f64> {
        Arm::new(Params::paper())
    }

    #[test]
    fn mass_matrix_is_symmetric_positive_definite_over_a_grid() {
        let a = arm();
        for i in -20..=20 {
            for j in -20..=20 {
                let q = Vector2::new(0.16 * i as f64, 0.16 * j as f64);
                let m = a.mass_matrix(&q);
                assert_eq!(m[(0, 1)], m[(1, 0)]);
                let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
                assert!(m[(0, 0)] > 0.0 && det > 0.0, "q = {q:?}");
                let mi = a.mass_matrix_inverse(&q);
                assert!((m * mi - Matrix2::identity()).norm() < 1e-12);
                let qm = a.q_matrix(&q);
                assert!((qm[(0, 1)] - qm[(1, 0)]).abs() < 1e-9 * qm.norm());
            }
        }
    }

    #[test]
    fn w_is_the_gradient_of_the_potential_plus_damping() {
        // With sigma = 0, w(q, .) = dV/dq.
        let mut p = Params::<f64>::paper();
        p.sigma = 0.0;
        let a = Arm::new(p);
        let h = 1e-6;
        let q = Vector2::new(0.3, -0.7);
        let w = a.w(&q, &Vector2::new(2.0, -1.0));
        for k in 0..2 {
            let mut dq = Vector2::zeros();
            dq[k] = h;
            let fd = (a.potential_energy(&(q + dq)) - a.potential_energy(&(q - dq))) / (2.0 * h);
            assert!((fd - w[k]).abs() < 1e-8);
        }
    }

    #[test]
    fn c_is_the_coriolis_term_of_the_lagrangian() {
        // For L = T - V with T = 1/2 q_dot^T M q_dot, the Euler-Lagrange equations give
        // M q_ddot + (dM/dt) q_dot - dT/dq + dV/dq = 0, so c = (dM/dt) q_dot - dT/dq.
        let a = arm();
        let h = 1e-6;
        let q = Vector2::new(0.4, -0.2);
        let qd = Vector2::new(1.7, -2.3);
        let mdot = (a.mass_matrix(&(q + qd * h)) - a.mass_matrix(&(q - qd * h))) / (2.0 * h);
        let mut dtdq = Vector2::zeros();
        for k in 0..2 {
            let mut dq = Vector2::zeros();
            dq[k] = h;
            dtdq[k] = (a.kinetic_energy(&(q + dq), &qd) - a.kinetic_energy(&(q - dq), &qd)) / (2.0 * h);
        }
        let c_fd = mdot * qd - dtdq;
        assert!((c_fd - a.c(&q, &qd)).norm() < 1e-8, "{c_fd:?} vs {:?}", a.c(&q, &qd));
    }

    #[test]
    fn tip_acceleration_matches_finite_differences_along_a_free_motion() {
        let a = arm();
        let q = Vector2::new(-0.2, -0.6);
        let qd = Vector2::new(0.8, -1.1);
        let u = Vector2::new(0.3, -0.1);
        let td = a.tip_dynamics(&q, &qd, &u);
        let h = 1e-5;
        let zdot = |dt: f64| {
            let qq = q + qd * dt + td.qdd_free * (0.5 * dt * dt);
            let qqd = qd + td.qdd_free * dt;
            jacobian(a.params.l, &qq) * qqd
        };
        let fd = (zdot(h) - zdot(-h)) / (2.0 * h);
        assert!((fd - td.a_free).norm() < 1e-6, "{fd:?} vs {:?}", td.a_free);
        // The force term: Q f is the tip acceleration added by f.
        let f = Vector2::new(-2.0, 5.0);
        let dz = td.jac * (td.qdd_with_force(&f) - td.qdd_free);
        assert!((dz - td.qmat * f).norm() < 1e-9);
    }

    #[test]
    fn p_is_mirror_symmetric() {
        // Mirroring the arm about the vertical (theta -> -theta) flips the sign of
        // Q_21 and keeps Q_22, so p(mirror q, mu, -dir) = p(q, mu, dir).
        let a = arm();
        for i in -10..=10 {
            for j in -10..=10 {
                let q = Vector2::new(0.12 * i as f64, 0.13 * j as f64 - 0.05);
                let qm = -q;
                for dir in [SlipDirection::Positive, SlipDirection::Negative] {
                    let lhs = a.p(&qm, dir.reversed());
                    let rhs = a.p(&q, dir);
                    assert!((lhs - rhs).abs() <= 1e-12 * rhs.abs().max(1.0), "q={q:?}");
                }
                // And with mu = 0, p = Q_22 > 0 whatever the direction.
                let mut p0 = a.params;
                p0.mu = 0.0;
                assert!(Arm::new(p0).p(&q, SlipDirection::Positive) > 0.0);
            }
        }
    }

    #[test]
    fn fused_tip_dynamics_equals_the_term_by_term_model() {
        let a = arm();
        for i in -5..=5 {
            let q = Vector2::new(0.3 * i as f64 - 0.1, -0.25 * i as f64 + 0.4);
            let qd = Vector2::new(1.1 - 0.3 * i as f64, 0.7 * i as f64);
            let u = Vector2::new(0.2, -0.3);
            let td = a.tip_dynamics(&q, &qd, &u);
            let m_inv = a.mass_matrix(&q).try_inverse().unwrap();
            let qdd = m_inv * (u - a.w(&q, &qd) - a.c(&q, &qd));
            let jac = jacobian(a.params.l, &q);
            assert!((td.qdd_free - qdd).norm() < 1e-10 * qdd.norm().max(1.0));
            assert!((td.jac - jac).norm() < 1e-15);
            assert!((td.z - tip_position(a.params.l, &q)).norm() < 1e-15);
            let a_free = jac * qdd + jdot_qdot(a.params.l, &q, &qd);
            assert!((td.a_free - a_free).norm() < 1e-10 * a_free.norm().max(1.0));
            assert!((td.qmat - jac * m_inv * jac.transpose()).norm() < 1e-10 * td.qmat.norm());
        }
    }

    #[test]
    fn f32_and_f64_agree() {
        let a64 = arm();
        let a32 = Arm::new(Params::<f32>::paper());
        let q = Vector2::new(-0.2, -0.6);
        let qd = Vector2::new(0.8, -1.1);
        let u = Vector2::new(0.3, -0.1);
        let t64 = a64.tip_dynamics(&q, &qd, &u);
        let t32 = a32.tip_dynamics(&q.cast::<f32>(), &qd.cast::<f32>(), &u.cast::<f32>());
        assert!(((t32.b() as f64) - t64.b()).abs() < 1e-4 * t64.b().abs().max(1.0));
        assert!(((t32.qmat[(1, 1)] as f64) - t64.qmat[(1, 1)]).abs() < 1e-4 * t64.qmat[(1, 1)]);
    }
}
