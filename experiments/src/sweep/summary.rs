//! A sweep's summary (`summary.json`): the critical `mu`, bands and outcome
//! counts ([`analyses::sweep::summary`]), the spec and shard, and this
//! invocation's timing.

use super::store::Manifest;
use analyses::sweep::{
    Draw, InitialCondition, Shard, SweepController, SweepSpec,
    cells::{self, CellRow, MuFractions},
    summary::Results,
};
use serde::Serialize;

/// The paper's experiment 3: 10 x 181 grid points, two initial conditions, 300 s each.
pub const PAPER_GRID_SIMULATED_S: f64 = 10.0 * 181.0 * 2.0 * 300.0;

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
    /// What each cell's result is drawn from: one sample, or the seeds' fractions.
    pub samples: Samples,
    /// Critical `mu`, bands and outcome counts.
    pub results: Results,
    /// With several seeds per cell: the fractions per `mu` and the undecided cells
    /// (every cell is in `cells.csv`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<EnsembleResults>,
    /// This invocation's timing (`None` for a merge).
    pub timing: Option<Timing>,
    /// Runs whose row was already in the journal when this invocation started.
    pub resumed_runs: usize,
    /// Files written.
    pub files: Vec<String>,
}

impl SweepSummary {
    /// The summary with the ensemble results of `cells` (a sweep of several seeds;
    /// `None` leaves it without).
    pub fn with_cells(self, cells: Option<&[CellRow]>) -> Self {
        Self { ensemble: cells.map(EnsembleResults::of), ..self }
    }
}

/// What each cell's result is drawn from (`summary.json`'s `samples`).
#[derive(Debug, Clone, Serialize)]
pub struct Samples {
    /// Runs per cell.
    pub seeds: usize,
    /// The jitter of seeds 1.. in words (`none`).
    pub jitter: String,
    /// What that means for reading the results.
    pub note: String,
    /// What each seed changed (seed 0: nothing).
    pub draws: Vec<Draw>,
}

impl Samples {
    /// The samples of `spec`.
    pub fn of(spec: &SweepSpec) -> Self {
        let sampled = spec.controller != SweepController::None && !spec.ideal;
        let noise = spec.scenario.as_ref().map_or(0, |s| s.sensors.seed);
        let note = match (spec.seeds, sampled) {
            (1, true) => format!(
                "one sample per cell: the sampled loop is a random process (its sensor noise, seed {noise}, decides the outcome where the loop saturates; docs/results.md); --seeds N gives each cell's fraction with its Wilson 95 % interval"
            ),
            (1, false) => "one run per cell: this loop has no noise; --seeds N with --jitter-mu or --jitter-start marks the cells whose outcome changes within that resolution"
                .into(),
            (n, true) => format!(
                "{n} runs per cell: sensor-noise seeds {noise} to {} (jitter: {}); each cell's fractions with their Wilson 95 % intervals in cells.csv; a grid point counts as bouncing in the bands when more than half its seeds do",
                noise.wrapping_add(n as u64 - 1),
                spec.jitter.describe()
            ),
            (n, false) => format!(
                "{n} runs per cell, differing by their jitter ({}) only (this loop has no noise); a cell whose runs disagree sits on a boundary within that resolution (cells.csv `boundary`); a grid point counts as bouncing in the bands when more than half its runs do",
                spec.jitter.describe()
            ),
        };
        Self { seeds: spec.seeds, jitter: spec.jitter.describe(), note, draws: (0..spec.seeds).map(|k| spec.draw(k)).collect() }
    }
}

/// `summary.json`'s `ensemble`: the cells over their seeds.
#[derive(Debug, Clone, Serialize)]
pub struct EnsembleResults {
    /// Per `mu` (all its cells pooled): the fractions that lift off, stop safe, keep contact.
    pub per_mu: Vec<MuFractions>,
    /// Cells whose lift-off interval holds one half.
    pub undecided: Vec<CellRow>,
    /// Cells whose seeds disagree.
    pub boundary_cells: usize,
    /// Cells.
    pub cells: usize,
}

impl EnsembleResults {
    /// The ensemble results of `cells`.
    pub fn of(cells: &[CellRow]) -> Self {
        Self {
            per_mu: cells::per_mu(cells),
            undecided: cells.iter().filter(|c| c.undecided).cloned().collect(),
            boundary_cells: cells.iter().filter(|c| c.boundary).count(),
            cells: cells.len(),
        }
    }
}

/// How the initial conditions are treated (in `summary.json`).
pub const PROJECTION_NOTE: &str = "the paper's initial conditions, given in rounded degrees, put the tip a fraction of a millimetre \
     inside the belt; each is projected onto the belt at the same z_t and elbow branch before simulating (height_above_belt is \
     the tip's height as given)";

/// Where `theta1_dot_max` and `z_n_max` come from (in `summary.json`).
pub const MAXIMA_NOTE: &str = "maxima over the continuous trajectory of the record window: both ends of every integrator step, \
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

/// `summary.json` of the sweep `m` from its `results` (with `missing` runs not
/// in its folder), this invocation's `timing` (`None` for a merge), the runs
/// `resumed` from the journal, whether it was `interrupted`, and the `files`
/// written; [`SweepSummary::with_cells`] adds a sweep's cells over several seeds.
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
        samples: Samples::of(&m.spec),
        results,
        ensemble: None,
        timing,
        resumed_runs: resumed,
        files,
    }
}
