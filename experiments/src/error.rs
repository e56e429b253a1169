//! The error of an experiment and of its outputs, shared by both fronts (the
//! `sil-host` command line calls it `CliError`; the Python package raises it as
//! `painleve.PainleveError`), and the exit codes it maps to.
//!
//! What an experiment computes fails with an [`analyses::AnalysisError`] (bad
//! input, a parameter, a scenario, the simulation, a closed-loop run, an
//! interruption), which [`Error::Analysis`] wraps with its message and exit
//! code; the other variants are the outputs' (files, folders, figures) and the
//! verdicts on a finished run (`--strict`, a part that failed, the bring-up).

use std::path::PathBuf;

use analyses::AnalysisError;

/// An error that ends an experiment (a `sil-host` command, a `painleve` call).
///
/// Exit codes ([`Error::exit_code`]): 2 for bad input (unknown flags,
/// out-of-range parameters, unreachable initial conditions, a folder or rig in
/// use), 1 for failures while running or writing.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// What the experiment computes failed: bad input, a parameter, a scenario,
    /// the simulation, a closed-loop run, an interruption (its message is the
    /// analysis error's).
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    /// The caller asked for something the experiment or its outputs cannot take
    /// (a flag out of range, a file that is not what it names, a serial port
    /// that does not open, a command whose feature is not built): the message
    /// names it. An analysis's own bad input is [`Error::Analysis`] holding
    /// [`AnalysisError::BadInput`], with the same message form.
    #[error("invalid input: {0}")]
    BadInput(String),
    /// Writing or reading a file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A table file cannot be read (a CSV file that is not the table it names): its message.
    #[error(transparent)]
    Table(tables::Error),
    /// The board refused a bring-up request, or a bring-up check failed.
    #[error("{0}")]
    Board(String),
    /// Part of a sweep or report failed (everything was written, the failures included).
    #[error("{0}")]
    PartFailed(String),
    /// `sil-host replay`: the firmware answered a recorded frame differently from
    /// the recording (everything was compared; the first difference named).
    #[error("{0}")]
    Diverged(String),
    /// `--strict`: a result violates the model (energy-creating impact, friction-cone
    /// violation, integrator failure); everything was written, the violations listed.
    #[error("results violate the model (--strict): {0}")]
    Invalid(String),
    /// Another process writes into the output folder; nothing was written.
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

/// A table file that cannot be written or read ([`tables::Error`]): the same
/// message, as the [`Error::Io`] it becomes (or [`Error::Table`]).
impl From<tables::Error> for Error {
    fn from(e: tables::Error) -> Self {
        match e {
            tables::Error::Io { path, source } => Self::Io { path, source },
            tables::Error::Input(e) => e.into(),
            other => Self::Table(other),
        }
    }
}

/// An input file that is not a regular file within its bound
/// ([`tables::input`]: a FIFO, a device, a directory, a file over its bound):
/// bad input (exit 2), its message naming the file, what it is and the bound.
impl From<tables::input::InputError> for Error {
    fn from(e: tables::input::InputError) -> Self {
        Self::BadInput(e.to_string())
    }
}

/// Maps an I/O error on `path` into an [`Error::Io`].
pub fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io { path: path.to_path_buf(), source }
}

impl Error {
    /// Bad input (exit 2; "invalid input: `message`"): [`Error::BadInput`].
    pub fn bad_input(message: impl Into<String>) -> Self {
        Self::BadInput(message.into())
    }

    /// A stop by Ctrl-C or SIGTERM part way (exit 1, what was computed is kept):
    /// [`AnalysisError::Interrupted`].
    pub fn interrupted(message: impl Into<String>) -> Self {
        Self::Analysis(AnalysisError::Interrupted(message.into()))
    }

    /// Process exit code: 2 for bad input, 1 otherwise. An analysis error counts
    /// as the error it holds: bad input, a parameter or a scenario 2, a simulation
    /// on bad input ([`plant::SimError::is_bad_input`]) 2, a run refused before it
    /// started (a rig in use, a firmware that does not fit) 2, the rest 1.
    pub fn exit_code(&self) -> i32 {
        use AnalysisError as A;
        match self {
            Self::FolderInUse { .. } | Self::BadInput(_) => 2,
            Self::Analysis(A::BadInput(_) | A::Param(_) | A::Scenario(_)) => 2,
            Self::Analysis(A::Sim(e)) if e.is_bad_input() => 2,
            Self::Analysis(A::Run(e)) if run_is_bad_input(e) => 2,
            _ => 1,
        }
    }
}

macro_rules! through_analysis {
    ($($t:ty),+) => {$(
        impl From<$t> for Error {
            fn from(e: $t) -> Self {
                Self::Analysis(e.into())
            }
        }
    )+};
}
through_analysis!(shared::ParamError, plant::SimError, rig::scenario::ScenarioError, rig::record::RunError);

/// Whether a run failed on its input rather than while running: the rig is
/// another's, the firmware process or a service does not fit, the scenario
/// asks a board for what it never runs, the scenario's `[law]` table does not
/// fit the firmware's law, the private folder of the locks is refused
/// (another user's, a link, open to others), or the plant refused the firmware
/// process (exit 2).
fn run_is_bad_input(e: &rig::record::RunError) -> bool {
    matches!(
        e,
        rig::record::RunError::RigInUse { .. }
            | rig::record::RunError::Handshake(_)
            | rig::record::RunError::Law(_)
            | rig::record::RunError::IncompatibleService(_)
            | rig::record::RunError::NotOnABoard(_)
            | rig::record::RunError::PrivateFolder(_)
            | rig::record::RunError::RefusedByPlant { .. }
    )
}

/// A figure's error ([`figures::Error`]) as the fronts' ([`Error`]), its message kept:
/// `Io` and `Plot` as theirs, bad input as theirs (exit 2).
impl From<figures::Error> for Error {
    fn from(e: figures::Error) -> Self {
        match e {
            figures::Error::Io { path, source } => Self::Io { path, source },
            figures::Error::Plot { path, message } => Self::Plot { path, message },
            figures::Error::BadInput(message) => Self::bad_input(message),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig::record::RunError;

    /// The exit codes of the analysis errors, and the messages, which are the
    /// analysis errors' own.
    #[test]
    fn an_analysis_error_keeps_its_message_and_its_exit_code() {
        let param = || shared::ParamError::NonFinite { name: "mu", value: f64::NAN };
        let in_use = || RunError::RigInUse { rig: "r".into(), role: "plant", pid: 1 };
        let refused = std::io::Error::new(std::io::ErrorKind::PermissionDenied, "/tmp/painleve-1: owned by uid 2");
        let cases: [(Error, &str, i32); 8] = [
            (AnalysisError::BadInput("--grid".into()).into(), "invalid input: --grid", 2),
            (param().into(), "invalid parameter: ", 2),
            (plant::SimError::BadStep(-1.0).into(), "simulation failed: ", 2),
            (in_use().into(), "run failed: ", 2),
            (RunError::Transport("gone".into()).into(), "run failed: ", 1),
            (RunError::private_folder("the rig's lock folder", &refused).into(), "run failed: the rig's lock folder: /tmp", 2),
            (RunError::private_folder("the rig's lock folder", &std::io::Error::other("disk")).into(), "run failed: ", 1),
            (Error::interrupted("sweep stopped"), "interrupted: sweep stopped", 1),
        ];
        for (e, prefix, code) in cases {
            assert!(matches!(e, Error::Analysis(_)), "{e:?}");
            assert!(e.to_string().starts_with(prefix), "{e}");
            assert_eq!(e.exit_code(), code, "{e}");
        }
        let folder = Error::FolderInUse { path: "out".into(), owner: "pid 1".into() };
        assert_eq!(folder.exit_code(), 2);
        // The experiments' own bad input: its own variant, the same message form and code.
        let bad = Error::bad_input("--grid");
        assert!(matches!(bad, Error::BadInput(_)), "{bad:?}");
        assert_eq!((bad.to_string().as_str(), bad.exit_code()), ("invalid input: --grid", 2));
        assert_eq!(Error::Invalid("x".into()).exit_code(), 1);
    }
}
