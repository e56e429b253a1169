//! One module per `sil-host` command.

pub mod admissible;
pub mod bench;
pub mod closed_loop;
pub mod firmware;
pub mod modes;
pub mod pil;
pub mod poincare;
pub mod report;
pub mod run;
pub mod simulate;
pub mod sweep;
pub mod zmax;

/// Parses `"MIN,MAX"` into a range, naming the flag in the error.
pub fn parse_range(flag: &str, s: &str) -> Result<(f64, f64), crate::error::CliError> {
    let bad = || crate::error::CliError::BadInput(format!("--{flag} expects MIN,MAX with MIN < MAX (finite numbers), got `{s}`"));
    let mut it = s.split(',').map(|x| x.trim().parse::<f64>());
    match (it.next(), it.next(), it.next()) {
        (Some(Ok(a)), Some(Ok(b)), None) if a.is_finite() && b.is_finite() && a < b => Ok((a, b)),
        _ => Err(bad()),
    }
}
