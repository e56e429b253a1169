//! `sil-host admissible` (stub).

use crate::{cli::AdmissibleArgs, error::CliError};

/// Runs the command.
pub fn run(_args: &AdmissibleArgs) -> Result<(), CliError> {
    Err(CliError::BadInput("not implemented yet".into()))
}
