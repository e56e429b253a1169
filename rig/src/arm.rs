//! The arm's parameters (paper Table I) of the commands without a scenario file
//! (`simulate`, `admissible`, `modes`, `poincare`, open-loop `sweep`): the
//! paper's, changed by `--set plant.KEY=VALUE` ([`crate::overrides`]) and checked
//! as in a scenario file.

use shared::Params;

use super::overrides::{Override, check_allowed};
use super::scenario::{ARM_KEYS, DEFAULT_TOML, Scenario, ScenarioError};

/// The dotted keys of the arm's parameters in `[plant]` (`plant.m`, ...), those of
/// [`ARM_KEYS`] named in `names` (all when `names` is empty).
pub fn arm_keys(names: &[&str]) -> Vec<String> {
    ARM_KEYS.iter().filter(|k| names.is_empty() || names.contains(k)).map(|k| format!("plant.{k}")).collect()
}

/// The arm's parameters for a command without a scenario file: paper Table I
/// ([`Params::paper`]) with the `--set plant.KEY=VALUE` overrides of the arm's
/// keys in `allowed` (full dotted keys, from [`arm_keys`]), and the command's
/// `mu` and `v_belt`. The arm's keys are checked as in a scenario file (errors
/// name the key); `mu` and `v_belt` are the caller's to check
/// ([`Params::validate`]).
///
/// # Errors
/// [`ScenarioError`] naming the key: not allowed here ([`OverrideError::NotHere`]),
/// given twice, a bad value or out of range.
pub fn arm_params(overrides: &[Override], allowed: &[String], command: &str, mu: f64, v_belt: f64) -> Result<Params<f64>, ScenarioError> {
    check_allowed(overrides, allowed, command)?;
    let s = Scenario::from_toml_with(DEFAULT_TOML, overrides)?;
    Ok(Params { mu, v_belt, ..s.plant.params() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(arg: &str) -> Override {
        arg.parse().unwrap()
    }

    #[test]
    fn only_the_allowed_arm_keys_reach_the_params() {
        let e = arm_params(&[set("controller.pid.kp=[1,0]")], &arm_keys(&[]), "simulate", 0.6, -0.4).unwrap_err().to_string();
        assert!(e.contains("controller.pid.kp") && e.contains("simulate"), "{e}");
        let e = arm_params(&[set("plant.m=0.2")], &arm_keys(&["l", "h"]), "admissible", 0.6, -0.4).unwrap_err().to_string();
        assert!(e.contains("plant.m") && e.contains("plant.l, plant.h"), "{e}");
        let e = arm_params(&[set("plant.g=-1")], &arm_keys(&[]), "modes", 0.6, -0.4).unwrap_err().to_string();
        assert!(e.contains("plant.g") && e.contains("-1"), "{e}");
        let p = arm_params(&[set("plant.m=0.24")], &arm_keys(&[]), "simulate", 0.5, -0.3).unwrap();
        assert_eq!(p, Params { m: 0.24, mu: 0.5, v_belt: -0.3, ..Params::paper() });
    }
}
