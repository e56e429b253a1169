//! `sil-host firmware`: the firmware process of the SIL rig (the firmware step
//! answering sensor frames over iceoryx2); `sil-host run` spawns it.

use crate::{cli::FirmwareArgs, error::CliError};
use experiments::scenario::load_scenario;
use rig::{
    firmware_process::{self, Ending},
    ipc::check_rig_name,
};

/// Runs `sil-host firmware`: exit 0 when the plant ends the run, 3 when the plant died.
///
/// # Errors
/// Bad scenario (exit 2); transport failures (exit 1).
pub fn firmware(args: &FirmwareArgs) -> Result<i32, CliError> {
    let scenario = load_scenario(&args.scenario)?;
    check_rig_name(&args.rig).map_err(CliError::bad_input)?;
    match firmware_process::serve(&scenario, &args.rig, args.realtime).map_err(CliError::from)? {
        Ending::EndOfRun { .. } => Ok(0),
        Ending::PeerLost { .. } => Ok(3),
    }
}
