//! Reading a scenario: the embedded default, TOML text with `--set` overrides
//! applied to its document, the old key `controller.hybrid_ki`, and errors that
//! name the key, the line or the override.

use super::{error::ScenarioError, sections::Scenario};
use crate::overrides::{self, Override};

/// The embedded default scenario (`scenarios/default.toml`).
pub const DEFAULT_TOML: &str = include_str!("../../../scenarios/default.toml");

impl Scenario {
    /// The control law a run of this scenario names in its outputs: the
    /// `[law]` table's name, else `controller.kind` (`hybrid`, `pid`).
    pub fn controller_name(&self) -> &str {
        self.law.as_ref().map_or(self.controller.kind.name(), |l| l.name.as_str())
    }

    /// The embedded default scenario.
    pub fn default_scenario() -> Self {
        // The embedded file is checked by a test; a parse failure here is a build defect.
        Self::from_toml(DEFAULT_TOML).unwrap_or_else(|e| panic!("embedded default scenario is invalid: {e}"))
    }

    /// Parses and validates a scenario.
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] (with the key and line from the TOML parser) or
    /// [`ScenarioError::OutOfRange`] naming the key and value.
    pub fn from_toml(text: &str) -> Result<Self, ScenarioError> {
        Self::from_toml_with(text, &[])
    }

    /// Parses a scenario, applies `overrides` to its TOML document (each
    /// `--set KEY=VALUE` replaces or adds the value at its dotted key path), then
    /// reads and validates it. The old key `controller.hybrid_ki` is read as
    /// `controller.hybrid.ki`.
    ///
    /// # Errors
    /// As [`Self::from_toml`]; an error caused by an override names it
    /// ([`ScenarioError::Override`], or the key and value of the bad key).
    pub fn from_toml_with(text: &str, overrides: &[Override]) -> Result<Self, ScenarioError> {
        let s = Self::read_with(text, overrides)?;
        s.validate()?;
        Ok(s)
    }

    /// [`Self::from_toml_with`] without the range checks ([`Scenario::validate`]):
    /// for a caller that uses part of the scenario only and checks that part itself.
    /// The open-loop commands take the arm's parameters of the embedded default
    /// with their `--set` overrides and check the arm alone
    /// ([`crate::arm::arm_params`]): the closed loop's keys they never use (the
    /// target `controller.target_z_t` within the arm's reach, the firmware's `f32`
    /// model) must not refuse an arm (issue 67: `simulate` refused every arm with
    /// `l <= 0.05` m, the default target 0.10 m out of its reach).
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] (with the key and line from the TOML parser, or the
    /// override that caused it) or [`ScenarioError::Override`]; never
    /// [`ScenarioError::OutOfRange`].
    pub(crate) fn read_with(text: &str, overrides: &[Override]) -> Result<Self, ScenarioError> {
        let mut doc: toml::Table = toml::from_str(text).map_err(|e| toml_error(&e))?;
        // The file's old key first (an override of `controller.hybrid.ki` then
        // wins over it), then an override's.
        let mut migrated = migrate_legacy(&mut doc)?;
        overrides::apply(&mut doc, overrides)?;
        migrated |= migrate_legacy(&mut doc)?;
        let s: Scenario = if overrides.is_empty() && !migrated {
            // The text itself: the TOML errors give the line.
            let de = toml::de::Deserializer::parse(text).map_err(|e| toml_error(&e))?;
            let s = read(de, &[])?;
            // The text's reader drops an array's extra elements (`kp = [1.0, 2.0,
            // "x"]` read as `[1.0, 2.0]`: toml's array reader never says it had
            // more; the document's, which `--set` goes through, refuses them):
            // every array of the file must have the length it was read with
            // (issue 52, 6).
            check_lengths(&doc, &s.to_table()?, "")?;
            // Tables not written back (`[board]` at its default) by the document's reader.
            read(toml::Value::Table(doc), &[])?;
            s
        } else {
            read(toml::Value::Table(doc), overrides)?
        };
        Ok(s)
    }

    /// The scenario as a TOML table (for [`overrides::apply`]).
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] if it cannot be written as TOML.
    pub fn to_table(&self) -> Result<toml::Table, ScenarioError> {
        toml::Table::try_from(self).map_err(|e| ScenarioError::Parse(format!("cannot write the scenario as TOML: {e}")))
    }

    /// This scenario with `overrides` applied, validated.
    ///
    /// # Errors
    /// As [`Self::from_toml_with`].
    pub fn with_overrides(&self, overrides: &[Override]) -> Result<Self, ScenarioError> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let mut doc = self.to_table()?;
        overrides::apply(&mut doc, overrides)?;
        migrate_legacy(&mut doc)?;
        let s: Scenario = read(toml::Value::Table(doc), overrides)?;
        s.validate()?;
        Ok(s)
    }
}

/// A TOML syntax error as a scenario error. The reader's errors give the line and
/// column, except its nesting limit's (keys, tables or arrays 80 levels deep), which
/// says only "recursion limit": that one is said here (found by the `scenario`
/// fuzzing harness, docs/fuzzing.md).
fn toml_error(e: &toml::de::Error) -> ScenarioError {
    let msg = e.to_string();
    if e.span().is_some() {
        return ScenarioError::Parse(msg);
    }
    let why = if msg.trim() == "recursion limit" {
        "keys, tables or arrays nested 80 levels deep or more (scenario keys are at most 3 deep)".to_string()
    } else {
        msg.trim().to_string()
    };
    ScenarioError::Parse(format!("the scenario is not valid TOML: {why}"))
}

/// Reads the old key `controller.hybrid_ki` as `controller.hybrid.ki` (scenario
/// files written before the gains were opened). Returns whether it did.
///
/// # Errors
/// [`ScenarioError::Parse`] when both are given.
fn migrate_legacy(doc: &mut toml::Table) -> Result<bool, ScenarioError> {
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
            "scenario keys `controller.hybrid_ki` and `controller.hybrid.ki` are the same gain K'_I: give one (controller.hybrid.ki)"
                .into(),
        )),
    }
}

/// Checks that every array of the document `doc` has the length of the same
/// key's array in `read` (the scenario read from it, as a table), `prefix` the
/// path of `doc`'s table.
///
/// # Errors
/// [`ScenarioError::Parse`] naming the first key whose array is longer (or
/// shorter) than the key takes, with both lengths.
fn check_lengths(doc: &toml::Table, read: &toml::Table, prefix: &str) -> Result<(), ScenarioError> {
    for (k, v) in doc {
        let path = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
        match (v, read.get(k)) {
            (toml::Value::Table(a), Some(toml::Value::Table(b))) => check_lengths(a, b, &path)?,
            (toml::Value::Array(a), Some(toml::Value::Array(b))) if a.len() != b.len() => {
                return Err(ScenarioError::Parse(format!(
                    "scenario key `{path}`: an array of {} elements where the key takes {} (an element too many is an error, never dropped)",
                    a.len(),
                    b.len()
                )));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Deserialises a scenario; the error names the key path (`controller.kind`) and,
/// when an override touched that key, the override.
fn read<'de, D: serde::Deserializer<'de>>(de: D, overrides: &[Override]) -> Result<Scenario, ScenarioError>
where
    D::Error: std::fmt::Display,
{
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // Errors from a document (not a text) repeat the key on a line of their own.
        let inner = if overrides.is_empty() { inner.as_str() } else { inner.lines().next().unwrap_or_default() };
        // toml's document reader on an array longer than the key takes.
        let longer =
            inner.strip_prefix("invalid length ").and_then(|r| r.split_once(", expected fewer elements in array")).map(|(n, rest)| {
                format!("an array of {n} elements, more than the key takes (an element too many is an error, never dropped){rest}")
            });
        let inner = longer.as_deref().unwrap_or(inner);
        let msg = if path == "." { inner.to_string() } else { format!("scenario key `{path}`: {inner}") };
        match overrides::culprit(overrides, &path) {
            Some(o) => ScenarioError::Parse(format!("{msg} (from --set {o})")),
            None => ScenarioError::Parse(msg),
        }
    })
}
