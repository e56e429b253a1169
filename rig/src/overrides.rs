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
//! Table I) and get their parameters from [`crate::arm::arm_params`].

use std::str::FromStr;

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
    /// A key inside another given key (`plant.m` and `plant`).
    #[error("--set {given}: `{inner}` is inside `{outer}`, both given; set one of them")]
    Overlap {
        /// `KEY=VALUE` as given (the later of the two).
        given: String,
        /// The inner key.
        inner: String,
        /// The table key that holds it.
        outer: String,
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

/// Most dot-separated parts a `--set` key may have (scenario keys have at most 3).
pub const MAX_KEY_PARTS: usize = 16;

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
        // A key thousands of parts deep would build as many nested tables, whose
        // recursive drop overflows the stack (found by the `scenario` fuzzing
        // harness, docs/fuzzing.md): refused here.
        let parts = key.split('.').count();
        if parts > MAX_KEY_PARTS {
            return Err(malformed(&format!("the key has {parts} parts; scenario keys have at most 3 (e.g. controller.model.l)")));
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

/// Whether key `inner` is inside table key `outer` (`plant.m` in `plant`).
fn inside(inner: &str, outer: &str) -> bool {
    inner.strip_prefix(outer).is_some_and(|rest| rest.starts_with('.'))
}

/// Every key given at most once, and no key inside another given one (`plant.m`
/// and `plant`: the later would silently replace the earlier, or merge into it,
/// depending on their order; found by fuzzing, docs/fuzzing.md).
///
/// # Errors
/// [`OverrideError::Twice`], [`OverrideError::Overlap`].
pub fn check_unique(overrides: &[Override]) -> Result<(), OverrideError> {
    for (i, o) in overrides.iter().enumerate() {
        if overrides[..i].iter().any(|p| p.key == o.key) {
            return Err(OverrideError::Twice { key: o.key.clone() });
        }
        if let Some(p) = overrides[..i].iter().find(|p| inside(&o.key, &p.key) || inside(&p.key, &o.key)) {
            let (inner, outer) = if inside(&o.key, &p.key) { (&o.key, &p.key) } else { (&p.key, &o.key) };
            return Err(OverrideError::Overlap { given: o.to_string(), inner: inner.clone(), outer: outer.clone() });
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

/// The override behind an error at key path `path` (serde's, e.g. `plant` for an
/// unknown key of `[plant]`, `controller.pid.kp` for a bad value), if any.
pub fn culprit<'a>(overrides: &'a [Override], path: &str) -> Option<&'a Override> {
    overrides
        .iter()
        .rev()
        .find(|o| o.key == path)
        .or_else(|| overrides.iter().rev().find(|o| o.key.starts_with(path) || path.starts_with(o.key.as_str())))
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

    /// Regression (fuzzing, docs/fuzzing.md): a key 60 000 parts deep overflowed the
    /// stack when the scenario was read; it is refused as malformed, naming the count.
    #[test]
    fn very_deep_keys_are_refused_not_a_stack_overflow() {
        let deep = format!("plant{}=1", ".x".repeat(60_000));
        let e = deep.parse::<Override>().unwrap_err().to_string();
        assert!(e.starts_with("--set plant.x.x") && e.contains("60001 parts"), "{}", &e[e.len() - 80..]);
        let at_limit = format!("plant{}=1", ".x".repeat(MAX_KEY_PARTS - 1));
        let o = at_limit.parse::<Override>().unwrap();
        let err = crate::scenario::Scenario::from_toml_with(crate::scenario::DEFAULT_TOML, &[o]).unwrap_err().to_string();
        assert!(err.contains("plant.x") || err.contains("`x`"), "{err}");
    }

    #[test]
    fn apply_sets_values_and_creates_tables() {
        let mut doc: toml::Table = toml::from_str("[plant]\nm = 0.12\n[[faults]]\nkind = \"stall\"\n").unwrap();
        apply(&mut doc, &[set("plant.m=0.2"), set("controller.model.l=0.3")]).unwrap();
        assert_eq!(doc["plant"]["m"].as_float(), Some(0.2));
        assert_eq!(doc["controller"]["model"]["l"].as_float(), Some(0.3));
        assert!(matches!(apply(&mut doc, &[set("plant.m.x=1")]), Err(OverrideError::NotATable { .. })));
        assert!(matches!(apply(&mut doc, &[set("faults=1")]), Err(OverrideError::NotATable { .. })));
        assert!(matches!(apply(&mut doc, &[set("plant.m=1"), set("plant.m=2")]), Err(OverrideError::Twice { .. })));
        // Regression (fuzzing): a key and the table holding it, in either order.
        for pair in [["faults.0.kind=stall", "faults=[]"], ["plant={m=1}", "plant.m=2"]] {
            let e = apply(&mut doc, &[set(pair[0]), set(pair[1])]).unwrap_err();
            assert!(matches!(e, OverrideError::Overlap { .. }), "{pair:?}: {e}");
        }
        let e = apply(&mut doc, &[set("plant.m=1"), set("plant=5")]).unwrap_err().to_string();
        assert!(e.contains("`plant.m` is inside `plant`"), "{e}");
        apply(&mut doc, &[set("plant.m=1"), set("plant.mu=0.5"), set("plantx.m=2")]).unwrap();
    }

    #[test]
    fn flags_own_their_keys() {
        let e = check_keys(&[set("plant.mu=0.3")], &[("plant.mu", "--mu")]).unwrap_err().to_string();
        assert!(e.contains("--mu") && e.contains("plant.mu"), "{e}");
        let e = check_allowed(&[set("plant.m=1")], &["plant.l".into()], "admissible").unwrap_err().to_string();
        assert!(e.contains("plant.m") && e.contains("admissible") && e.contains("plant.l"), "{e}");
    }
}
