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
    /// An analysis failed ([`analyses::AnalysisError`], kept typed); its message is
    /// the analysis error's, its exit code follows the variant ([`CliError::exit_code`]).
    #[error(transparent)]
    Analysis(#[from] analyses::AnalysisError),
}

/// Maps an I/O error on `path` into a [`CliError::Io`].
pub fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> CliError + '_ {
    move |source| CliError::Io { path: path.to_path_buf(), source }
}

impl CliError {
    /// Process exit code: 2 for bad input, 1 otherwise. An analysis error counts
    /// as the error it holds: bad input, a parameter or a scenario 2, a simulation
    /// or a run as [`CliError::Sim`] and [`CliError::Run`], an interruption 1.
    pub fn exit_code(&self) -> i32 {
        use analyses::AnalysisError as A;
        match self {
            Self::BadInput(_) | Self::Param(_) | Self::Scenario(_) | Self::FolderInUse { .. } => 2,
            Self::Analysis(A::BadInput(_) | A::Param(_) | A::Scenario(_)) => 2,
            Self::Sim(e) | Self::Analysis(A::Sim(e)) if e.is_bad_input() => 2,
            Self::Run(e) | Self::Analysis(A::Run(e)) if run_is_bad_input(e) => 2,
            _ => 1,
        }
    }
}

/// Whether a run failed on its input rather than while running: the rig is
/// another's, or the firmware process or a service does not fit (exit 2).
fn run_is_bad_input(e: &rig::record::RunError) -> bool {
    matches!(
        e,
        rig::record::RunError::RigInUse { .. } | rig::record::RunError::Handshake(_) | rig::record::RunError::IncompatibleService(_)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use analyses::AnalysisError as A;
    use rig::record::RunError;

    #[test]
    fn an_analysis_error_keeps_its_message_and_exit_code() {
        let param = || shared::ParamError::NonFinite { name: "mu", value: f64::NAN };
        let in_use = || RunError::RigInUse { rig: "r".into(), role: "plant", pid: 1 };
        let cases: [(A, CliError); 6] = [
            (A::BadInput("--grid".into()), CliError::BadInput("--grid".into())),
            (A::Param(param()), CliError::Param(param())),
            (A::Sim(plant::SimError::BadStep(-1.0)), CliError::Sim(plant::SimError::BadStep(-1.0))),
            (A::Run(in_use()), CliError::Run(in_use())),
            (A::Run(RunError::Transport("gone".into())), CliError::Run(RunError::Transport("gone".into()))),
            (A::Interrupted("sweep stopped".into()), CliError::Interrupted("sweep stopped".into())),
        ];
        for (analysis, own) in cases {
            let typed = CliError::from(analysis);
            assert!(matches!(typed, CliError::Analysis(_)), "{typed:?}");
            assert_eq!(typed.to_string(), own.to_string());
            assert_eq!(typed.exit_code(), own.exit_code(), "{typed}");
        }
    }
}
