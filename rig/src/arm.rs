//! The arm's parameters (paper Table I) of the commands without a scenario file
//! (`simulate`, `admissible`, `modes`, `poincare`, open-loop `sweep`): the
//! paper's, changed by `--set plant.KEY=VALUE` ([`crate::overrides`]) and checked
//! as in a scenario file.

use shared::Params;

use super::overrides::{Override, check_allowed};
use super::scenario::{ARM_KEYS, DEFAULT_TOML, Scenario, ScenarioError, validate_arm};

/// The dotted keys of the arm's parameters in `[plant]` (`plant.m`, ...), those of
/// [`ARM_KEYS`] named in `names` (all when `names` is empty).
pub fn arm_keys(names: &[&str]) -> Vec<String> {
    ARM_KEYS.iter().filter(|k| names.is_empty() || names.contains(k)).map(|k| format!("plant.{k}")).collect()
}

/// The arm's parameters for a command without a scenario file: paper Table I
/// ([`Params::paper`]) with the `--set plant.KEY=VALUE` overrides of the arm's
/// keys in `allowed` (full dotted keys, from [`arm_keys`]), and the command's
/// `mu` and `v_belt`. The arm's keys are checked as in a scenario file
/// ([`validate_arm`]: errors name the key); `mu` and `v_belt` are the caller's to
/// check ([`Params::validate`]).
///
/// Only the arm is checked: the default scenario's closed-loop keys, which
/// these commands do not use and `--set` cannot change here, are not (issue 67:
/// its target `controller.target_z_t` = 0.10 m refused every arm with
/// `l <= 0.05` m, out of the reach `2 l`; the firmware's `f32` model refused
/// values only the firmware cannot hold). A closed-loop command reads its
/// scenario whole ([`Scenario::from_toml_with`]) and still refuses a target out
/// of its arm's reach.
///
/// # Errors
/// [`ScenarioError`] naming the key: not allowed here ([`OverrideError::NotHere`]),
/// given twice, a bad value or out of range.
pub fn arm_params(overrides: &[Override], allowed: &[String], command: &str, mu: f64, v_belt: f64) -> Result<Params<f64>, ScenarioError> {
    check_allowed(overrides, allowed, command)?;
    let arm = Scenario::read_with(DEFAULT_TOML, overrides)?.plant.params();
    validate_arm("plant", &arm)?;
    Ok(Params { mu, v_belt, ..arm })
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

    /// Issue 67: an arm too short for the default scenario's closed-loop target
    /// (`controller.target_z_t` = 0.10 m, at or beyond the reach `2 l` when
    /// `l <= 0.05` m) is an arm for the open-loop commands, which never use the
    /// target; the arm itself is still checked (the belt within its reach), and
    /// the whole scenario still refuses the target.
    #[test]
    fn a_short_arm_is_not_refused_for_a_target_it_does_not_use() {
        let short = [set("plant.l=0.04"), set("plant.h=0.07")];
        let p = arm_params(&short, &arm_keys(&[]), "simulate", 0.6, -0.5).unwrap();
        assert_eq!((p.l, p.h, p.mu, p.v_belt), (0.04, 0.07, 0.6, -0.5));
        let e = arm_params(&[set("plant.l=0.04")], &arm_keys(&[]), "simulate", 0.6, -0.5).unwrap_err().to_string();
        assert!(e.contains("plant.h") && e.contains("0.08 m"), "H = 0.4 m out of the short arm's reach: {e}");
        let e = Scenario::from_toml_with(DEFAULT_TOML, &short).unwrap_err().to_string();
        assert!(e.contains("controller.target_z_t") && e.contains("2 l = 0.08 m"), "{e}");
    }
}
