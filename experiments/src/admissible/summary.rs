//! The outputs of `sil-host admissible` other than the figure: `admissible.json` and the human summary.

use analyses::admissible::{AdmissibleReport, MIRROR_TOL_M, PositiveInterval, ROOT_TOL_M, SCAN_STEPS};
use serde::Serialize;
use shared::{ElbowBranch, SlipDirection};

/// The admissible intervals of `z_t` (m, `[lo, hi]` pairs) on each elbow branch, for one sign of `z_r_dot`.
#[derive(Serialize)]
pub struct JsonBranches {
    /// Elbow up, m.
    pub elbow_up: Vec<[f64; 2]>,
    /// Elbow down, m.
    pub elbow_down: Vec<[f64; 2]>,
}

/// The mirror check: the intervals for `z_r_dot < 0` are those for `z_r_dot > 0` mirrored (`z_t -> -z_t`, elbow up <-> down).
#[derive(Serialize)]
pub struct JsonMirror {
    /// Whether the ends agree within the tolerance.
    pub ok: bool,
    /// The largest difference of corresponding ends, m (`None` when the interval counts differ).
    pub max_endpoint_difference_m: Option<f64>,
    /// The tolerance, m.
    pub tolerance_m: f64,
}

/// `admissible.json` (and `--json`): paper Table II for `mu`, both signs of `z_r_dot`.
#[derive(Serialize)]
pub struct JsonReport<'a> {
    /// The experiment, as docs/model.md names it.
    pub experiment: &'static str,
    /// Friction coefficient `mu`.
    pub mu: f64,
    /// Height `H` of the shoulder above the belt, m.
    pub h_m: f64,
    /// Link length `l`, m.
    pub l_m: f64,
    /// Half-length of the reachable belt segment, m.
    pub reach_m: f64,
    /// How the intervals were found (the scan and the root tolerance).
    pub method: String,
    /// The intervals where `p > 0` with `z_r_dot > 0` (the paper's Table II).
    pub z_r_dot_positive: JsonBranches,
    /// The intervals where `p > 0` with `z_r_dot < 0`.
    pub z_r_dot_negative: JsonBranches,
    /// Which sign of `z_r_dot` the paper's table is ([`PAPER_DIRECTION`]).
    pub paper_direction: &'static str,
    /// The mirror check.
    pub mirror_check: JsonMirror,
    /// Files written.
    pub files: &'a [String],
    /// The parameters used (paper Table I with `--set`, `mu`; SI, radians).
    pub params: shared::Params<f64>,
}

/// Why the paper's Table II is the `z_r_dot > 0` half.
pub const PAPER_DIRECTION: &str = "The paper's experiments have v_belt < 0 with the tip at rest or moving slower than the belt, \
so z_r_dot = z_t_dot - v_belt > 0: its Table II corresponds to z_r_dot_positive. \
z_r_dot_negative is the mirror image (z_t -> -z_t, elbow up <-> elbow down).";

/// `admissible.json`'s document of the report `r`, listing `files`.
pub fn json_report<'a>(r: &AdmissibleReport, files: &'a [String]) -> JsonReport<'a> {
    let pairs = |b, d| r.intervals(b, d).iter().map(|i| [i.lo, i.hi]).collect::<Vec<_>>();
    let branches = |d| JsonBranches { elbow_up: pairs(ElbowBranch::Up, d), elbow_down: pairs(ElbowBranch::Down, d) };
    JsonReport {
        experiment: "docs/model.md experiment 2 (paper Table II): ranges of z_t (m) on the belt (z_n = -H) where p > 0",
        mu: r.params.mu,
        h_m: r.params.h,
        l_m: r.params.l,
        reach_m: r.reach,
        method: format!(
            "scan of {SCAN_STEPS} steps over [-reach, reach] plus bisection of each sign change of p to {ROOT_TOL_M:e} m; \
             an interval end equal to +-reach_m is the end of the reachable belt, not a zero of p"
        ),
        z_r_dot_positive: branches(SlipDirection::Positive),
        z_r_dot_negative: branches(SlipDirection::Negative),
        paper_direction: PAPER_DIRECTION,
        mirror_check: JsonMirror {
            ok: r.mirror_max_diff.is_some_and(|d| d <= MIRROR_TOL_M),
            max_endpoint_difference_m: r.mirror_max_diff,
            tolerance_m: MIRROR_TOL_M,
        },
        params: r.params,
        files,
    }
}

/// The intervals as text, `[lo, hi] m` each (4 decimals), or `none`.
pub fn fmt_intervals(iv: &[PositiveInterval]) -> String {
    if iv.is_empty() {
        return "none".into();
    }
    iv.iter()
        .map(|i| {
            let end = |x: f64, root: bool| if root { format!("{x:.4}") } else { format!("{x:.4}*") };
            format!("[{}, {}]", end(i.lo, i.lo_is_root), end(i.hi, i.hi_is_root))
        })
        .collect::<Vec<_>>()
        .join(" U ")
}
