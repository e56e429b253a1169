//! The sweep's runs dealt to shards ([`Shard`], `--shard K/N`) and how they are
//! dealt ([`Assignment`]): every shard, its merge and its resume agree on which
//! shard computes each run.

use serde::{Deserialize, Serialize};

use super::SweepSpec;

/// How the runs of a sweep are dealt to `N` shards (`sweep.json`'s
/// `shard.assignment`). Every shard of a sweep, its merge and its resume use the
/// same one, computed from the spec alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Assignment {
    /// Run `i` to shard `i mod N`: folders written before the balanced assignment
    /// (a `sweep.json` whose shard has no `assignment`), resumed and merged as
    /// they were. Unbalanced: with two initial conditions and an even `N`, every
    /// run from `x0a` (the costly, bouncing one) lands on an even shard.
    #[default]
    Modulo,
    /// Balanced ([`Shard::owner`]): each row of the grid (all belt speeds at one
    /// IWC rule, impact law, `e_n`, initial condition and `mu`) is dealt round
    /// robin over the shards, continuing where the previous row stopped, its
    /// speeds rotated by a row-dependent offset.
    Balanced,
}

impl Assignment {
    fn is_modulo(&self) -> bool {
        *self == Self::Modulo
    }
}

/// `K/N` of `--shard`: this process computes shard `K` of `N` (`0 <= K < N`) of
/// the sweep's runs, dealt by [`Assignment::Balanced`] ([`Shard::owner`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, `0 <= k < n`.
    pub k: usize,
    /// Number of shards, `>= 1`.
    pub n: usize,
    /// How runs are dealt to the shards (absent in `sweep.json`: [`Assignment::Modulo`],
    /// the only one before; never written for `n = 1`, where both are the whole sweep).
    #[serde(default, skip_serializing_if = "Assignment::is_modulo")]
    pub assignment: Assignment,
}

impl Shard {
    /// The whole sweep.
    pub const ALL: Shard = Shard { k: 0, n: 1, assignment: Assignment::Modulo };

    /// Parses `K/N`: shard `K` of `N`, balanced ([`Shard::ALL`] for `0/1`).
    ///
    /// # Errors
    /// A message when the text is not `K/N` with `0 <= K < N`.
    pub fn parse(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard expects K/N with 0 <= K < N (e.g. 0/8), got `{s}`");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n) = (k.trim().parse::<usize>().map_err(|_| bad())?, n.trim().parse::<usize>().map_err(|_| bad())?);
        if n == 0 || k >= n {
            return Err(bad());
        }
        Ok(if n == 1 { Self::ALL } else { Self { k, n, assignment: Assignment::Balanced } })
    }

    /// The shard (`0..n`) that computes run `index` (`< spec.n_runs()`) of `spec`.
    ///
    /// Balanced: the runs are put in the order (IWC rule, impact law, `e_n`,
    /// initial condition, `mu`, `v_belt`), `v_belt` fastest; the run at position
    /// `p` of that order goes to shard `p mod n`. Each row (one rule, law, `e_n`,
    /// initial condition and `mu`; `n_v` belt speeds) thus holds consecutive
    /// positions, and so does every block of rows: every shard gets the same
    /// number of runs (to one), of every initial condition and of every row, and
    /// neighbouring belt speeds go to different shards. The cost of a run depends
    /// on its row (the initial condition and `mu`: on the paper's grid a run from
    /// `x0a` costs 5 to 6 times one from `x0d`) and, along the row, on the band of speeds that
    /// bounce; both are spread evenly without a cost model. Within a row the
    /// speeds are rotated by `floor(frac(r phi) n_v)` (`r` the row's number, `phi`
    /// the golden ratio; Fibonacci hashing, integer arithmetic), so that when `n_v`
    /// is a multiple of `n` a speed does not land on the same shard in every row.
    pub fn owner(&self, spec: &SweepSpec, index: usize) -> usize {
        match self.assignment {
            Assignment::Modulo => index % self.n,
            Assignment::Balanced => {
                let (n_ic, n_v, n_mu) = (spec.n_ics(), spec.v_belt.len(), spec.mu.len());
                let i_ic = index % n_ic;
                let rest = index / n_ic;
                let i_v = rest % n_v;
                // (rule, law, e_n, mu), mu fastest.
                let outer = rest / n_v;
                let row = ((outer / n_mu) * n_ic + i_ic) * n_mu + outer % n_mu;
                let offset = (((row as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) as u128 * n_v as u128) >> 64) as usize;
                (row * n_v + (i_v + offset) % n_v) % self.n
            }
        }
    }

    /// Whether run `index` of `spec` belongs to this shard.
    pub fn owns(&self, spec: &SweepSpec, index: usize) -> bool {
        self.n == 1 || self.owner(spec, index) == self.k
    }

    /// The indices of this shard's runs of `spec`, ascending.
    pub fn indices(&self, spec: &SweepSpec) -> Vec<usize> {
        (0..spec.n_runs()).filter(|&i| self.owns(spec, i)).collect()
    }
}
