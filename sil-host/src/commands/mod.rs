//! One module per `sil-host` command.

pub mod admissible;
pub mod bench;
pub mod board;
pub mod closed_loop;
pub mod firmware;
pub mod modes;
pub mod pil;
pub mod poincare;
pub mod report;
pub mod run;
pub mod sensitivity;
pub mod simulate;
pub mod sweep;
pub mod zmax;

pub use experiments::Done;
pub use experiments::arm::{PLANT_FLAGS, arm_params, parse_range};

/// Prints `note`, if any, on standard error as `warning: <note>` (standard output
/// stays the command's document).
pub fn warn(note: Option<String>) {
    if let Some(note) = note {
        eprintln!("warning: {note}");
    }
}

/// Prints `value` as the command's one JSON document (`--json`).
///
/// # Errors
/// [`crate::error::CliError::Io`] when it cannot be serialised.
pub fn print_json<T: serde::Serialize + ?Sized>(value: &T) -> Result<(), crate::error::CliError> {
    let json = serde_json::to_string_pretty(value).map_err(|e| crate::error::CliError::Io { path: "<stdout>".into(), source: e.into() })?;
    outln!("{json}");
    Ok(())
}
