//! The bisection for the largest value with a property ([`super`] documentation):
//! [`bisect_largest`], its outcome ([`Bisection`]) and its cost.

use serde::Serialize;

/// The outcome of a bisection for the largest `x` with `ok(x)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum Bisection {
    /// `ok(lo)` and not `ok(hi)` with `hi - lo <= tol`: the limit is `lo`.
    Found {
        /// Largest value found ok.
        lo: f64,
        /// Smallest value found not ok.
        hi: f64,
        /// Evaluations of the predicate.
        evaluations: u32,
    },
    /// The lower end of the bracket is already not ok: no limit in the bracket.
    LowerFails {
        /// The lower end.
        lo: f64,
        /// Evaluations.
        evaluations: u32,
    },
    /// The upper end is ok: the limit is at least `hi`.
    UpperReached {
        /// The upper end.
        hi: f64,
        /// Evaluations.
        evaluations: u32,
    },
}

impl Bisection {
    /// The largest value verified ok (`None` if the lower end fails).
    pub fn limit(&self) -> Option<f64> {
        match *self {
            Self::Found { lo, .. } => Some(lo),
            Self::LowerFails { .. } => None,
            Self::UpperReached { hi, .. } => Some(hi),
        }
    }

    /// The outcome's name in tables: `found`, `lower_fails` or `upper_reached`.
    pub fn outcome_name(&self) -> &'static str {
        match self {
            Self::Found { .. } => "found",
            Self::LowerFails { .. } => "lower_fails",
            Self::UpperReached { .. } => "upper_reached",
        }
    }

    /// Evaluations of the predicate.
    pub fn evaluations(&self) -> u32 {
        match *self {
            Self::Found { evaluations, .. } | Self::LowerFails { evaluations, .. } | Self::UpperReached { evaluations, .. } => evaluations,
        }
    }
}

/// Evaluations [`bisect_largest`] makes on `[lo, hi]` to tolerance `tol` at most.
pub fn max_evaluations(lo: f64, hi: f64, tol: f64) -> u32 {
    2 + ((hi - lo) / tol).log2().ceil().max(0.0) as u32
}

/// Trials a [`search`](super::search) on `[lo, hi]` to `tol` runs at most: the lift-off
/// bisection, then the tracking bisection inside its bracket (whose ends it reuses).
pub fn max_trials(lo: f64, hi: f64, tol: f64) -> u32 {
    2 * max_evaluations(lo, hi, tol) - 2
}

/// Bisection for the largest `x` in `[lo, hi]` with `ok(x)`, assuming `ok` is true
/// below a threshold and false above it: `ok(lo)`, then `ok(hi)`, then halving
/// until the bracket is at most `tol` wide (`lo < hi`, `tol > 0`, all finite; the
/// caller checks). For a non-monotone `ok` it returns one switching point.
///
/// # Errors
/// The first error of `ok`.
pub fn bisect_largest<E>(mut lo: f64, mut hi: f64, tol: f64, mut ok: impl FnMut(f64) -> Result<bool, E>) -> Result<Bisection, E> {
    let mut evaluations = 1;
    if !ok(lo)? {
        return Ok(Bisection::LowerFails { lo, evaluations });
    }
    evaluations += 1;
    if ok(hi)? {
        return Ok(Bisection::UpperReached { hi, evaluations });
    }
    while hi - lo > tol {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        evaluations += 1;
        if ok(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Bisection::Found { lo, hi, evaluations })
}
