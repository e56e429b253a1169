//! The outputs of `sil-host zmax` other than the figures: the rows of `zmax.csv` and `trials.csv`, `summary.json` and the human table.

use analyses::zmax::Setting;
use analyses::zmax::{Bisection, Criteria, Search, StopReason, Trial};
use firmware::ControllerKind;
use plant::{Validity, initial::PaperX0};
use rig::scenario::Scenario;
use serde::Serialize;

/// One row of `zmax.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxRow {
    /// `pid` or `hybrid`.
    pub controller: ControllerKind,
    /// `d` or `u`.
    pub x0: PaperX0,
    /// `ideal` or `sampled`.
    pub setting: Setting,
    /// The lift-off bisection: `found`, `lower_fails` or `upper_reached`.
    pub outcome: &'static str,
    /// `Z_t,sliding`, m: the largest target the tip was verified to slide to (the
    /// paper's definition; empty when the lower end already fails).
    pub z_t_sliding_m: Option<f64>,
    /// `max |z_t - z_t*|` over the settle window of the trial at `Z_t,sliding`, m:
    /// how far from its target the tip was there (a PID past the fold of `theta1`
    /// stays free of lift-off without getting near its target).
    pub error_at_limit_m: Option<f64>,
    /// Smallest target found that the tip does not slide to, m (empty unless found).
    pub first_failing_m: Option<f64>,
    /// That trial's (or, for `lower_fails`, the lower end's) stop reason:
    /// `lift_off`, `safe_state`, `failure`, `not_reached` or `invalid`.
    pub stop_failing: Option<StopReason>,
    /// Why it failed, in words.
    pub why_failing: Option<String>,
    /// The paper's `Z_t,sliding` for this case, m (empty where it found none).
    pub paper_z_t_sliding_m: Option<f64>,
    /// The tracking bisection (on `[lo, Z_t,sliding]`): `found`, `lower_fails` or
    /// `upper_reached`.
    pub tracking_outcome: &'static str,
    /// The tracking limit, m: the largest target verified tracked (slid to and
    /// settled within the settle tolerance).
    pub z_t_tracking_m: Option<f64>,
    /// Smallest target found not tracked, m.
    pub tracking_first_failing_m: Option<f64>,
    /// That trial's stop reason (`not_settled`, or a reason above).
    pub tracking_stop_failing: Option<StopReason>,
    /// Why it was not tracked, in words.
    pub tracking_why_failing: Option<String>,
    /// Bracket searched, m.
    pub bracket_lo_m: f64,
    /// Bracket searched, m.
    pub bracket_hi_m: f64,
    /// End of the admissible range (`p = 0` on the belt, `z_r_dot > 0`) on the
    /// initial condition's elbow branch, m (paper Table II).
    pub p_zero_end_m: Option<f64>,
    /// Where `theta1` is largest along the belt on the initial condition's branch, m
    /// (empty if at the end of the bracket): the PID acts on `theta1` alone, and
    /// `theta1*(z_t*)` past this fold is also the `theta1` of a point before it.
    pub theta1_fold_m: Option<f64>,
    /// Trials run.
    pub trials: u32,
    /// Trials whose trajectory violated the model (never counted as reached).
    pub invalid_trials: u32,
    /// Wall-clock time of the search, s.
    pub wall_s: f64,
}

// `zmax.csv`: the columns serde writes, declared (CSV reader, Arrow schema).
tables::declare!(ZmaxRow {
    controller: str,
    x0: str,
    setting: str,
    outcome: str,
    z_t_sliding_m: f64,
    error_at_limit_m: f64,
    first_failing_m: f64,
    stop_failing: str,
    why_failing: str,
    paper_z_t_sliding_m: f64,
    tracking_outcome: str,
    z_t_tracking_m: f64,
    tracking_first_failing_m: f64,
    tracking_stop_failing: str,
    tracking_why_failing: str,
    bracket_lo_m: f64,
    bracket_hi_m: f64,
    p_zero_end_m: f64,
    theta1_fold_m: f64,
    trials: int,
    invalid_trials: int,
    wall_s: f64,
});

/// The gains of `sil-host zmax`'s trials (paper eqs. 8 to 11), ideal and sampled alike.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxGains {
    /// PID gains per joint (eq. 8).
    pub pid: rig::scenario::PidSection,
    /// `K'_P`, 1/s^2 (eq. 10).
    pub hybrid_kp: f64,
    /// `K'_D`, 1/s (eq. 10).
    pub hybrid_kd: f64,
    /// `K'_I` from `x0d`, 1/s (eq. 11).
    pub hybrid_ki_x0d: f64,
    /// `K'_I` from `x0u`, 1/s (eq. 11).
    pub hybrid_ki_x0u: f64,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxSummary {
    /// One row per case.
    pub results: Vec<ZmaxRow>,
    /// Every trial of every case.
    pub trials: Vec<Trial>,
    /// The criteria of a trial.
    pub criteria: Criteria,
    /// Bisection tolerance, m.
    pub tol_m: f64,
    /// What a trial checks.
    pub definition: &'static str,
    /// The paper's figures and definition (docs/model.md "What the paper reports").
    pub paper: &'static str,
    /// The base scenario of the sampled setting (its target, run length, controller
    /// and initial condition are set per trial).
    pub base_scenario: Scenario,
    /// Validity counters summed over every trial.
    pub validity: Validity,
    /// The plant's parameters of every trial (paper Table I, `mu`, `v_belt`; SI,
    /// radians), from the base scenario.
    pub plant_params: shared::Params<f64>,
    /// The gains of every trial (paper eqs. 8 to 11), `K'_I` resolved per
    /// initial condition.
    pub gains: ZmaxGains,
    /// What the sampled results are drawn from: one noise seed, or several.
    pub samples: String,
    /// With `--seeds N`: every sampled case's search per seed (`zmax_seeds.csv`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub seeds: Vec<SeedRow>,
    /// With `--seeds N`: `Z_t,sliding` and the tracking limit of each sampled case
    /// over its seeds.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub distributions: Vec<ZmaxDistribution>,
    /// Wall-clock time of the whole command, s.
    pub wall_s: f64,
}

/// One row of `zmax_seeds.csv`: a sampled case's search at one seed.
#[derive(Debug, Clone, Serialize)]
pub struct SeedRow {
    /// `pid` or `hybrid`.
    pub controller: ControllerKind,
    /// `d` or `u`.
    pub x0: PaperX0,
    /// `sampled`.
    pub setting: Setting,
    /// The seed (`0..N`; 0 is `results`' search).
    pub seed: usize,
    /// The lift-off bisection: `found`, `lower_fails` or `upper_reached`.
    pub outcome: &'static str,
    /// `Z_t,sliding` at this seed, m (empty when the lower end fails).
    pub z_t_sliding_m: Option<f64>,
    /// `max |z_t - z_t*|` over the settle window of this seed's trial at its
    /// `Z_t,sliding`, m (the noise moves it even where the limit stays).
    pub error_at_limit_m: Option<f64>,
    /// Smallest target found that the tip does not slide to, m.
    pub first_failing_m: Option<f64>,
    /// That trial's stop reason.
    pub stop_failing: Option<StopReason>,
    /// The tracking limit at this seed, m.
    pub z_t_tracking_m: Option<f64>,
    /// Trials run.
    pub trials: u32,
}

// `zmax_seeds.csv`: the columns serde writes, declared (CSV reader, Arrow schema, Python).
tables::declare!(SeedRow {
    controller: str,
    x0: str,
    setting: str,
    seed: int,
    outcome: str,
    z_t_sliding_m: f64,
    error_at_limit_m: f64,
    first_failing_m: f64,
    stop_failing: str,
    z_t_tracking_m: f64,
    trials: int,
});

impl SeedRow {
    /// The row of search `s` at seed `seed`.
    pub fn of(seed: usize, s: &Search) -> Self {
        let c = s.combination;
        Self {
            controller: c.controller,
            x0: c.x0,
            setting: c.setting,
            seed,
            outcome: s.bisection.outcome_name(),
            z_t_sliding_m: s.z_t_sliding,
            error_at_limit_m: s.z_t_sliding.and_then(|z| s.trial_at(z)).map(|t| t.settle_error_m),
            first_failing_m: match s.bisection {
                Bisection::Found { hi, .. } => Some(hi),
                _ => None,
            },
            stop_failing: s.failing_trial(&s.bisection).map(|t| t.stop),
            z_t_tracking_m: s.z_t_tracking,
            trials: s.trials.len() as u32,
        }
    }
}

/// Quantiles of a limit over the seeds, m: the values ordered with "none" (the
/// lower end of the bracket already fails) below every target; a quantile that
/// lands on "none" is `None`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    /// Smallest.
    pub min_m: Option<f64>,
    /// Lower quartile.
    pub q1_m: Option<f64>,
    /// Median.
    pub median_m: Option<f64>,
    /// Upper quartile.
    pub q3_m: Option<f64>,
    /// Largest.
    pub max_m: Option<f64>,
    /// Seeds with no limit (the lower end fails).
    pub none: usize,
}

impl Spread {
    /// The spread of `values` (one per seed; non-empty), quantiles by the nearest
    /// rank on the sorted values (`rank = ceil(q n)`, the median of an even count the
    /// lower middle one, a value some seed gave).
    pub fn of(values: &[Option<f64>]) -> Self {
        let mut v: Vec<Option<f64>> = values.to_vec();
        v.sort_by(|a, b| match (a, b) {
            (None, None) => std::cmp::Ordering::Equal,
            (None, Some(_)) => std::cmp::Ordering::Less,
            (Some(_), None) => std::cmp::Ordering::Greater,
            (Some(x), Some(y)) => x.total_cmp(y),
        });
        let n = v.len();
        let at = |q: f64| if n == 0 { None } else { v[((q * n as f64).ceil() as usize).clamp(1, n) - 1] };
        Self {
            min_m: at(0.0),
            q1_m: at(0.25),
            median_m: at(0.5),
            q3_m: at(0.75),
            max_m: at(1.0),
            none: v.iter().filter(|x| x.is_none()).count(),
        }
    }

    /// `median [q1, q3], min..max` in mm-resolved metres, e.g. `0.1523 [0.1490, 0.1531], 0.1402..0.1540 m`.
    pub fn describe(&self) -> String {
        let t = |x: Option<f64>| x.map_or("none".to_string(), |v| format!("{v:.4}"));
        format!("{} [{}, {}], {}..{} m", t(self.median_m), t(self.q1_m), t(self.q3_m), t(self.min_m), t(self.max_m))
    }
}

/// A sampled case's limits over its seeds (`summary.json`'s `distributions`).
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxDistribution {
    /// `pid` or `hybrid`.
    pub controller: ControllerKind,
    /// `d` or `u`.
    pub x0: PaperX0,
    /// `sampled`.
    pub setting: Setting,
    /// Seeds.
    pub seeds: usize,
    /// `Z_t,sliding` over the seeds.
    pub z_t_sliding: Spread,
    /// The tracking limit over the seeds.
    pub z_t_tracking: Spread,
}

impl ZmaxDistribution {
    /// One per sampled case of `rows` (in their order of first appearance) when
    /// `seeds > 1`; none otherwise.
    pub fn of_rows(rows: &[SeedRow], seeds: usize) -> Vec<Self> {
        if seeds <= 1 {
            return Vec::new();
        }
        let mut out: Vec<Self> = Vec::new();
        for r in rows {
            if out.iter().any(|d| (d.controller, d.x0) == (r.controller, r.x0)) {
                continue;
            }
            let of: Vec<&SeedRow> = rows.iter().filter(|x| (x.controller, x.x0) == (r.controller, r.x0)).collect();
            let sliding: Vec<Option<f64>> = of.iter().map(|x| x.z_t_sliding_m).collect();
            let tracking: Vec<Option<f64>> = of.iter().map(|x| x.z_t_tracking_m).collect();
            out.push(Self {
                controller: r.controller,
                x0: r.x0,
                setting: r.setting,
                seeds: of.len(),
                z_t_sliding: Spread::of(&sliding),
                z_t_tracking: Spread::of(&tracking),
            });
        }
        out
    }
}

#[cfg(test)]
mod spread_tests {
    use super::Spread;

    /// Nearest-rank quantiles: of 1..=8 the median is 4, the quartiles 2 and 6;
    /// "none" sorts below every value.
    #[test]
    fn nearest_rank_quantiles() {
        let v: Vec<Option<f64>> = (1..=8).map(|i| Some(f64::from(i))).collect();
        let s = Spread::of(&v);
        assert_eq!((s.min_m, s.q1_m, s.median_m, s.q3_m, s.max_m, s.none), (Some(1.0), Some(2.0), Some(4.0), Some(6.0), Some(8.0), 0));
        let s = Spread::of(&[Some(0.2), None, None, Some(0.1)]);
        assert_eq!((s.min_m, s.median_m, s.max_m, s.none), (None, None, Some(0.2), 2));
        assert_eq!(Spread::of(&[Some(0.3)]).median_m, Some(0.3));
    }
}

/// What a trial is and what counts as sliding (in `summary.json`).
pub const DEFINITION: &str = "A trial drives z_t* from the initial tip position by a quintic move over move_time_s, then holds it until duration_s. \
The tip slides to the target when it never leaves the belt (no lift-off event, located exactly between samples too; no impact without collision; no sample in flight), \
the run ends normally (no plant failure, firmware safe state or ideal-law fault) with no model violation (energy-creating impact, friction-cone violation), \
and |z_t - z_t*| <= reach_tol_m at every sample of the last settle_window_s. The target is tracked when, in addition, |z_t - z_t*| <= settle_tol_m there. \
Z_t,sliding (the paper's definition, the largest z_t such that no lift-off occurs) is the largest target the tip was verified to slide to, by bisection on [lo, hi] to tol_m; \
the tracking limit is the largest target verified tracked, by bisection on [lo, Z_t,sliding]. \
lower_fails: lo already fails (no limit); upper_reached: the limit is at least hi. \
Each trial's stop reason (the first that applies): invalid, lift_off, safe_state, failure, not_reached, not_settled or tracked.";

/// What the paper reports for `Z_t,sliding` (in `summary.json`).
pub const PAPER: &str = analyses::paper::Z_T_SLIDING_SUMMARY;

impl ZmaxRow {
    /// The row of one search; `p_zero_end_m` and `theta1_fold_m` as computed by the command.
    pub fn of(s: &Search, p_zero_end_m: Option<f64>, theta1_fold_m: Option<f64>) -> Self {
        let first = |b: &Bisection| match *b {
            Bisection::Found { hi, .. } => Some(hi),
            _ => None,
        };
        let lift = s.failing_trial(&s.bisection);
        let track = s.failing_trial(&s.tracking);
        let c = s.combination;
        Self {
            controller: c.controller,
            x0: c.x0,
            setting: c.setting,
            outcome: s.bisection.outcome_name(),
            z_t_sliding_m: s.z_t_sliding,
            error_at_limit_m: s.z_t_sliding.and_then(|z| s.trial_at(z)).map(|t| t.settle_error_m),
            first_failing_m: first(&s.bisection),
            stop_failing: lift.map(|t| t.stop),
            why_failing: lift.and_then(Trial::why_not),
            paper_z_t_sliding_m: analyses::paper::z_t_sliding(c.controller, c.x0).flatten(),
            tracking_outcome: s.tracking.outcome_name(),
            z_t_tracking_m: s.z_t_tracking,
            tracking_first_failing_m: first(&s.tracking),
            tracking_stop_failing: track.map(|t| t.stop),
            tracking_why_failing: track.and_then(Trial::why_not),
            bracket_lo_m: s.bracket.0,
            bracket_hi_m: s.bracket.1,
            p_zero_end_m,
            theta1_fold_m,
            trials: s.trials.len() as u32,
            invalid_trials: s.trials.iter().filter(|t| t.stop == StopReason::Invalid).count() as u32,
            wall_s: s.wall_s,
        }
    }
}

/// A row of `trials.csv`: one trial ([`Trial`], borrowed) as flat cells, its case's
/// three fields and its validity counters inline. A view, not a copy: the `csv` crate
/// writes no nested struct under a header, and [`Validity`]'s JSON leaves zero
/// counters out where a table needs every column. Its columns, each with its kind
/// and its cell, are declared once ([`tables::declare_view!`]).
pub struct TrialRow<'a>(pub &'a Trial);

tables::declare_view!(TrialRow of Trial {
    controller: str = |t| t.combination.controller,
    x0: str = |t| t.combination.x0,
    setting: str = |t| t.combination.setting,
    target_z_t_m: f64 = |t| t.target_z_t,
    stop: str = |t| t.stop,
    slides_to_target: bool = |t| t.slides_to_target,
    tracked: bool = |t| t.tracked,
    lift_offs: int = |t| t.lift_offs,
    impacts_without_collision: int = |t| t.impacts_without_collision,
    first_lift_off_s: f64 = |t| t.first_lift_off_s,
    settle_error_m: f64 = |t| t.settle_error_m,
    failure: str = |t| t.failure,
    simulated_s: f64 = |t| t.simulated_s,
    wall_s: f64 = |t| t.wall_s,
    energy_gains: int = |t| t.validity.energy_gains,
    newton_fallbacks: int = |t| t.validity.newton_fallbacks,
    poisson_fallbacks: int = |t| t.validity.poisson_fallbacks,
    cone_violations: int = |t| t.validity.cone_violations,
    zeno_stops: int = |t| t.validity.zeno_stops,
    integrator_failures: int = |t| t.validity.integrator_failures,
    ledger_violations: int = |t| t.validity.ledger_violations,
});

/// A limit for tables: `< lo` when the lower end fails, `>= hi` when the upper end
/// passes, else the value, m to 4 decimals.
pub fn limit_text(outcome: &str, value: Option<f64>, lo: f64, hi: f64) -> String {
    match (outcome, value) {
        ("lower_fails", _) => format!("< {lo:.4}"),
        ("upper_reached", Some(v)) => format!(">= {v:.4}"),
        ("upper_reached", None) => format!(">= {hi:.4}"),
        (_, Some(v)) => format!("{v:.4}"),
        (_, None) => "-".into(),
    }
}
