//! `sil-host admissible`: the admissible configurations of the tip on the belt
//! (docs/model.md experiment 2, paper Table II), computed by [`analyses::admissible`];
//! this command prints them, writes `admissible.json` and draws `admissible.svg`.

use std::io::Write;

use crate::commands::Done;
use crate::{cli::AdmissibleArgs, error::CliError, output::OutputSet};
use analyses::admissible::AdmissibleReport;
pub use experiments::admissible::{compute, document, summary};

pub mod figures;
mod print;
use figures::*;
use print::*;

/// Computes the admissible configurations and writes `admissible.json` and
/// `admissible.svg`; prints nothing.
///
/// # Errors
/// [`CliError::Analysis`] (exit 2: a parameter error) for a bad `mu`, before anything is written;
/// [`CliError::Io`] / [`CliError::Plot`] when writing fails.
pub fn execute(args: &AdmissibleArgs) -> Result<Done<AdmissibleReport>, CliError> {
    let report = compute(args)?;
    let mut out = OutputSet::new(&args.output.out)?;
    let files: Vec<String> = ["admissible.json", "admissible.svg"].iter().map(|f| out.path(f).display().to_string()).collect();
    out.write_bytes("admissible.json", document(&report, &files)?.as_bytes())?;
    let svg = out.stage_figure("admissible.svg")?;
    draw_figure(&report, &svg)?;
    out.commit()?;
    Ok(Done::ok(report, files.into_iter().map(Into::into).collect()))
}

/// Runs `sil-host admissible` (docs/model.md experiment 2): computes the admissible
/// intervals for `--mu`, prints them (human table, or one JSON document with
/// `--json`), and writes `admissible.json` and `admissible.svg` under `--out`,
/// all or nothing.
///
/// # Errors
/// [`CliError::Analysis`] (exit 2: a parameter error) for a negative or non-finite `--mu`, before
/// anything is written; [`CliError::Io`] / [`CliError::Plot`] when writing fails
/// (nothing is left half-written).
pub fn run(args: &AdmissibleArgs) -> Result<(), CliError> {
    run_with(args, &mut crate::stdout::out())
}

/// [`run`], printing to `stdout` instead of the process's standard output.
///
/// # Errors
/// As [`run`].
pub fn run_with<W: Write>(args: &AdmissibleArgs, stdout: &mut W) -> Result<(), CliError> {
    let done = execute(args)?;
    let files: Vec<String> = done.files.iter().map(|f| f.display().to_string()).collect();
    let text = if args.output.json {
        document(&done.result, &files)? + "\n"
    } else {
        human_summary(&done.result) + &format!("wrote {}\n", files.join(", "))
    };
    stdout.write_all(text.as_bytes()).map_err(|source| CliError::Io { path: "<stdout>".into(), source })?;
    Ok(())
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_mu_is_rejected_with_exit_code_2_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        for mu in [-0.1, f64::NAN, f64::INFINITY] {
            let args = AdmissibleArgs { mu, set: vec![], output: crate::cli::OutputArgs { out: dir.path().join("o"), json: true } };
            let e = run_with(&args, &mut Vec::new()).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains("mu"), "{e}");
            if mu.is_finite() {
                assert!(e.to_string().contains("-0.1"), "{e}");
            }
            assert!(!dir.path().join("o").exists());
        }
    }

    #[test]
    fn run_writes_json_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let args = AdmissibleArgs { mu: 0.6, set: vec![], output: crate::cli::OutputArgs { out: dir.path().to_path_buf(), json: true } };
        let mut printed = Vec::new();
        run_with(&args, &mut printed).unwrap();
        let printed: serde_json::Value = serde_json::from_slice(&printed).unwrap();
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("admissible.json")).unwrap()).unwrap();
        assert_eq!(json["mu"], 0.6);
        assert!(json["z_r_dot_positive"]["elbow_up"].is_array());
        assert_eq!(json["mirror_check"]["ok"], true);
        assert_eq!(printed, json, "--json prints the document written to admissible.json");
        let svg = std::fs::read_to_string(dir.path().join("admissible.svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("zₜ (m)"));
        assert!(dir.path().join("admissible.pdf").is_file(), "the figure as PDF too");
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
            .collect();
        assert!(leftovers.is_empty());
    }
}
