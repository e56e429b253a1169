//! `--set KEY=VALUE`: one scenario key changed on the command line.
//!
//! `KEY` is the dotted key path of a scenario file (`plant.m`,
//! `controller.pid.kp`, `controller.model.l`); `VALUE` is a TOML value (`0.13`,
//! `[150, 0]`, `"pid"`, `nan`; a bare word such as `pid` is read as a string).
//! Each override replaces or adds the value at its path in the scenario's TOML
//! document before the document is read, so a bad value is reported exactly as
//! in a file, naming the key ([`crate::scenario::Scenario::from_toml_with`]).
//! A key may be given once; a key a command sets with a flag of its own cannot
//! be given with `--set` too ([`check_keys`]).
//!
//! Commands without a scenario file (`simulate`, `admissible`, `modes`,
//! `poincare`, open-loop `sweep`) take only the arm's keys of `[plant]` (paper
//! Table I) and get their [`Params`] from [`arm_params`].

use std::str::FromStr;

use shared::Params;

use super::scenario::{ARM_KEYS, DEFAULT_TOML, Scenario, ScenarioError};

/// One `--set KEY=VALUE`.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The dotted key path, e.g. `plant.m`.
    pub key: String,
    /// The value, parsed as TOML.
    pub value: toml::Value,
    /// `VALUE` as written (for messages).
    pub text: String,
}

impl std::fmt::Display for Override {
    /// `KEY=VALUE` as written.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.key, self.text)
    }
}

/// Why an override was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OverrideError {
    /// Not `KEY=VALUE`, an empty key part, or a value that is not TOML.
    #[error("--set {given}: {why}")]
    Malformed {
        /// The argument as given.
        given: String,
        /// What is wrong.
        why: String,
    },
    /// The same key given twice.
    #[error("--set {key}: the key is given twice")]
    Twice {
        /// The key.
        key: String,
    },
    /// A key this command does not take.
    #[error("--set {given}: {why}")]
    NotHere {
        /// `KEY=VALUE` as given.
        given: String,
        /// Why, and what the command takes.
        why: String,
    },
    /// A key the command sets with a flag; the flag is the one way to set it.
    #[error("--set {given}: `{key}` is set by {flag} in this command; use {flag}")]
    Flag {
        /// `KEY=VALUE` as given.
        given: String,
        /// The key.
        key: String,
        /// The flag.
        flag: String,
    },
    /// The path crosses a value that is not a table (`plant.m.x`) or an array of tables (`faults`).
    #[error("--set {given}: `{prefix}` is not a table of keys")]
    NotATable {
        /// `KEY=VALUE` as given.
        given: String,
        /// The part of the key that is not a table.
        prefix: String,
    },
}

/// Whether `word` is a bare word read as a string (`pid`, `x0d`), not a TOML
/// keyword (`true`, `false`, `nan`, `inf`).
fn bare_word(word: &str) -> bool {
    let mut chars = word.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        && !matches!(word, "true" | "false" | "nan" | "inf")
}

impl FromStr for Override {
    type Err = OverrideError;

    /// Parses `KEY=VALUE`.
    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let malformed = |why: &str| OverrideError::Malformed { given: arg.into(), why: why.into() };
        let (key, text) = arg.split_once('=').ok_or_else(|| malformed("expected KEY=VALUE, e.g. plant.m=0.13"))?;
        let key = key.trim();
        let text = text.trim();
        if key.is_empty() || key.split('.').any(|part| part.is_empty() || part.contains(char::is_whitespace)) {
            return Err(malformed("the key must be a dotted scenario key, e.g. plant.m"));
        }
        if text.is_empty() {
            return Err(malformed("no value after `=`"));
        }
        let value = if bare_word(text) {
            toml::Value::String(text.into())
        } else {
            let doc: toml::Table = toml::from_str(&format!("v = {text}"))
                .map_err(|_| malformed("the value is not a TOML value (a number, [a, b], \"text\", true or false)"))?;
            doc.get("v").cloned().ok_or_else(|| malformed("no value"))?
        };
        Ok(Self { key: key.into(), value, text: text.into() })
    }
}

/// Every key given at most once.
///
/// # Errors
/// [`OverrideError::Twice`].
pub fn check_unique(overrides: &[Override]) -> Result<(), OverrideError> {
    for (i, o) in overrides.iter().enumerate() {
        if overrides[..i].iter().any(|p| p.key == o.key) {
            return Err(OverrideError::Twice { key: o.key.clone() });
        }
    }
    Ok(())
}

/// Refuses overrides of keys a flag of the command sets: `flags` pairs a key with
/// its flag (`("plant.mu", "--mu")`). This is the precedence rule: a key is set in
/// one place on the command line, so a `--set` never silently loses to a flag nor
/// beats it.
///
/// # Errors
/// [`OverrideError::Flag`] for the first such override.
pub fn check_keys(overrides: &[Override], flags: &[(&str, &str)]) -> Result<(), OverrideError> {
    for o in overrides {
        if let Some((key, flag)) = flags.iter().find(|(k, _)| *k == o.key) {
            return Err(OverrideError::Flag { given: o.to_string(), key: (*key).into(), flag: (*flag).into() });
        }
    }
    Ok(())
}

/// Refuses overrides of keys outside `allowed` (full dotted keys); `command`
/// names the command in the message.
///
/// # Errors
/// [`OverrideError::NotHere`] for the first such override.
pub fn check_allowed(overrides: &[Override], allowed: &[String], command: &str) -> Result<(), OverrideError> {
    for o in overrides {
        if !allowed.contains(&o.key) {
            let why = format!("`{}` is not a key `{command}` takes; it takes {}", o.key, allowed.join(", "));
            return Err(OverrideError::NotHere { given: o.to_string(), why });
        }
    }
    Ok(())
}

/// Applies `overrides` in order to a scenario's TOML document, creating the
/// tables on the way (`controller.model` when absent). Keys are checked when the
/// document is read, not here.
///
/// # Errors
/// [`OverrideError::Twice`], or [`OverrideError::NotATable`] when the path crosses
/// a value or an array (`faults` cannot be set this way).
pub fn apply(doc: &mut toml::Table, overrides: &[Override]) -> Result<(), OverrideError> {
    check_unique(overrides)?;
    for o in overrides {
        let parts: Vec<&str> = o.key.split('.').collect();
        let (last, path) = parts.split_last().unwrap_or((&"", &[]));
        let mut table = &mut *doc;
        for (i, part) in path.iter().enumerate() {
            let entry = table.entry((*part).to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
            table = match entry {
                toml::Value::Table(t) => t,
                _ => return Err(OverrideError::NotATable { given: o.to_string(), prefix: parts[..=i].join(".") }),
            };
        }
        if matches!(table.get(*last), Some(toml::Value::Table(_) | toml::Value::Array(_))) && !o.value.is_array() && !o.value.is_table() {
            return Err(OverrideError::NotATable { given: o.to_string(), prefix: o.key.clone() });
        }
        table.insert((*last).to_string(), o.value.clone());
    }
    Ok(())
}

/// Reads the old key `controller.hybrid_ki` as `controller.hybrid.ki` (scenario
/// files written before the gains were opened). Returns whether it did.
///
/// # Errors
/// [`ScenarioError::Parse`] when both are given.
pub fn migrate_legacy(doc: &mut toml::Table) -> Result<bool, ScenarioError> {
    let Some(toml::Value::Table(controller)) = doc.get_mut("controller") else {
        return Ok(false);
    };
    let Some(ki) = controller.remove("hybrid_ki") else {
        return Ok(false);
    };
    let hybrid = controller.entry("hybrid").or_insert_with(|| toml::Value::Table(toml::Table::new()));
    match hybrid {
        toml::Value::Table(h) if !h.contains_key("ki") => {
            h.insert("ki".into(), ki);
            Ok(true)
        }
        _ => Err(ScenarioError::Parse(
            "scenario keys `controller.hybrid_ki` and `controller.hybrid.ki` are the same gain K'_I: give one (controller.hybrid.ki)".into(),
        )),
    }
}

/// The override behind an error at key path `path` (serde's, e.g. `plant` for an
/// unknown key of `[plant]`, `controller.pid.kp` for a bad value), if any.
pub fn culprit<'a>(overrides: &'a [Override], path: &str) -> Option<&'a Override> {
    overrides
        .iter()
        .rev()
        .find(|o| o.key == path)
        .or_else(|| overrides.iter().rev().find(|o| o.key.starts_with(path) || path.starts_with(o.key.as_str())))
}

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
    fn parses_toml_values_and_bare_words() {
        assert_eq!(set("plant.m=0.13").value, toml::Value::Float(0.13));
        assert_eq!(set("controller.kind=pid").value, toml::Value::String("pid".into()));
        assert_eq!(set("controller.kind=\"pid\"").value, toml::Value::String("pid".into()));
        assert!(set("plant.m=nan").value.as_float().unwrap().is_nan());
        assert!(set("controller.pid.kp=[150,0]").value.is_array());
        for bad in ["plant.m", "=1", "plant..m=1", "plant.m=", "plant.m=[1"] {
            assert!(bad.parse::<Override>().is_err(), "{bad}");
        }
    }

    #[test]
    fn overrides_reach_the_scenario_and_errors_name_the_key() {
        let s = Scenario::from_toml_with(DEFAULT_TOML, &[set("plant.m=0.24"), set("controller.pid.kp=[150,1]")]).unwrap();
        assert_eq!((s.plant.m, s.controller.pid.kp), (0.24, [150.0, 1.0]));
        let err = |args: &[&str]| {
            let o: Vec<Override> = args.iter().map(|a| set(a)).collect();
            Scenario::from_toml_with(DEFAULT_TOML, &o).unwrap_err().to_string()
        };
        let e = err(&["plant.m=-1"]);
        assert!(e.contains("`plant.m` = -1") && e.contains("> 0"), "{e}");
        let e = err(&["plant.m=nan"]);
        assert!(e.contains("`plant.m` = NaN"), "{e}");
        let e = err(&["plant.mass=1"]);
        assert!(e.contains("mass") && e.contains("plant.mass=1"), "{e}");
        let e = err(&["controller.pid.kp=[1]"]);
        assert!(e.contains("controller.pid.kp"), "{e}");
        let e = err(&["controller.hybrid.kd=-3"]);
        assert!(e.contains("controller.hybrid.kd") && e.contains("-3"), "{e}");
        let e = err(&["plant.m=1", "plant.m=2"]);
        assert!(e.contains("twice"), "{e}");
        let e = err(&["plant.m.x=1"]);
        assert!(e.contains("`plant.m` is not a table"), "{e}");
        let e = err(&["controller.model.l=0.1"]);
        assert!(e.contains("controller.model.h"), "{e}");
    }

    #[test]
    fn the_legacy_hybrid_ki_key_is_read_as_hybrid_ki() {
        let old = DEFAULT_TOML.replace("[controller]\n", "[controller]\nhybrid_ki = 321.0\n");
        assert_eq!(Scenario::from_toml(&old).unwrap().controller.hybrid.ki, Some(321.0));
        let both = old.replace("kd = 900.0 ", "ki = 1.0\nkd = 900.0 ");
        assert!(Scenario::from_toml(&both).is_err());
    }

    #[test]
    fn flags_own_their_keys() {
        let e = check_keys(&[set("plant.mu=0.3")], &[("plant.mu", "--mu")]).unwrap_err().to_string();
        assert!(e.contains("--mu") && e.contains("plant.mu"), "{e}");
        let e = arm_params(&[set("controller.pid.kp=[1,0]")], &arm_keys(&[]), "simulate", 0.6, -0.4).unwrap_err().to_string();
        assert!(e.contains("controller.pid.kp") && e.contains("simulate"), "{e}");
        let p = arm_params(&[set("plant.m=0.24")], &arm_keys(&[]), "simulate", 0.5, -0.3).unwrap();
        assert_eq!(p, Params { m: 0.24, mu: 0.5, v_belt: -0.3, ..Params::paper() });
    }
}
