//! The slip of the tip on the belt and the coefficient `p` it sets (paper eq. 7):
//! what both the dynamics (`model`) and the contact modes (`contact`) need.

use nalgebra::Matrix2;

use crate::Real;

/// Direction of slip: the sign of the relative tangential velocity
/// `z_r_dot = z_t_dot - v_belt`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum SlipDirection {
    /// `z_r_dot > 0`: friction acts along `-z_t`.
    Positive,
    /// `z_r_dot < 0`: friction acts along `+z_t`.
    Negative,
}

impl SlipDirection {
    /// `+1` or `-1`, as the scalar `T`.
    #[inline]
    pub fn sign<T: Real>(self) -> T {
        match self {
            Self::Positive => T::one(),
            Self::Negative => -T::one(),
        }
    }

    /// The direction of a relative velocity `z_r_dot` (m/s); zero counts as positive.
    #[inline]
    pub fn of<T: Real>(z_r_dot: T) -> Self {
        if z_r_dot < T::zero() { Self::Negative } else { Self::Positive }
    }

    /// The opposite direction (the mirror image of the arm, docs/model.md).
    #[inline]
    pub fn reversed(self) -> Self {
        match self {
            Self::Positive => Self::Negative,
            Self::Negative => Self::Positive,
        }
    }
}

/// `p = Q_22 - mu sign(z_r_dot) Q_21` (1/kg), paper eq. 7, from `Q = J M^-1 J^T`.
#[inline]
pub fn p_of<T: Real>(qmat: &Matrix2<T>, mu: T, dir: SlipDirection) -> T {
    qmat[(1, 1)] - mu * dir.sign::<T>() * qmat[(1, 0)]
}
