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

/// What a command computed and wrote: its typed result, the files it wrote, and
/// why it stopped early when it did (everything up to then is written). Each
/// command's `execute` returns one, its `run` prints it; `sil-host report` calls
/// the `execute`s directly.
#[derive(Debug)]
pub struct Done<T> {
    /// The command's result (its JSON document's type, or the analysis result).
    pub result: T,
    /// The files written, in the order the command lists them.
    pub files: Vec<std::path::PathBuf>,
    /// Why the command stopped early or part of it failed; `None` when it finished.
    pub failure: Option<crate::error::CliError>,
}

impl<T> Done<T> {
    /// A finished command.
    pub fn ok(result: T, files: Vec<std::path::PathBuf>) -> Self {
        Self { result, files, failure: None }
    }

    /// With `strict`, a command that finished but whose results have violations
    /// (`validity`, summed over its runs) fails with [`crate::error::CliError::Invalid`]
    /// (exit 1); an earlier failure is kept.
    pub fn strict(mut self, strict: bool, validity: &plant::Validity) -> Self {
        if strict && self.failure.is_none() && !validity.is_valid() {
            self.failure = Some(crate::error::CliError::Invalid(validity.describe_violations()));
        }
        self
    }

    /// The command's outcome: `Err` with the failure, if any.
    ///
    /// # Errors
    /// The failure.
    pub fn into_result(self) -> Result<(), crate::error::CliError> {
        self.failure.map_or(Ok(()), Err)
    }
}

/// The keys of `[plant]` each open-loop command sets with a flag of its own:
/// `--set` of one of them is refused (use the flag).
pub const PLANT_FLAGS: [(&str, &str); 9] = [
    ("plant.mu", "--mu"),
    ("plant.v_belt", "--v-belt"),
    ("plant.x0", "--x0 or --x0-deg"),
    ("plant.impact_law", "--impact-law"),
    ("plant.e_n", "--e-n"),
    ("plant.rtol", "--rtol"),
    ("plant.atol", "--atol"),
    ("plant.iwc", "--iwc"),
    ("plant.singular", "--singular"),
];

/// The parameters of a command without a scenario file (`simulate`,
/// `admissible`, `modes`, `poincare`): paper Table I with the `--set` overrides
/// of the arm's keys named in `arm` (all seven when empty), and the command's
/// `mu` and `v_belt`, validated. Precedence: a key a flag of the command sets
/// ([`PLANT_FLAGS`]) cannot be given with `--set`, whether or not the flag is
/// given (its default is a value too).
///
/// # Errors
/// [`crate::error::CliError::Scenario`] naming the key (exit 2), or
/// [`crate::error::CliError::Param`] for a bad `mu` or `v_belt`.
pub fn arm_params(
    set: &[rig::overrides::Override],
    command: &str,
    arm: &[&str],
    mu: f64,
    v_belt: f64,
) -> Result<shared::Params<f64>, crate::error::CliError> {
    use rig::{overrides, scenario::ScenarioError};
    overrides::check_keys(set, &PLANT_FLAGS).map_err(ScenarioError::from)?;
    let params = rig::arm::arm_params(set, &rig::arm::arm_keys(arm), command, mu, v_belt)?;
    params.validate()?;
    Ok(params)
}

/// Prints `value` as the command's one JSON document (`--json`).
///
/// # Errors
/// [`crate::error::CliError::Io`] when it cannot be serialised.
pub fn print_json<T: serde::Serialize + ?Sized>(value: &T) -> Result<(), crate::error::CliError> {
    let json = serde_json::to_string_pretty(value).map_err(|e| crate::error::CliError::Io { path: "<stdout>".into(), source: e.into() })?;
    println!("{json}");
    Ok(())
}

/// Parses `"MIN,MAX"` into a range, naming the flag in the error.
pub fn parse_range(flag: &str, s: &str) -> Result<(f64, f64), crate::error::CliError> {
    let bad = || crate::error::CliError::BadInput(format!("--{flag} expects MIN,MAX with MIN < MAX (finite numbers), got `{s}`"));
    let mut it = s.split(',').map(|x| x.trim().parse::<f64>());
    match (it.next(), it.next(), it.next()) {
        (Some(Ok(a)), Some(Ok(b)), None) if a.is_finite() && b.is_finite() && a < b => Ok((a, b)),
        _ => Err(bad()),
    }
}

#[cfg(test)]
mod strict_tests {
    use super::Done;

    /// `--strict` turns a violation into exit 1, keeps an earlier failure, and
    /// leaves clean results and non-strict runs alone.
    #[test]
    fn strict_fails_only_on_violations() {
        let cone = plant::Validity { cone_violations: 2, ..plant::Validity::default() };
        let rules = plant::Validity { zeno_stops: 5, newton_fallbacks: 1, ..plant::Validity::default() };
        let e = Done::ok((), vec![]).strict(true, &cone).into_result().unwrap_err();
        assert_eq!(e.exit_code(), 1);
        assert!(e.to_string().contains("2 friction-cone violations"), "{e}");
        assert!(Done::ok((), vec![]).strict(false, &cone).into_result().is_ok());
        assert!(Done::ok((), vec![]).strict(true, &rules).into_result().is_ok(), "fallbacks and Zeno stops are not violations");
        let earlier = Done { result: (), files: vec![], failure: Some(crate::error::CliError::BadInput("x".into())) };
        assert_eq!(earlier.strict(true, &cone).into_result().unwrap_err().exit_code(), 2);
    }
}
