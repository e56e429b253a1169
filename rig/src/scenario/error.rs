//! Why a scenario was rejected: the one error type of reading, overriding and
//! validating a scenario.

use crate::overrides;

/// Why a scenario was rejected.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// Not valid TOML, or keys unknown, missing or of the wrong type.
    #[error("{0}")]
    Parse(String),
    /// A value out of range.
    #[error("scenario key `{key}` = {value} is out of range: expected {expected}")]
    OutOfRange {
        /// Dotted key.
        key: String,
        /// The value as written.
        value: String,
        /// What is allowed.
        expected: String,
    },
    /// The `[board]` or `[calibration]` table is invalid (the message names the key).
    #[error("scenario key {0}")]
    Board(String),
    /// A `[[faults]]` entry is invalid.
    #[error("scenario key `faults[{index}]`: {what}")]
    Fault {
        /// Index of the entry (0-based, in file order).
        index: usize,
        /// What is wrong, naming the key and value.
        what: String,
    },
    /// A `--set KEY=VALUE` override is malformed, names no key this command
    /// takes, or contradicts a flag ([`crate::overrides`]).
    #[error("{0}")]
    Override(#[from] overrides::OverrideError),
}
