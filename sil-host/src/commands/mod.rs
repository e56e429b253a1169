//! One module per `sil-host` command.

pub mod admissible;
pub mod bench;
#[cfg(feature = "board")]
pub mod board;
pub mod closed_loop;
pub mod firmware;
pub mod modes;
pub mod pil;
pub mod poincare;
pub mod replay;
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

/// The end of every command that computes, then prints: `done`'s JSON document
/// (`document` of its result) with `--json`, else `human` with the result and the
/// files written; then the command's exit (`Done::into_result`: a failure after
/// writing, or `--strict`'s verdict).
///
/// # Errors
/// [`crate::error::CliError::Io`] when the document cannot be serialised; the
/// failure `done` carries.
pub fn finish<R, D: serde::Serialize + ?Sized>(
    done: experiments::done::Done<R>,
    json: bool,
    document: impl FnOnce(&R) -> &D,
    human: impl FnOnce(&R, &[std::path::PathBuf]),
) -> Result<(), crate::error::CliError> {
    if json {
        print_json(document(&done.result))?;
    } else {
        human(&done.result, &done.files);
    }
    done.into_result()
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
