//! What a command asks of an optional part this build lacks (sil-host/Cargo.toml
//! `[features]`: `board`, `live`, `formats`, `pdf`; `--version` lists those
//! built): bad input (exit 2) naming the feature to build with, never a missing
//! subcommand or a silently different output.

use crate::error::CliError;

/// The error of `what` (a command or an option, as the user wrote it) in a build
/// without `feature`: [`CliError::BadInput`] (exit 2) saying how to build it.
pub fn missing(feature: &str, what: &str) -> CliError {
    CliError::BadInput(format!(
        "{what} needs the `{feature}` feature, which this sil-host was built without: \
         cargo build --release -p sil-host --features {feature} (or --features full for everything)"
    ))
}

/// `Ok` when `on` (a feature's `cfg!`), else [`missing`].
///
/// # Errors
/// [`missing`]`(feature, what)` when the feature is off.
pub fn require(on: bool, feature: &str, what: &str) -> Result<(), CliError> {
    if on { Ok(()) } else { Err(missing(feature, what)) }
}

/// `Ok` for a table format this build writes: CSV always, Arrow and MCAP with
/// the feature `formats`.
///
/// # Errors
/// [`missing`] for `--format arrow|mcap` in a build without `formats`.
pub fn require_format(format: tables::TableFormat) -> Result<(), CliError> {
    match format {
        tables::TableFormat::Csv => Ok(()),
        _ if cfg!(feature = "formats") => Ok(()),
        other => Err(format_missing(other)),
    }
}

/// The error of `--format` `format` (Arrow or MCAP) in a build without `formats`.
pub fn format_missing(format: tables::TableFormat) -> CliError {
    missing("formats", &format!("--format {}", format.extension()))
}

/// Says once per process, on standard error, that figures are written as SVG
/// alone (a build without `pdf`).
pub fn note_svg_only() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        eprintln!("note: figures are written as SVG only: this sil-host was built without the `pdf` feature (--features pdf)");
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The refusal is bad input (exit 2) and says how to build the part.
    #[test]
    fn a_missing_feature_is_bad_input_naming_the_build() {
        let e = missing("board", "--link twin");
        assert_eq!(e.exit_code(), 2);
        let text = e.to_string();
        assert!(text.contains("--link twin needs the `board` feature") && text.contains("--features board"), "{text}");
        assert!(require(true, "board", "x").is_ok());
        assert_eq!(require_format(tables::TableFormat::Csv).map_err(|e| e.to_string()), Ok(()));
        let arrow = require_format(tables::TableFormat::Arrow);
        assert_eq!(arrow.is_ok(), cfg!(feature = "formats"), "{arrow:?}");
    }
}
