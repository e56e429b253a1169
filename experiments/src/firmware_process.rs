//! The firmware process of the SIL rig (`sil-host firmware`) for any control
//! law: [`serve`] the paper's laws or a law of one's own over iceoryx2, and
//! [`main`], the whole command a law's crate makes its binary of
//! (`examples/law-template/`, docs/board.md "Your own law"): the same
//! options, scenario handling and exit codes as `sil-host firmware`.

use firmware::ControlLaw;
use rig::{
    firmware_process::{Ending, serve_law},
    ipc::check_rig_name,
    record::RunError,
};

use crate::{error::Error, scenario::load_scenario, settings::FirmwareArgs};

/// Serves rig `args.rig` with the firmware running law `L` until the plant
/// ends the run (exit 0) or dies (3).
///
/// # Errors
/// Bad scenario, rig name, configuration or `[law]` table (exit 2); transport
/// failures (exit 1).
pub fn serve<L: ControlLaw>(args: &FirmwareArgs) -> Result<i32, Error> {
    let scenario = load_scenario(&args.scenario)?;
    check_rig_name(&args.rig).map_err(Error::bad_input)?;
    match serve_law::<L>(&scenario, &args.rig, args.realtime) {
        Ok(Ending::EndOfRun { .. }) => Ok(0),
        Ok(Ending::PeerLost { .. }) => Ok(3),
        Err(e @ (RunError::Law(_) | RunError::Firmware(_))) => Err(Error::bad_input(e.to_string())),
        Err(e) => Err(Error::from(e)),
    }
}

/// The command line of a law's own firmware process: `BIN firmware --rig NAME
/// [--realtime] [--scenario FILE] [--set KEY=VALUE ...]`, exactly as `sil-host
/// firmware` takes it (so `rig::ipc_link::IpcLink` can spawn either);
/// `firmware --help` names the law and its declared parameters. Errors go to
/// stderr as `error: ...`; the exit code is [`serve`]'s.
#[cfg(feature = "clap")]
pub fn main<L: ControlLaw>() -> std::process::ExitCode {
    use clap::{Args, Command, FromArgMatches};
    let spec = &L::SPEC;
    let width = spec.params.iter().map(|p| p.name.len()).max().unwrap_or(0);
    let params: Vec<String> = spec
        .params
        .iter()
        .map(|p| format!("  {:width$}  {}: default {}, from {} to {}", p.name, p.unit, p.default, p.min, p.max))
        .collect();
    let params = format!(
        "The law's parameters, set in the scenario's `[law]` table (`name = \"{}\"`, then `NAME = VALUE`):\n{}",
        spec.name,
        if params.is_empty() { "  (none)".to_string() } else { params.join("\n") }
    );
    let about = format!(
        "The SIL rig's firmware process running the control law `{}` ({}), for `sil-host run --attach RIG`.",
        spec.name, spec.source
    );
    // The binary as the user typed it (a law's crate names its own: `law-firmware`).
    let name = std::env::args_os()
        .next()
        .and_then(|a| std::path::Path::new(&a).file_name().map(|f| f.to_string_lossy().into_owned()))
        .unwrap_or_else(|| format!("{}-firmware", spec.name));
    // clap without its `string` feature names a command by a `&'static str`: once per process.
    let name: &'static str = Box::leak(name.into_boxed_str());
    // The subcommand's about and the parameters set after `augment_args`, which
    // would otherwise put `FirmwareArgs`' own doc comment in their place.
    let cmd = Command::new(name)
        .about(format!("The firmware process of control law `{}` for the SIL rig (`{name} firmware --help`).", spec.name))
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(FirmwareArgs::augment_args(Command::new("firmware")).about(about).long_about(None).after_help(params));
    let args = match cmd.try_get_matches().and_then(|m| match m.subcommand() {
        Some(("firmware", sub)) => FirmwareArgs::from_arg_matches(sub),
        _ => Err(clap::Error::new(clap::error::ErrorKind::MissingSubcommand)),
    }) {
        Ok(a) => a,
        Err(e) => e.exit(),
    };
    match serve::<L>(&args) {
        Ok(code) => std::process::ExitCode::from(code as u8),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::from(e.exit_code() as u8)
        }
    }
}
