//! `sil-host modes`: the map of contact modes over `(theta1, theta1_dot)` with the
//! tip on the belt (docs/model.md experiment 1, paper Fig. 2), computed by
//! [`analyses::modes`]; this command writes `modes.csv`, draws `modes.svg` and prints
//! the counts.

use std::io::Write;

use crate::commands::Done;
use crate::{cli::ModesArgs, error::CliError, output::OutputSet};
use analyses::modes::*;

pub mod figures;
mod print;
pub use experiments::modes::{branch_label, compute, summary};
use figures::*;
use print::*;
use summary::*;

/// Computes the mode map and writes `modes.csv` and `modes.svg`; prints nothing.
///
/// # Errors
/// [`CliError::Analysis`] (exit 2: the analysis's bad input or a parameter error)
/// for bad ranges, `mu`, `v_belt` or a bad grid size, before
/// anything is written; [`CliError::Io`] / [`CliError::Plot`] when writing fails.
pub fn execute(args: &ModesArgs) -> Result<Done<ModeMap>, CliError> {
    let map = compute(args)?;
    let mut out = OutputSet::new(&args.output.out)?;
    let files = ["modes.csv", "modes.svg"].iter().map(|f| out.path(f)).collect();
    let (tmp, w) = out.create("modes.csv")?;
    write_csv(&map, w, &tmp)?;
    let svg = out.stage_figure("modes.svg")?;
    draw_figure(&map, &svg)?;
    out.commit()?;
    Ok(Done::ok(map, files))
}

/// Runs `sil-host modes` (docs/model.md experiment 1): computes the map, prints the
/// counts per mode (human table, or one JSON document with `--json`) and writes
/// `modes.csv` and `modes.svg` under `--out`, all or nothing.
///
/// # Errors
/// [`CliError::Analysis`] (exit 2: the analysis's bad input or a parameter error)
/// for bad ranges, `mu`, `v_belt` or a bad grid size, before
/// anything is written; [`CliError::Io`] / [`CliError::Plot`] when writing fails
/// (nothing is left half-written).
pub fn run(args: &ModesArgs) -> Result<(), CliError> {
    run_with(args, &mut crate::stdout::out())
}

/// [`run`], printing to `stdout` instead of the process's standard output.
///
/// # Errors
/// As [`run`].
pub fn run_with<W: Write>(args: &ModesArgs, stdout: &mut W) -> Result<(), CliError> {
    let done = execute(args)?;
    let (map, files) = (&done.result, done.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>());
    let text = if args.output.json {
        serde_json::to_string_pretty(&summary(map, &files))
            .map_err(|e| CliError::Io { path: "<stdout>".into(), source: std::io::Error::other(e) })?
            + "\n"
    } else {
        human_summary(map) + &format!("wrote {}\n", files.join(", "))
    };
    stdout.write_all(text.as_bytes()).map_err(|source| CliError::Io { path: "<stdout>".into(), source })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const MU: f64 = 0.6;
    const V: f64 = -0.4;

    fn args(out: &Path) -> ModesArgs {
        ModesArgs {
            mu: MU,
            v_belt: V,
            branch: shared::ElbowBranch::Down,
            theta1_deg: "-40,40".parse().unwrap(),
            theta1_dot: "-10,10".parse().unwrap(),
            grid: 60,
            theta2_sign: Theta2Sign::Auto,
            set: vec![],
            output: crate::cli::OutputArgs { out: out.to_path_buf(), json: true },
        }
    }

    #[test]
    fn bad_input_exits_2_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("o");
        let cases: [fn(&mut ModesArgs); 8] = [
            |a| a.mu = -1.0,
            |a| a.mu = f64::NAN,
            |a| a.v_belt = f64::INFINITY,
            |a| a.grid = 1,
            |a| a.grid = GRID_MAX + 1,
            |a| a.theta1_deg = "10,-10".parse().unwrap(),
            |a| a.theta1_dot = "1,2,3".parse().unwrap(),
            |a| a.theta1_dot = "-1e308,1e308".parse().unwrap(),
        ];
        for set in cases {
            let mut a = args(&out);
            set(&mut a);
            let e = run_with(&a, &mut Vec::new()).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            assert!(!out.exists());
        }
    }

    #[test]
    fn run_writes_csv_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let mut printed = Vec::new();
        run_with(&args(dir.path()), &mut printed).unwrap();
        let json: serde_json::Value = serde_json::from_slice(&printed).unwrap();
        assert_eq!(json["points"], 3600);
        let total: u64 = json["counts"].as_array().unwrap().iter().map(|c| c["count"].as_u64().unwrap()).sum();
        assert_eq!(total, 3600);
        let csv = std::fs::read_to_string(dir.path().join("modes.csv")).unwrap();
        let mut lines = csv.lines();
        assert_eq!(lines.next().unwrap(), "theta1_rad,theta1_deg,theta1_dot,theta2_rad,b,p,z_r_dot,mode,theta2_dot,branch");
        assert_eq!(lines.count(), 60 * 60);
        let svg = std::fs::read_to_string(dir.path().join("modes.svg")).unwrap();
        assert!(svg.contains("θ₁ (deg)") && svg.contains("sliding"));
        assert!(dir.path().join("modes.pdf").is_file(), "the figure as PDF too");
    }
}
