//! The outputs of `sil-host admissible` other than the figure: `admissible.json` and the human summary.

use analyses::admissible::{AdmissibleReport, MIRROR_TOL_M, PositiveInterval, ROOT_TOL_M, SCAN_STEPS};
use serde::Serialize;
use shared::{ElbowBranch, SlipDirection};

#[derive(Serialize)]
pub(crate) struct JsonBranches {
    pub(crate) elbow_up: Vec<[f64; 2]>,
    pub(crate) elbow_down: Vec<[f64; 2]>,
}

#[derive(Serialize)]
pub(crate) struct JsonMirror {
    pub(crate) ok: bool,
    pub(crate) max_endpoint_difference_m: Option<f64>,
    pub(crate) tolerance_m: f64,
}

#[derive(Serialize)]
pub(crate) struct JsonReport<'a> {
    pub(crate) experiment: &'static str,
    pub(crate) mu: f64,
    pub(crate) h_m: f64,
    pub(crate) l_m: f64,
    /// Half-length of the reachable belt segment, m.
    pub(crate) reach_m: f64,
    pub(crate) method: String,
    pub(crate) z_r_dot_positive: JsonBranches,
    pub(crate) z_r_dot_negative: JsonBranches,
    pub(crate) paper_direction: &'static str,
    pub(crate) mirror_check: JsonMirror,
    pub(crate) files: &'a [String],
    /// The parameters used (paper Table I with `--set`, `mu`; SI, radians).
    pub(crate) params: shared::Params<f64>,
}

pub(crate) const PAPER_DIRECTION: &str = "The paper's experiments have v_belt < 0 with the tip at rest or moving slower than the belt, \
so z_r_dot = z_t_dot - v_belt > 0: its Table II corresponds to z_r_dot_positive. \
z_r_dot_negative is the mirror image (z_t -> -z_t, elbow up <-> elbow down).";

pub(crate) fn json_report<'a>(r: &AdmissibleReport, files: &'a [String]) -> JsonReport<'a> {
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

pub(crate) fn fmt_intervals(iv: &[PositiveInterval]) -> String {
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

/// The human summary printed by the command.
pub fn human_summary(r: &AdmissibleReport) -> String {
    let mut s = String::new();
    s += "Admissible configurations on the belt (docs/model.md experiment 2, paper Table II)\n";
    s += &format!(
        "mu = {}, H = {} m, l = {} m; reachable belt: z_t in [{:.4}, {:.4}] m\n",
        r.params.mu, r.params.h, r.params.l, -r.reach, r.reach
    );
    s += "Ranges of z_t (m) where p > 0 (* = end of the reachable belt, not a zero of p):\n";
    let rows = [("z_r_dot > 0 (paper's case)", SlipDirection::Positive), ("z_r_dot < 0 (mirror image)", SlipDirection::Negative)];
    for (label, dir) in rows {
        s += &format!("  {label}\n");
        s += &format!("    elbow up   : {}\n", fmt_intervals(r.intervals(ElbowBranch::Up, dir)));
        s += &format!("    elbow down : {}\n", fmt_intervals(r.intervals(ElbowBranch::Down, dir)));
    }
    s += "Note: the paper's experiments have v_belt < 0 with the tip at rest or slower than the belt,\n";
    s += "so z_r_dot = z_t_dot - v_belt > 0: paper Table II is the z_r_dot > 0 case.\n";
    match r.mirror_max_diff {
        Some(d) if d <= MIRROR_TOL_M => {
            s += &format!("Mirror check (z_t -> -z_t, up <-> down, z_r_dot -> -z_r_dot): ok, ends agree to {d:.1e} m\n")
        }
        Some(d) => s += &format!("Mirror check FAILED: ends differ by up to {d:.3e} m (tolerance {MIRROR_TOL_M:e} m)\n"),
        None => s += "Mirror check FAILED: the numbers of intervals differ\n",
    }
    s += &format!("Method: scan of {SCAN_STEPS} steps plus bisection of each sign change of p to {ROOT_TOL_M:e} m.\n");
    s
}
