//! The online friction estimate of the hybrid law's robust variant
//! ([`FrictionCompensation::Estimated`](crate::config::FrictionCompensation::Estimated);
//! docs/controllers.md "Friction not known"): `mu` from the load cell's `f_t / f_n`
//! while the tip slides, low-pass filtered, bounded around `mu_hat`, and frozen
//! where the ratio cannot be trusted.
//!
//! While the tip slides, Coulomb's law gives `f_t = -mu s f_n` whatever the
//! torques, so `-s f_t / f_n` measures `mu` with no feedback through the estimate
//! (unlike feeding the measured `f_t` itself into the law, whose loop gain
//! `-mu s Q_21 / p` grows without bound as `p -> 0+`; config.rs). The estimate is a
//! first-order filter of that ratio with time constant [`TAU_S`] (Olsson, Åström,
//! Canudas de Wit, Gäfvert and Lischinsky, "Friction models and friction
//! compensation", Eur. J. Control 4, 1998, sec. 6: friction estimation from
//! measured forces, filtered), bounded to `mu_hat (1 +- BOUND)`, and frozen
//! (held) where the ratio is not a measure of `mu`:
//! - the measured `f_n` below [`F_N_MIN_FRACTION`] of `f_n*` (or below 0.5 N):
//!   lift-off, flight, or a ratio of small, noisy forces;
//! - the slip speed `|z_r_dot|` below [`V_R_MIN`], or its sign changed since the
//!   last period: sticking or slip reversal, where `|f_t| <= mu f_n` is a
//!   constraint force, not Coulomb's;
//! - `p / Q_22` below [`P_MIN`] (near the Painlevé boundary `p -> 0+`), where the
//!   slide is about to jam or leave and the forces move faster than a period.
//!
//! The estimate is held as the correction `mu_est - mu_hat` (0 at the start), so
//! that the law's state starts from zeros.

/// Time constant of the estimate's low-pass filter, s: 20 periods at 1 kHz, 5 at
/// 250 Hz, 200 at 10 kHz.
pub const TAU_S: f32 = 0.02;

/// Bound of the estimate around `mu_hat`, as a fraction of it: `mu_hat (1 +- 0.5)`.
pub const BOUND: f32 = 0.5;

/// Smallest measured `f_n` for an update, as a fraction of `f_n*` (and at least 0.5 N).
pub const F_N_MIN_FRACTION: f32 = 0.3;

/// Smallest slip speed `|z_r_dot|` for an update, m/s.
pub const V_R_MIN: f32 = 0.01;

/// Smallest `p / Q_22` for an update (dimensionless).
pub const P_MIN: f32 = 0.2;

/// The estimate's state: the correction `mu_est - mu_hat` and the last slip
/// direction (`+-1`; 0 before the first update).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MuEstimate {
    /// `mu_est - mu_hat` (dimensionless).
    pub correction: f32,
    /// `sign(z_r_dot)` at the last period (0: none yet).
    pub last_slip: f32,
}

/// What one period measured, for [`MuEstimate::update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionSample {
    /// Measured `f_t`, N.
    pub f_t: f32,
    /// Measured `f_n`, N.
    pub f_n: f32,
    /// The normal force reference `f_n*`, N.
    pub f_n_ref: f32,
    /// Estimated slip speed `z_r_dot = z_t_dot - v_belt`, m/s.
    pub v_r: f32,
    /// `p` with the current estimate and `Q_22`, in one positive scale (the law
    /// passes both times `det M`, which saves the division by it): only their
    /// ratio is used.
    pub p: f32,
    /// `Q_22`, in the scale of `p` (> 0).
    pub q22: f32,
}

impl MuEstimate {
    /// The estimate `mu_hat + correction` (dimensionless).
    pub fn mu(&self, mu_hat: f32) -> f32 {
        mu_hat + self.correction
    }

    /// One period of `dt` s: updates the estimate from `sample` if it can be
    /// trusted (module docs), else holds it. Returns whether it updated. A
    /// non-finite sample is never used.
    pub fn update(&mut self, mu_hat: f32, sample: &FrictionSample, dt: f32) -> bool {
        self.update_with_gain(mu_hat, sample, gain(dt))
    }

    /// [`MuEstimate::update`] with the filter's gain per period folded once per
    /// configuration, `alpha = `[`gain`]`(dt)` (0: never updates): the same bits,
    /// without the step's checks of `dt` (a score of integer instructions on the MCU).
    // Inlined: one call site (the hybrid law), whose register saves cost about as much as its body.
    #[inline(always)]
    pub fn update_with_gain(&mut self, mu_hat: f32, sample: &FrictionSample, alpha: f32) -> bool {
        let s = if sample.v_r < 0.0 { -1.0 } else { 1.0 };
        let same_slip = self.last_slip == s;
        self.last_slip = if sample.v_r.abs() >= V_R_MIN { s } else { 0.0 };
        let f_min = if F_N_MIN_FRACTION * sample.f_n_ref > 0.5 { F_N_MIN_FRACTION * sample.f_n_ref } else { 0.5 };
        let trusted = sample.f_n > f_min && sample.v_r.abs() >= V_R_MIN && same_slip && sample.p > P_MIN * sample.q22;
        let ratio = -s * sample.f_t / sample.f_n;
        // No check of `f_t` of its own: where `trusted` holds, `f_n > f_min >= 0.5`
        // (so not NaN) and, checked here, finite; then a non-finite `f_t` (inf or
        // NaN) makes `ratio = -s f_t / f_n` inf or NaN, which the check rejects.
        // `f_n` and `ratio` in one check, of their sum: with `f_n > 0.5` the sum is
        // finite exactly when both are (`f_n = +inf` makes it inf or NaN, and two
        // finite terms never overflow: `|ratio| <= MAX / f_n`, so the sum is at most
        // `f_n + MAX / f_n`, below `MAX + 2` on `(0.5, MAX]`). The same verdict for
        // every input (tests `a_non_finite_force_*`, `the_sums_check_*`).
        let finite = crate::finite::finite(sample.f_n + ratio);
        if !(trusted && finite && alpha > 0.0) {
            return false;
        }
        let bound = BOUND * mu_hat;
        let target = clamp(ratio - mu_hat, -bound, bound);
        self.correction += alpha * (target - self.correction);
        true
    }
}

/// The estimate's filter gain per period of `dt` s: `dt / TAU_S`, at most 1 (a
/// period past the time constant takes the ratio whole); 0 for a `dt` that is not
/// finite and positive (then the estimate never updates).
pub fn gain(dt: f32) -> f32 {
    if !(dt.is_finite() && dt > 0.0) {
        0.0
    } else if dt < TAU_S {
        dt * (1.0 / TAU_S)
    } else {
        1.0
    }
}

/// `x` clamped to `[lo, hi]` by comparisons (core's `f32::clamp` calls `fminf`/`fmaxf` on the MCU).
fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sliding(f_t: f32) -> FrictionSample {
        FrictionSample { f_t, f_n: 10.0, f_n_ref: 10.0, v_r: 0.3, p: 0.8, q22: 1.0 }
    }

    /// A slide with `mu = 0.72` seen by a law told `mu_hat = 0.6`: the estimate is a
    /// first-order filter of the ratio (after the first period, which only sets the
    /// slip direction), within 1 % of `mu` after five time constants.
    /// The gain folded once per configuration is the step's: `update_with_gain(gain(dt))`
    /// keeps `update(dt)`'s state bit for bit, over rates from 250 Hz to 100 kHz, a
    /// period past the time constant and the refused periods (0, negative, NaN, infinite).
    #[test]
    fn the_folded_gain_is_the_steps() {
        for dt in [1e-3f32, 1e-4, 4e-3, 1e-5, 0.02, 0.05, 0.0, -1e-3, f32::NAN, f32::INFINITY] {
            let (mut a, mut b) = (MuEstimate::default(), MuEstimate::default());
            for i in 0..50 {
                let sample = FrictionSample { f_t: -4.0 - 0.1 * i as f32, ..sliding(-5.0) };
                assert_eq!(a.update(0.5, &sample, dt), b.update_with_gain(0.5, &sample, gain(dt)), "dt {dt}");
                assert_eq!(
                    (a.correction.to_bits(), a.last_slip.to_bits()),
                    (b.correction.to_bits(), b.last_slip.to_bits()),
                    "dt {dt}, step {i}"
                );
            }
        }
        assert_eq!(gain(1e-3).to_bits(), (1e-3f32 * (1.0 / TAU_S)).to_bits());
        assert_eq!((gain(0.05), gain(0.0), gain(f32::NAN)), (1.0, 0.0, 0.0));
    }

    #[test]
    fn the_estimate_converges_to_the_measured_ratio() {
        let mut e = MuEstimate::default();
        let dt = 1e-3;
        assert!(!e.update(0.6, &sliding(-7.2), dt), "no slip direction yet");
        assert!(e.update(0.6, &sliding(-7.2), dt));
        assert!((e.correction - 0.12 * dt / TAU_S).abs() < 1e-7, "one filter step: {}", e.correction);
        for _ in 0..(5.0 * TAU_S / dt) as usize {
            e.update(0.6, &sliding(-7.2), dt);
        }
        assert!((e.mu(0.6) - 0.72).abs() < 0.01 * 0.72, "{}", e.mu(0.6));
        // A slide the other way measures the same mu from f_t of the other sign.
        let mut back = MuEstimate::default();
        let reverse = FrictionSample { f_t: 7.2, v_r: -0.3, ..sliding(0.0) };
        for _ in 0..200 {
            back.update(0.6, &reverse, dt);
        }
        assert!((back.mu(0.6) - 0.72).abs() < 0.01 * 0.72, "{}", back.mu(0.6));
    }

    /// Bounded to `mu_hat (1 +- 0.5)` however wrong the ratio.
    #[test]
    fn the_estimate_is_bounded() {
        let mut e = MuEstimate::default();
        for _ in 0..1000 {
            e.update(0.6, &sliding(-30.0), 1e-3);
        }
        assert!((e.correction - BOUND * 0.6).abs() < 1e-6, "{}", e.correction);
        for _ in 0..1000 {
            e.update(0.6, &sliding(0.0), 1e-3);
        }
        assert!((e.correction + BOUND * 0.6).abs() < 1e-6, "{}", e.correction);
    }

    /// Without `f_t`'s own finiteness check the verdict and the state are those of
    /// the three checks (`f_t`, `f_n`, the ratio) for every non-finite force, with
    /// `f_n` above, at and below the trust threshold: a NaN or infinite force is never used.
    #[test]
    fn a_non_finite_force_is_refused_as_by_the_three_checks() {
        let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -f32::NAN];
        let three = |e: &mut MuEstimate, x: &FrictionSample| {
            let finite = x.f_t.is_finite() && x.f_n.is_finite() && (-x.f_t / x.f_n).is_finite();
            let before = *e;
            let used = e.update_with_gain(0.6, x, gain(1e-3));
            if !finite {
                *e = before;
                return false;
            }
            used
        };
        let mut held = MuEstimate::default();
        held.update(0.6, &sliding(-7.2), 1e-3);
        for &bad in &odd {
            for (f_t, f_n) in [(bad, 10.0), (-7.2, bad), (bad, bad), (bad, 0.5), (bad, 1e30), (bad, -10.0), (1e38, 1e-30)] {
                let x = FrictionSample { f_t, f_n, ..sliding(0.0) };
                let (mut a, mut b) = (held, held);
                let used = a.update_with_gain(0.6, &x, gain(1e-3));
                assert_eq!(used, three(&mut b, &x), "{x:?}");
                assert_eq!(a.correction.to_bits(), b.correction.to_bits(), "{x:?}");
                if !(f_t.is_finite() && f_n.is_finite()) {
                    assert!(!used && a.correction.to_bits() == held.correction.to_bits(), "{x:?} was used");
                }
                assert!(a.correction.is_finite());
            }
        }
    }

    /// The sum's check gives the two checks' verdict (`f_n` and the ratio finite)
    /// wherever `trusted` holds: forces over the whole `f32` range by exponent and
    /// mantissa, both signs, the non-finite values, and `f_n` from just above the
    /// trust threshold to `MAX`; the same state after every update.
    #[test]
    fn the_sums_check_is_the_two_checks() {
        let two_checks = |e: &mut MuEstimate, x: &FrictionSample| {
            let s = if x.v_r < 0.0 { -1.0 } else { 1.0 };
            let ratio = -s * x.f_t / x.f_n;
            if !(crate::finite::finite(x.f_n) && crate::finite::finite(ratio)) {
                // Refused either way: only the slip direction moves.
                e.last_slip = if x.v_r.abs() >= V_R_MIN { s } else { 0.0 };
                return false;
            }
            e.update_with_gain(0.6, x, gain(1e-3))
        };
        let mut values = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, -f32::MAX, 0.0, -0.0, 0.5, 3.0];
        for e in -126..=127 {
            for m in [1.0f32, 1.25, 1.999_999_9] {
                let x = m * libm::exp2f(e as f32);
                values.extend([x, -x]);
            }
        }
        let mut held = MuEstimate::default();
        held.update(0.6, &sliding(-7.2), 1e-3);
        let mut n = 0;
        for &f_t in &values {
            for &f_n in &values {
                for v_r in [0.3f32, -0.3] {
                    let x = FrictionSample { f_t, f_n, v_r, ..sliding(0.0) };
                    let (mut a, mut b) = (held, held);
                    assert_eq!(a.update_with_gain(0.6, &x, gain(1e-3)), two_checks(&mut b, &x), "{x:?}");
                    assert_eq!((a.correction.to_bits(), a.last_slip.to_bits()), (b.correction.to_bits(), b.last_slip.to_bits()), "{x:?}");
                    n += 1;
                }
            }
        }
        assert!(n > 1_000_000);
    }

    /// Frozen where the ratio is not `mu`: low `f_n`, slow slip, the period after a
    /// slip reversal, near `p -> 0`, and a sample that is not finite.
    #[test]
    fn the_estimate_is_frozen_where_it_cannot_be_trusted() {
        let mut e = MuEstimate::default();
        e.update(0.6, &sliding(-7.2), 1e-3);
        e.update(0.6, &sliding(-7.2), 1e-3);
        let held = e;
        let untrusted = [
            FrictionSample { f_n: 2.0, f_t: -2.0, ..sliding(0.0) },
            FrictionSample { v_r: 0.005, ..sliding(-7.2) },
            FrictionSample { p: 0.1, ..sliding(-7.2) },
            sliding(f32::NAN),
            FrictionSample { f_n: f32::INFINITY, ..sliding(-7.2) },
        ];
        for sample in untrusted {
            let mut e = held;
            assert!(!e.update(0.6, &sample, 1e-3), "{sample:?}");
            assert_eq!(e.correction, held.correction, "{sample:?}");
        }
        // A reversal: the first period in the new direction is held, the next updates.
        let mut e = held;
        let reverse = FrictionSample { f_t: 7.2, v_r: -0.3, ..sliding(0.0) };
        assert!(!e.update(0.6, &reverse, 1e-3));
        assert!(e.update(0.6, &reverse, 1e-3));
    }
}
