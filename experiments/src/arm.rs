//! The arm's parameters of the open-loop experiments (paper Table I with the
//! `--set` overrides and each experiment's own `mu` and `v_belt`), and the
//! parsing of a `MIN,MAX` range.

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
/// [`crate::error::Error`] (exit 2): a scenario error naming the key, or a parameter
/// error for a bad `mu` or `v_belt`.
pub fn arm_params(
    set: &[rig::overrides::Override],
    command: &str,
    arm: &[&str],
    mu: f64,
    v_belt: f64,
) -> Result<shared::Params<f64>, crate::error::Error> {
    use rig::{overrides, scenario::ScenarioError};
    overrides::check_keys(set, &PLANT_FLAGS).map_err(ScenarioError::from)?;
    let params = rig::arm::arm_params(set, &rig::arm::arm_keys(arm), command, mu, v_belt)?;
    params.validate()?;
    Ok(params)
}

/// The range `MIN,MAX` of a setting (`--theta1-deg`, `--bracket`), naming the
/// flag in the error.
///
/// # Errors
/// [`crate::error::Error`] (bad input, exit 2) unless it is two finite numbers, the first smaller.
pub fn parse_range(flag: &str, s: &crate::settings::NumberList) -> Result<(f64, f64), crate::error::Error> {
    match s.0.as_slice() {
        [a, b] if a.is_finite() && b.is_finite() && a < b => Ok((*a, *b)),
        _ => Err(crate::error::Error::bad_input(format!("--{flag} expects MIN,MAX with MIN < MAX (finite numbers), got `{s}`"))),
    }
}
