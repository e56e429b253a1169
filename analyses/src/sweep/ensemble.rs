//! A sweep's ensemble over seeds (`--seeds N`, issue 82): what each seed changes
//! ([`Jitter`], [`Draw`]) and the statistics of a proportion over the seeds
//! ([`Proportion`], the Wilson score interval).
//!
//! The sampled closed loop is a random process: the load cell's noise decides
//! where the saturated loop lifts off (docs/results.md, Fig. 9 at `mu` 0.9), so
//! one run per grid point is one sample of it. Seed `k` of `N`:
//! - `k = 0` is the nominal run: the scenario's noise seed, no jitter (a sweep
//!   with `--seeds 1`, the default, is the sweep as it was);
//! - `k >= 1` runs the scenario's sensor-noise seed plus `k` (closed loop) and,
//!   when bounds are given, draws independent uniform offsets within them for
//!   `mu`, the start's `z_t`, `f_n*` and the command delay `delta` (ChaCha8,
//!   seeded from the sweep's `seed` and `k`). The draws of seed `k` are the same
//!   at every grid point (common random numbers, as the random initial
//!   conditions are), so neighbouring cells differ by the grid only.
//!
//! The open loop has no noise: there the seeds only jitter (`mu` and the start),
//! and a cell whose seeds disagree sits on a boundary of the outcome within that
//! resolution (a band's edge, the critical `mu`).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The largest number of seeds per grid point.
pub const MAX_SEEDS: usize = 10_000;

/// Half-widths of the uniform jitter of seeds `k >= 1` (each offset is drawn
/// from `[-bound, bound]`); 0 leaves that quantity at its nominal value.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Jitter {
    /// Friction coefficient `mu` (the plant's; closed loop, `mu_hat` follows it), dimensionless.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub mu: f64,
    /// The start's tip position along the belt `z_t`, m (the arm re-placed on the
    /// belt by inverse kinematics at the same elbow branch, at rest).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub start_m: f64,
    /// Closed loop: the normal-force reference `f_n*`, N.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub f_n_ref_n: f64,
    /// Closed loop: the command delay `delta` (`timing.delta_s`), s.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub delay_s: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl Jitter {
    /// Whether no quantity is jittered.
    pub fn is_none(&self) -> bool {
        *self == Self::default()
    }

    /// Checks that every bound is finite and `>= 0`.
    ///
    /// # Errors
    /// A message naming the option (`--jitter-mu`, ...).
    pub fn check(&self) -> Result<(), String> {
        for (flag, v) in self.named() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("--{flag} must be finite and >= 0, got {v}"));
            }
        }
        Ok(())
    }

    /// The bounds with their options' names.
    pub fn named(&self) -> [(&'static str, f64); 4] {
        [("jitter-mu", self.mu), ("jitter-start", self.start_m), ("jitter-f-n-ref", self.f_n_ref_n), ("jitter-delay", self.delay_s)]
    }

    /// The jitter in words, e.g. `mu +-0.001, z_t of the start +-0.1 mm`; `none`.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.mu > 0.0 {
            parts.push(format!("mu +-{}", self.mu));
        }
        if self.start_m > 0.0 {
            parts.push(format!("z_t of the start +-{} mm", self.start_m * 1e3));
        }
        if self.f_n_ref_n > 0.0 {
            parts.push(format!("f_n* +-{} N", self.f_n_ref_n));
        }
        if self.delay_s > 0.0 {
            parts.push(format!("delta +-{} us", self.delay_s * 1e6));
        }
        if parts.is_empty() { "none".into() } else { parts.join(", ") }
    }
}

/// What seed `k` of a sweep changes: the sensor-noise seed offset and the
/// jitter's offsets (all 0 for `k = 0`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Draw {
    /// The seed's number, `0..N`.
    pub seed: usize,
    /// Added to the scenario's `sensors.seed` (closed loop): `k`.
    pub noise_seed_offset: u64,
    /// Added to `mu`.
    pub d_mu: f64,
    /// Added to the start's `z_t`, m.
    pub d_start_m: f64,
    /// Added to `f_n*`, N.
    pub d_f_n_ref_n: f64,
    /// Added to the command delay `delta`, s.
    pub d_delay_s: f64,
}

impl Draw {
    /// Seed `k`'s draw from the sweep's `seed` and `jitter`: nothing for `k = 0`;
    /// otherwise the noise seed offset `k` and uniform offsets in `[-bound,
    /// bound]` from ChaCha8 seeded with `seed` and `k` (drawn in the order `mu`,
    /// start, `f_n*`, delay, whether or not a bound is 0, so adding a bound does
    /// not move the others' draws).
    pub fn of(seed: u64, jitter: &Jitter, k: usize) -> Self {
        if k == 0 {
            return Self::default();
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let mut uniform = |bound: f64| {
            let u: f64 = rng.random_range(-1.0..=1.0);
            u * bound
        };
        Self {
            seed: k,
            noise_seed_offset: k as u64,
            d_mu: uniform(jitter.mu),
            d_start_m: uniform(jitter.start_m),
            d_f_n_ref_n: uniform(jitter.f_n_ref_n),
            d_delay_s: uniform(jitter.delay_s),
        }
    }
}

/// The two-sided 95 % normal quantile (`z` of the Wilson interval).
pub const Z95: f64 = 1.959_963_984_540_054;

/// A proportion `k` of `n` with its Wilson score 95 % interval (E. B. Wilson,
/// "Probable inference, the law of succession, and statistical inference",
/// JASA 22, 1927; Brown, Cai and DasGupta, Stat. Sci. 16, 2001, recommend it
/// over the Wald interval for small `n` and proportions near 0 or 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Proportion {
    /// Successes.
    pub k: usize,
    /// Trials.
    pub n: usize,
    /// `k / n` (NaN for `n = 0`).
    pub fraction: f64,
    /// Lower end of the 95 % interval (0 for `n = 0`).
    pub lo: f64,
    /// Upper end of the 95 % interval (1 for `n = 0`).
    pub hi: f64,
}

impl Proportion {
    /// `k` of `n` (`k <= n`) with the Wilson score interval at `z` = [`Z95`]:
    /// centre `(p + z^2/2n) / (1 + z^2/n)`, half-width
    /// `z sqrt(p (1 - p)/n + z^2/4n^2) / (1 + z^2/n)`.
    pub fn of(k: usize, n: usize) -> Self {
        if n == 0 {
            return Self { k, n, fraction: f64::NAN, lo: 0.0, hi: 1.0 };
        }
        let (kf, nf) = (k.min(n) as f64, n as f64);
        let p = kf / nf;
        let z2 = Z95 * Z95;
        let denom = 1.0 + z2 / nf;
        let centre = (p + z2 / (2.0 * nf)) / denom;
        let half = Z95 * (p * (1.0 - p) / nf + z2 / (4.0 * nf * nf)).sqrt() / denom;
        // At k = 0 and k = n the interval touches 0 and 1 exactly.
        let lo = if k == 0 { 0.0 } else { (centre - half).max(0.0) };
        let hi = if k >= n { 1.0 } else { (centre + half).min(1.0) };
        Self { k, n, fraction: p, lo, hi }
    }

    /// Whether the interval contains one half: the cell's outcome is not decided
    /// by its seeds either way (at 95 %).
    pub fn straddles_half(&self) -> bool {
        self.lo <= 0.5 && self.hi >= 0.5
    }

    /// `k/n = fraction [lo, hi]`, e.g. `10/30 = 0.33 [0.19, 0.51]`.
    pub fn describe(&self) -> String {
        format!("{}/{} = {:.2} [{:.2}, {:.2}]", self.k, self.n, self.fraction, self.lo, self.hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Published values: Newcombe (1998, Stat. Med. 17, Table I, method 3):
    /// 81/263 -> [0.2553, 0.3662]; 15/148 -> [0.0624, 0.1605]; 0/20 -> [0, 0.1611];
    /// 1/29 -> [0.0061, 0.1718].
    #[test]
    fn wilson_matches_newcombe() {
        for (k, n, lo, hi) in [(81, 263, 0.2553, 0.3662), (15, 148, 0.0624, 0.1605), (0, 20, 0.0, 0.1611), (1, 29, 0.0061, 0.1718)] {
            let p = Proportion::of(k, n);
            assert!((p.lo - lo).abs() < 5e-5 && (p.hi - hi).abs() < 5e-5, "{k}/{n}: {p:?}");
        }
    }

    proptest! {
        /// The interval holds the fraction, lies in [0, 1], is symmetric under
        /// k -> n - k, and narrows as n grows at a fixed fraction.
        #[test]
        fn wilson_interval_properties(n in 1usize..500, k in 0usize..500) {
            let k = k % (n + 1);
            let p = Proportion::of(k, n);
            prop_assert!(0.0 <= p.lo && p.lo <= p.fraction && p.fraction <= p.hi && p.hi <= 1.0, "{:?}", p);
            let q = Proportion::of(n - k, n);
            prop_assert!((p.lo - (1.0 - q.hi)).abs() < 1e-12 && (p.hi - (1.0 - q.lo)).abs() < 1e-12);
            let big = Proportion::of(4 * k, 4 * n);
            prop_assert!(big.hi - big.lo < p.hi - p.lo);
        }

        /// Seed 0 is nominal; the others lie within their bounds, depend on the
        /// seed and `k`, and a zero bound gives a zero offset.
        #[test]
        fn draws_lie_within_their_bounds(seed in any::<u64>(), k in 1usize..1000, mu in 0.0f64..0.1, f in 0.0f64..2.0) {
            let j = Jitter { mu, start_m: 0.0, f_n_ref_n: f, delay_s: 1e-4 };
            prop_assert_eq!(Draw::of(seed, &j, 0), Draw::default());
            let d = Draw::of(seed, &j, k);
            prop_assert!(d.d_mu.abs() <= mu && d.d_f_n_ref_n.abs() <= f && d.d_delay_s.abs() <= 1e-4);
            prop_assert_eq!(d.d_start_m, 0.0);
            prop_assert_eq!((d.seed, d.noise_seed_offset), (k, k as u64));
            prop_assert_eq!(d, Draw::of(seed, &j, k));
        }
    }

    /// Uniform draws: over 4 000 seeds the offsets' mean is near 0 and their
    /// variance near `bound^2 / 3` (a 5-sigma margin of the sample statistics).
    #[test]
    fn draws_are_uniform() {
        let j = Jitter { mu: 1.0, ..Jitter::default() };
        let n = 4000;
        let x: Vec<f64> = (1..=n).map(|k| Draw::of(7, &j, k).d_mu).collect();
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| v * v).sum::<f64>() / n as f64;
        // Var of U(-1,1) is 1/3, sd of the mean sqrt(1/3/n); of x^2: sqrt(4/45/n).
        assert!(mean.abs() < 5.0 * (1.0 / 3.0 / n as f64).sqrt(), "{mean}");
        assert!((var - 1.0 / 3.0).abs() < 5.0 * (4.0 / 45.0 / n as f64).sqrt(), "{var}");
    }
}
