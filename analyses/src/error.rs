//! The error of the analyses (admissible configurations, mode map, Z_t,sliding,
//! sweeps, bifurcation diagrams); the command line keeps it typed
//! (`CliError::Analysis`), with its message, and decides the exit code from the
//! variant.

/// An error that ends an analysis.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// The caller asked for something invalid (a range, a grid size, a tolerance); the message names it.
    #[error("invalid input: {0}")]
    BadInput(String),
    /// A model parameter failed validation.
    #[error("invalid parameter: {0}")]
    Param(#[from] shared::ParamError),
    /// The simulation failed.
    #[error("simulation failed: {0}")]
    Sim(#[from] plant::SimError),
    /// A scenario is invalid.
    #[error("invalid scenario: {0}")]
    Scenario(#[from] rig::scenario::ScenarioError),
    /// A closed-loop run failed part way.
    #[error("run failed: {0}")]
    Run(#[from] rig::record::RunError),
    /// The analysis was stopped (Ctrl-C, SIGTERM) before it finished.
    #[error("interrupted: {0}")]
    Interrupted(String),
}
