//! Errors of the command-line tool and the exit codes they map to.

use std::path::PathBuf;

/// An error that ends a `sil-host` command.
///
/// Exit codes: 2 for bad input (unknown flags, out-of-range parameters,
/// unreachable initial conditions), 1 for failures while running or writing.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The user asked for something invalid; nothing was written.
    #[error("invalid input: {0}")]
    BadInput(String),
    /// A parameter failed validation.
    #[error("invalid parameter: {0}")]
    Param(#[from] shared::ParamError),
    /// The simulation failed.
    #[error("simulation failed: {0}")]
    Sim(#[from] plant::SimError),
    /// Writing an output file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A scenario file is invalid.
    #[error("invalid scenario: {0}")]
    Scenario(#[from] rig::scenario::ScenarioError),
    /// The closed-loop run failed part way.
    #[error("run failed: {0}")]
    Run(#[from] rig::record::RunError),
    /// The board refused a bring-up request, or a bring-up check failed.
    #[error("{0}")]
    Board(String),
    /// Part of a sweep or report failed (everything was written, the failures included).
    #[error("{0}")]
    PartFailed(String),
    /// `--strict`: a result violates the model (energy-creating impact, friction-cone
    /// violation, integrator failure); everything was written, the violations listed.
    #[error("results violate the model (--strict): {0}")]
    Invalid(String),
    /// The command was stopped (Ctrl-C, SIGTERM) part way; what it computed is kept.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// Another process writes into the output folder ([`crate::folder_lock`]);
    /// nothing was written.
    #[error("{} is in use by {owner}: wait for it to finish, or write to another --out", path.display())]
    FolderInUse {
        /// The folder.
        path: PathBuf,
        /// The holder, as its owner file names it (pid and command line).
        owner: String,
    },
    /// Drawing a figure failed.
    #[error("cannot draw {path}: {message}")]
    Plot {
        /// The figure file.
        path: PathBuf,
        /// What plotters reported.
        message: String,
    },
}

/// Maps an I/O error on `path` into a [`CliError::Io`].
pub fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> CliError + '_ {
    move |source| CliError::Io { path: path.to_path_buf(), source }
}

impl CliError {
    /// Process exit code: 2 for bad input, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Self::BadInput(_) | Self::Param(_) | Self::Scenario(_) | Self::FolderInUse { .. } => 2,
            Self::Sim(e) if e.is_bad_input() => 2,
            Self::Run(
                rig::record::RunError::RigInUse { .. }
                | rig::record::RunError::Handshake(_)
                | rig::record::RunError::IncompatibleService(_),
            ) => 2,
            _ => 1,
        }
    }
}

impl From<analyses::AnalysisError> for CliError {
    /// The same message and exit code as the analysis error.
    fn from(e: analyses::AnalysisError) -> Self {
        use analyses::AnalysisError as A;
        match e {
            A::BadInput(m) => Self::BadInput(m),
            A::Param(e) => Self::Param(e),
            A::Sim(e) => Self::Sim(e),
            A::Scenario(e) => Self::Scenario(e),
            A::Run(e) => Self::Run(e),
            A::Interrupted(m) => Self::Interrupted(m),
        }
    }
}
