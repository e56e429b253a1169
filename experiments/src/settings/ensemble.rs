//! `--seeds N` and its jitter bounds (issue 82): how many runs a sampled-loop
//! result is drawn from, shared by `sweep`, `zmax`, `sensitivity` and `report`
//! ([`analyses::sweep::ensemble`] says what each seed changes).

use analyses::sweep::Jitter;

/// `--seeds` and `--jitter-*`.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct EnsembleArgs {
    /// Runs per grid point (or per study point): seed 0 is the nominal run (the
    /// scenario's sensor-noise seed, no jitter), seeds 1.. the noise's next seeds
    /// and the --jitter-* draws. Each result is then a fraction with its Wilson
    /// 95 % interval. 1, the default, is one sample of the sampled loop's random
    /// process (the saturated loop's outcome depends on its noise: docs/results.md).
    /// The open loop and --ideal have no noise: there, N > 1 needs --jitter-mu or
    /// --jitter-start.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1, value_name = "N"))]
    pub seeds: usize,
    /// Seeds 1..: draw mu uniformly within +-this of each grid value (mu_hat follows).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0, value_name = "DMU"))]
    pub jitter_mu: f64,
    /// Seeds 1..: move the start's tip along the belt uniformly within +-this, m
    /// (the arm re-placed on the belt at the same elbow branch, at rest).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0, value_name = "M"))]
    pub jitter_start: f64,
    /// Seeds 1.., sampled closed loop: draw f_n* uniformly within +-this, N.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0, value_name = "N"))]
    pub jitter_f_n_ref: f64,
    /// Seeds 1.., sampled closed loop: draw the command delay (timing.delta_s)
    /// uniformly within +-this, s (it must stay within [0, one period)).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0, value_name = "S"))]
    pub jitter_delay: f64,
}

impl Default for EnsembleArgs {
    fn default() -> Self {
        Self { seeds: 1, jitter_mu: 0.0, jitter_start: 0.0, jitter_f_n_ref: 0.0, jitter_delay: 0.0 }
    }
}

impl EnsembleArgs {
    /// The jitter's bounds.
    pub fn jitter(&self) -> Jitter {
        Jitter { mu: self.jitter_mu, start_m: self.jitter_start, f_n_ref_n: self.jitter_f_n_ref, delay_s: self.jitter_delay }
    }
}
