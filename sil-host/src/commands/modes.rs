//! `sil-host modes` (stub).

use crate::{cli::ModesArgs, error::CliError};

/// Runs the command.
pub fn run(_args: &ModesArgs) -> Result<(), CliError> {
    Err(CliError::BadInput("not implemented yet".into()))
}
