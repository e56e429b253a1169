//! `sil-host simulate` (stub).

use crate::{cli::SimulateArgs, error::CliError};

/// Runs the command.
pub fn run(_args: &SimulateArgs) -> Result<(), CliError> {
    Err(CliError::BadInput("not implemented yet".into()))
}
