//! Target `scenario`: [`Scenario::from_toml`](rig::scenario::Scenario::from_toml) and
//! [`Scenario::from_toml_with`](rig::scenario::Scenario::from_toml_with)
//! (the command line's `--set KEY=VALUE`, `rig::overrides`) under hostile input.
//!
//! A case is either
//!
//! - **a document**: one of `scenarios/*.toml` (or the default with three valid
//!   `[[faults]]`) as a TOML table, changed by up to 8 edits (a key of the
//!   scenario's key set, an unknown key, or a key 3 to 300 tables deep set to a
//!   hostile value or removed; a `[[faults]]` entry added), written back as TOML
//!   and then changed line by line (lines repeated, removed or replaced by
//!   hostile ones); or
//! - **bytes**: a scenario file with 1 to 8 byte mutations (those of
//!   [`crate::pil_decode::Mutation`]), read as UTF-8 with replacement characters,
//!
//! and up to 4 `--set` arguments (a known, unknown, malformed or very deep key
//! with a TOML, bare-word or malformed value).
//!
//! Hostile values: floats at and one or two ulps around every documented bound
//! (and the `f32` range's), NaN, infinities, `-0.0`, subnormals, any bits; integers
//! at the ends of `u8`, `u16`, `u32` and `i64`; the enum words of every key,
//! `"nan"`, `""`, strings up to 100 000 characters, odd Unicode; booleans; arrays
//! (up to 100 000 elements) and inline tables, nested up to 300 levels.
//!
//! The property ([`check`]): no panic, no stack overflow (on the 8 MiB stack of
//! [`crate::on_harness_thread`]); an accepted scenario satisfies every bound of
//! docs/rig.md's tables, re-checked here independently ([`violations`]), its
//! firmware configuration is one the firmware accepts, and it round-trips (written
//! with `toml` and read again it is the same scenario, bit for bit: the firmware
//! process gets its scenario that way); `from_toml_with` and
//! `from_toml` followed by [`Scenario::with_overrides`](rig::scenario::Scenario::with_overrides) agree when both accept;
//! without overrides `from_toml_with` is `from_toml`; an error's message is not
//! empty and names a key (in backticks, or the `--set` argument) or where the
//! TOML is malformed (line and column) ([`error_names_its_place`]).
//!
//! The files: `keys` (the scenario files, the key set and the keys' documented
//! ranges), `hostile` (the hostile words, bounds and integers), `case` (a case and
//! how its parts are written), `generators` (the proptest strategies), `document`
//! (a case's scenario text) and `property` (the checks).

mod case;
mod document;
mod generators;
mod hostile;
mod keys;
mod property;

pub use case::{Case, Edit, InRange, LineEdit, Path, SetArg, SetKey, SetValue, Source, Val};
pub use document::text;
pub use generators::strategy;
pub use hostile::WORDS;
pub use keys::{FAULT_KEYS, FILES, KEYS, TABLES};
pub use property::{check, check_accepted, error_names_its_place, violations};
