//! Physical parameters of the arm and the belt (docs/model.md, Table I of the paper).

use crate::{Real, lit};

/// Why a [`Params`] value was rejected by [`Params::validate`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// A parameter is NaN or infinite.
    #[error("parameter `{name}` must be finite, got {value}")]
    NonFinite {
        /// Field name, as in [`Params`].
        name: &'static str,
        /// The offending value, as `f64`.
        value: f64,
    },
    /// A parameter that must be strictly positive (masses, lengths, gravity, `H`) is not.
    #[error("parameter `{name}` must be > 0, got {value}")]
    NotPositive {
        /// Field name, as in [`Params`].
        name: &'static str,
        /// The offending value, as `f64`.
        value: f64,
    },
    /// A parameter that must be non-negative (`mu`, `sigma`, `k`) is negative.
    #[error("parameter `{name}` must be >= 0, got {value}")]
    Negative {
        /// Field name, as in [`Params`].
        name: &'static str,
        /// The offending value, as `f64`.
        value: f64,
    },
    /// A parameter is beyond its upper bound (`mu <= 10`, `|v_belt| <= 5 m/s`).
    #[error("parameter `{name}` must be at most {max}, got {value}")]
    TooLarge {
        /// Field name, as in [`Params`].
        name: &'static str,
        /// The offending value, as `f64`.
        value: f64,
        /// The bound.
        max: f64,
    },
    /// An angle (`alpha0`) beyond a half-turn: angles are in radians, and a value
    /// like paper Table I's 13.72 was most likely meant in degrees (issue 69).
    // The degrees' radians are computed when the message is written (on the host):
    // the MCU images check in `T` and link no f64 arithmetic for it (issue 69: the
    // first form multiplied in f64 and cost the PIL image 0.9 KiB of soft float).
    #[error(
        "parameter `{name}` is an angle in radians and must be within [-pi, pi], got {value} (if that was degrees, it is {rad} rad)",
        rad = .value.to_radians()
    )]
    AngleOutOfRange {
        /// Field name, as in [`Params`].
        name: &'static str,
        /// The offending value, rad.
        value: f64,
    },
    /// The belt is out of reach: the base height `H` must be below the arm's reach `2 l`.
    #[error("belt out of reach: H = {h} m must be < 2 l = {reach} m")]
    BeltOutOfReach {
        /// Height of the base above the belt, m.
        h: f64,
        /// Reach of the arm `2 l`, m.
        reach: f64,
    },
}

/// Parameters of the arm and the belt, SI units, angles in radians.
///
/// Defaults ([`Params::paper`]) are Table I of the paper (from Zhao et al. 2008),
/// with `mu = 0.6` and `v_belt = -0.4 m/s`, the values of its control experiments.
/// Construct with [`Params::new`] (validated) or take the defaults and change
/// fields, then call [`Params::validate`]; every model function assumes valid
/// parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct Params<T> {
    /// Mass of each link `m`, kg (0.12).
    pub m: T,
    /// Length of each link `l`, m (0.21).
    pub l: T,
    /// Joint damping `sigma`, N m s/rad (0.005; the paper writes N s/m).
    pub sigma: T,
    /// Stiffness of the spring between the links `k`, N m/rad (1.3).
    pub k: T,
    /// Height of the base joint above the belt `H`, m (0.3775).
    pub h: T,
    /// Spring rest angle `alpha0`, rad (13.72 degrees).
    pub alpha0: T,
    /// Gravity `g`, m/s^2 (9.81).
    pub g: T,
    /// Coulomb friction coefficient between tip and belt `mu`, dimensionless (0.6).
    pub mu: T,
    /// Belt speed along `z_t` `v_belt`, m/s (-0.4; negative in every experiment).
    pub v_belt: T,
}

impl<T: Real> Default for Params<T> {
    fn default() -> Self {
        Self::paper()
    }
}

impl<T: Real> Params<T> {
    /// Table I of the paper, with `mu = 0.6` and `v_belt = -0.4 m/s`.
    pub fn paper() -> Self {
        Self {
            m: lit(0.12),
            l: lit(0.21),
            sigma: lit(0.005),
            k: lit(1.3),
            h: lit(0.3775),
            alpha0: lit(13.72_f64.to_radians()),
            g: lit(9.81),
            mu: lit(0.6),
            v_belt: lit(-0.4),
        }
    }

    /// The paper's parameters with the given friction coefficient and belt speed,
    /// validated.
    ///
    /// # Errors
    /// [`ParamError`] when `mu` is negative or either value is not finite.
    pub fn new(mu: T, v_belt: T) -> Result<Self, ParamError> {
        let p = Self { mu, v_belt, ..Self::paper() };
        p.validate()?;
        Ok(p)
    }

    /// Checks the parameters: all finite; `m`, `l`, `h`, `g` > 0; `mu`, `sigma`,
    /// `k` >= 0; `mu <= 10`, `|v_belt| <= 5 m/s`; on the host, `|alpha0| <= pi` (radians: Table
    /// I's 13.72 degrees is 0.2395 rad); `h < 2 l` (the belt within reach).
    ///
    /// # Errors
    /// The first violation found, as a [`ParamError`] naming the field.
    pub fn validate(&self) -> Result<(), ParamError> {
        let fields: [(&'static str, T); 9] = [
            ("m", self.m),
            ("l", self.l),
            ("sigma", self.sigma),
            ("k", self.k),
            ("h", self.h),
            ("alpha0", self.alpha0),
            ("g", self.g),
            ("mu", self.mu),
            ("v_belt", self.v_belt),
        ];
        for (name, value) in fields {
            if !value.is_finite() {
                return Err(ParamError::NonFinite { name, value: to_f64(value) });
            }
        }
        for (name, value) in [("m", self.m), ("l", self.l), ("h", self.h), ("g", self.g)] {
            if value <= T::zero() {
                return Err(ParamError::NotPositive { name, value: to_f64(value) });
            }
        }
        for (name, value) in [("mu", self.mu), ("sigma", self.sigma), ("k", self.k)] {
            if value < T::zero() {
                return Err(ParamError::Negative { name, value: to_f64(value) });
            }
        }
        // Upper bounds: a friction coefficient, not a lock; the belts of docs/hardware.md.
        if self.mu > lit(10.0) {
            return Err(ParamError::TooLarge { name: "mu", value: to_f64(self.mu), max: 10.0 });
        }
        if self.v_belt.abs() > lit(5.0) {
            return Err(ParamError::TooLarge { name: "|v_belt|", value: to_f64(self.v_belt), max: 5.0 });
        }
        // A unit check for people (13.72 meant as degrees), on the host: an angle
        // beyond a half-turn is meaningless but harmless to the control (its sine
        // and cosine are a smaller angle's), so the MCU images leave it out and
        // keep their flash (180 bytes of the PIL image's 33 KiB ceiling).
        #[cfg(not(target_os = "none"))]
        if self.alpha0.abs() > lit(core::f64::consts::PI) {
            return Err(ParamError::AngleOutOfRange { name: "alpha0", value: to_f64(self.alpha0) });
        }
        let reach = self.l + self.l;
        if self.h >= reach {
            return Err(ParamError::BeltOutOfReach { h: to_f64(self.h), reach: to_f64(reach) });
        }
        Ok(())
    }

    /// The same parameters in another scalar type (e.g. the plant's `f64` set for
    /// the firmware's `f32` model).
    pub fn cast<U: Real>(&self) -> Params<U> {
        let c = |x: T| -> U { lit(to_f64(x)) };
        Params {
            m: c(self.m),
            l: c(self.l),
            sigma: c(self.sigma),
            k: c(self.k),
            h: c(self.h),
            alpha0: c(self.alpha0),
            g: c(self.g),
            mu: c(self.mu),
            v_belt: c(self.v_belt),
        }
    }
}

/// Widens a model scalar to `f64` (for error messages and casts).
pub fn to_f64<T: Real>(x: T) -> f64 {
    // `RealField` offers no direct conversion; go through simba's subset relation.
    nalgebra::try_convert::<T, f64>(x).unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_defaults_are_valid() {
        Params::<f64>::paper().validate().unwrap();
        Params::<f32>::paper().validate().unwrap();
    }

    #[test]
    fn rejects_bad_values_naming_them() {
        let mut p = Params::<f64>::paper();
        p.m = -1.0;
        assert_eq!(p.validate(), Err(ParamError::NotPositive { name: "m", value: -1.0 }));
        let mut p = Params::<f64>::paper();
        p.mu = f64::NAN;
        assert!(matches!(p.validate(), Err(ParamError::NonFinite { name: "mu", .. })));
        let mut p = Params::<f64>::paper();
        p.h = 0.5;
        assert!(matches!(p.validate(), Err(ParamError::BeltOutOfReach { .. })));
        assert!(matches!(Params::<f64>::new(-0.1, -0.4), Err(ParamError::Negative { name: "mu", .. })));
    }

    /// Issue 69 (5): `alpha0` is in radians; Table I's 13.72 given as is (degrees
    /// meant) is refused with the radians it would be, and so is any angle beyond
    /// a half-turn either way; a half-turn itself is taken.
    #[test]
    fn an_angle_beyond_a_half_turn_is_refused_with_its_radians() {
        let mut p = Params::<f64>::paper();
        p.alpha0 = 13.72;
        let e = p.validate().unwrap_err();
        assert!(matches!(e, ParamError::AngleOutOfRange { name: "alpha0", .. }));
        let text = std::string::ToString::to_string(&e);
        assert!(text.contains("radians") && text.contains("0.2394"), "{text}");
        for (a, ok) in [
            (core::f64::consts::PI, true),
            (-core::f64::consts::PI, true),
            (core::f64::consts::PI + 1e-9, false),
            (-100.0, false),
            (0.0, true),
        ] {
            p.alpha0 = a;
            assert_eq!(p.validate().is_ok(), ok, "alpha0 = {a}");
        }
    }

    #[test]
    fn cast_round_trips_within_f32_rounding() {
        let p = Params::<f64>::paper();
        let back: Params<f64> = p.cast::<f32>().cast();
        assert!((back.alpha0 - p.alpha0).abs() < 1e-7);
        assert!((back.h - p.h).abs() < 1e-7);
    }
}
