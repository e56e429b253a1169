//! `sil-host firmware`: the firmware process of the SIL rig (the firmware step
//! answering sensor frames over iceoryx2) with the paper's laws; `sil-host run`
//! spawns it. A law of one's own has the same command in its own binary
//! (`experiments::firmware_process::main`).

use crate::{cli::FirmwareArgs, error::CliError};
use firmware::PaperLaws;

/// Runs `sil-host firmware`: exit 0 when the plant ends the run, 3 when the plant died.
///
/// # Errors
/// Bad scenario (exit 2); transport failures (exit 1).
pub fn firmware(args: &FirmwareArgs) -> Result<i32, CliError> {
    experiments::firmware_process::serve::<PaperLaws>(args)
}
