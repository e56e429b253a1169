//! What one step of the report produced: the experiment's typed result.

use analyses::{admissible::AdmissibleReport, modes::ModeMap};
use rig::summary::RunSummary;

use crate::bench::figure::Figure as BenchFigure;
use crate::commands::{
    self, poincare::summary::Summary as PoincareSummary, sensitivity::Summary as SensitivitySummary,
    simulate::summary::Summary as SimulateSummary, sweep::outputs::SweepSummary, zmax::summary::ZmaxSummary,
};

/// The typed result of one experiment.
#[derive(Debug)]
pub enum Outcome {
    /// `modes`.
    Modes(ModeMap),
    /// `admissible`.
    Admissible(AdmissibleReport),
    /// `simulate`.
    Simulate(Box<SimulateSummary>),
    /// `sweep`.
    Sweep(Box<SweepSummary>),
    /// `poincare`.
    Poincare(Box<PoincareSummary>),
    /// `zmax`.
    Zmax(Box<ZmaxSummary>),
    /// `run` and `pil`.
    Run(Box<RunSummary>),
    /// `bench`.
    Bench(Vec<BenchFigure>),
    /// `sensitivity`.
    Sensitivity(Box<SensitivitySummary>),
}

impl Outcome {
    /// The command's JSON document (what `--json` prints), for `report.json`.
    pub(super) fn document(&self, files: &[String]) -> serde_json::Value {
        let v = match self {
            Self::Modes(m) => serde_json::to_value(commands::modes::summary::summary(m, files)),
            Self::Admissible(a) => serde_json::to_value(commands::admissible::summary::json_report(a, files)),
            Self::Simulate(s) => serde_json::to_value(s),
            Self::Sweep(s) => serde_json::to_value(s),
            Self::Poincare(p) => serde_json::to_value(p),
            Self::Zmax(z) => serde_json::to_value(z),
            Self::Run(r) => serde_json::to_value(r),
            Self::Bench(b) => serde_json::to_value(b),
            Self::Sensitivity(s) => serde_json::to_value(s),
        };
        v.unwrap_or(serde_json::Value::Null)
    }

    /// The plant's validity counters of the experiment (summed over its runs);
    /// `None` for those that do not simulate (modes, admissible, bench).
    pub fn validity(&self) -> Option<plant::Validity> {
        match self {
            Self::Simulate(s) => Some(s.validity),
            Self::Sweep(s) => Some(s.results.validity),
            Self::Poincare(p) => Some(p.validity),
            Self::Zmax(z) => Some(z.validity),
            Self::Run(r) => Some(r.validity),
            Self::Sensitivity(s) => Some(s.study.validity),
            Self::Modes(_) | Self::Admissible(_) | Self::Bench(_) => None,
        }
    }
}

/// What one step produced.
#[derive(Debug)]
pub struct StepResult {
    /// The step's id (its folder).
    pub id: &'static str,
    /// The command line that reproduces it.
    pub command: String,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// The typed result; `None` when the command failed before producing one.
    pub outcome: Option<Outcome>,
    /// Why it failed, if it did.
    pub error: Option<String>,
    /// Files it wrote, relative to the report folder.
    pub files: Vec<String>,
}

impl StepResult {
    /// The result of step `st` that produced nothing: not run, or abandoned,
    /// with `why`; the files it left in its folder are listed.
    pub fn not_run(root: &std::path::Path, st: &super::sections::Step, why: &str) -> Self {
        Self {
            id: st.id,
            command: super::command_line(root, st),
            wall_s: 0.0,
            outcome: None,
            error: Some(why.to_string()),
            files: super::files_in(root, &root.join(st.id)),
        }
    }
}
