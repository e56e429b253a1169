//! The outputs of `sil-host sweep` and `sil-host merge`: `sweep.csv`, `summary.json`, the figures and the human summary.

use crate::{
    error::CliError,
    output::OutputSet,
    sweep::{
        figures,
        store::{self, Manifest},
    },
};
use analyses::sweep::{
    InitialCondition, Shard, SweepController, SweepSpec,
    run::RunRow,
    summary::{self, Results},
};
use serde::Serialize;
use std::{collections::BTreeMap, io::Write, path::Path};

/// The paper's experiment 3: 10 x 181 grid points, two initial conditions, 300 s each.
pub(crate) const PAPER_GRID_SIMULATED_S: f64 = 10.0 * 181.0 * 2.0 * 300.0;

/// Timing of this invocation.
#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    /// Runs computed by this invocation.
    pub runs_computed: usize,
    /// Worker threads.
    pub threads: usize,
    /// Wall-clock time of the runs, s.
    pub wall_s: f64,
    /// Simulated time of the runs computed, s.
    pub simulated_s: f64,
    /// Simulated seconds per wall second per worker thread.
    pub simulated_s_per_wall_s_per_core: f64,
    /// CPU time (user + system) of the process during the runs, s.
    pub cpu_s: f64,
    /// Simulated seconds per CPU second (what a core does when not shared with
    /// other work: on a loaded machine the wall-clock rate is lower).
    pub simulated_s_per_cpu_s: f64,
    /// The paper's full open-loop grid (3620 runs of 300 s) at this rate on
    /// `threads` cores, s (an extrapolation: the cost per simulated second varies
    /// over the grid, bouncing runs costing most).
    pub paper_grid_projection_s: f64,
}

impl Timing {
    /// The timing of `computed` runs of `spec` on `threads` threads in `wall_s`
    /// s of wall-clock time and `cpu_s` s of CPU time.
    pub fn of(spec: &SweepSpec, computed: usize, threads: usize, wall_s: f64, cpu_s: f64) -> Self {
        let simulated_s = computed as f64 * spec.run_duration();
        let rate = simulated_s / (wall_s.max(1e-9) * threads as f64);
        Self {
            runs_computed: computed,
            threads,
            wall_s,
            simulated_s,
            simulated_s_per_wall_s_per_core: rate,
            cpu_s,
            simulated_s_per_cpu_s: simulated_s / cpu_s.max(1e-9),
            paper_grid_projection_s: if rate > 0.0 { PAPER_GRID_SIMULATED_S / (rate * threads as f64) } else { f64::NAN },
        }
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SweepSummary {
    /// `complete`, `incomplete` (runs missing: --limit, or a merge with
    /// --allow-missing) or `interrupted`.
    pub status: &'static str,
    /// The sweep.
    pub spec: SweepSpec,
    /// The part of it in this folder.
    pub shard: Shard,
    /// The initial conditions (before the plant's projection onto the belt).
    pub initial_conditions: Vec<InitialCondition>,
    /// How the initial conditions were treated.
    pub projection_note: &'static str,
    /// Where `theta1_dot_max` and `z_n_max` come from.
    pub maxima_note: &'static str,
    /// Critical `mu`, bands and outcome counts.
    pub results: Results,
    /// This invocation's timing (`None` for a merge).
    pub timing: Option<Timing>,
    /// Runs whose row was already in the journal when this invocation started.
    pub resumed_runs: usize,
    /// Files written.
    pub files: Vec<String>,
}

pub(crate) const PROJECTION_NOTE: &str = "the paper's initial conditions, given in rounded degrees, put the tip a fraction of a millimetre \
     inside the belt; each is projected onto the belt at the same z_t and elbow branch before simulating (height_above_belt is \
     the tip's height as given)";

pub(crate) const MAXIMA_NOTE: &str = "maxima over the continuous trajectory of the record window: both ends of every integrator step, \
     and maxima inside steps located where the slope changes sign and read from the step's 7th-order dense output";

/// User plus system CPU time of this process so far, s (getrusage).
pub fn cpu_seconds() -> f64 {
    // SAFETY: getrusage only writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    tv(u.ru_utime) + tv(u.ru_stime)
}

/// Writes the outputs of the folder from its rows: `sweep.csv`, `summary.json` and
/// the figures (all or nothing, [`OutputSet`]).
pub(crate) fn finish(
    dir: &Path,
    m: &Manifest,
    mut rows: Vec<RunRow>,
    timing: Option<Timing>,
    resumed: usize,
    interrupted: bool,
) -> Result<SweepSummary, CliError> {
    rows.sort_by_key(|r| r.index);
    let missing = store::missing(m, &rows).len();
    let results = summary::results(&m.spec, &rows, missing);
    let mut out = OutputSet::new(dir)?;
    let csv_tmp = out.stage("sweep.csv");
    store::write_rows(&csv_tmp, &rows)?;
    // Figures per impact law and e_n.
    let mut by_case: BTreeMap<(String, u64), Vec<&RunRow>> = BTreeMap::new();
    for r in &rows {
        by_case.entry((r.impact_law.clone(), r.e_n.to_bits())).or_default().push(r);
    }
    let mut files = vec![dir.join("sweep.csv")];
    for law in &m.spec.impact_laws {
        for &e_n in &m.spec.e_n {
            let empty = Vec::new();
            let case_rows = by_case.get(&(law.name().to_string(), e_n.to_bits())).unwrap_or(&empty);
            let suffix = figures::case_suffix(law.name(), e_n);
            let map = format!("map_{suffix}.svg");
            let slices = format!("slices_{suffix}.svg");
            figures::draw_map(&out.stage(&map), &m.spec, law.name(), e_n, case_rows)?;
            figures::draw_slices(&out.stage(&slices), &m.spec, law.name(), e_n, case_rows)?;
            files.push(dir.join(map));
            files.push(dir.join(slices));
        }
    }
    files.push(dir.join("summary.json"));
    let files = files.iter().map(|p| p.display().to_string()).collect();
    let summary = summary_of(m, results, missing, timing, resumed, interrupted, files);
    out.write_json("summary.json", &summary)?;
    out.commit()?;
    Ok(summary)
}

/// `summary.json` of the sweep `m` from its `results` (with `missing` runs not
/// in its folder), this invocation's `timing` (`None` for a merge), the runs
/// `resumed` from the journal, whether it was `interrupted`, and the `files` written.
pub fn summary_of(
    m: &Manifest,
    results: Results,
    missing: usize,
    timing: Option<Timing>,
    resumed: usize,
    interrupted: bool,
    files: Vec<String>,
) -> SweepSummary {
    SweepSummary {
        status: if interrupted {
            "interrupted"
        } else if missing > 0 {
            "incomplete"
        } else {
            "complete"
        },
        spec: m.spec.clone(),
        shard: m.shard,
        initial_conditions: m.spec.initial_conditions(),
        projection_note: PROJECTION_NOTE,
        maxima_note: MAXIMA_NOTE,
        results,
        timing,
        resumed_runs: resumed,
        files,
    }
}

pub(crate) fn report(s: &SweepSummary, json: bool) {
    if json {
        println!("{}", serde_json::to_string_pretty(s).unwrap_or_default());
        return;
    }
    let mut o = std::io::stdout().lock();
    let ctrl = match (s.spec.controller, s.spec.ideal) {
        (SweepController::None, _) => "open loop (u = 0)".to_string(),
        (c, true) => format!("closed loop, {} (ideal continuous-time)", c.name()),
        (c, false) => format!("closed loop, {} firmware in-process at the scenario's rate", c.name()),
    };
    let _ = writeln!(
        o,
        "sweep: {}, mu {}..{} ({} values), v_belt {}..{} m/s ({} values), transient {} s + record {} s, {} initial conditions",
        ctrl,
        s.spec.mu.start,
        s.spec.mu.stop,
        s.spec.mu.len(),
        s.spec.v_belt.start,
        s.spec.v_belt.stop,
        s.spec.v_belt.len(),
        s.spec.transient_s,
        s.spec.record_s,
        s.initial_conditions.len()
    );
    for ic in &s.initial_conditions {
        let deg = ic.x0.map(f64::to_degrees);
        let _ = writeln!(
            o,
            "  {}: [{:.4}, {:.1}, {:.4}, {:.1}] deg (elbow {}), tip {:.3} mm {} the belt{}",
            ic.name,
            deg[0],
            deg[1],
            deg[2],
            deg[3],
            ic.branch.name(),
            ic.height_above_belt.abs() * 1e3,
            if ic.height_above_belt < 0.0 { "inside" } else { "above" },
            if ic.height_above_belt <= 1e-12 { ": projected onto it" } else { "" }
        );
    }
    summary::print_table(&mut o, &s.results);
    if let Some(t) = &s.timing
        && t.runs_computed > 0
    {
        let _ = writeln!(
            o,
            "speed: {} runs in {:.1} s on {} threads: {:.0} simulated s per wall s per core ({:.0} per CPU s); a grid of the paper's size (3620 runs x 300 s) would take {:.1} min at this rate",
            t.runs_computed,
            t.wall_s,
            t.threads,
            t.simulated_s_per_wall_s_per_core,
            t.simulated_s_per_cpu_s,
            t.paper_grid_projection_s / 60.0
        );
    }
    let _ = writeln!(o, "status: {}; wrote {}", s.status, s.files.join(", "));
}
