//! The law a configuration is for and its own parameters' values
//! ([`LawParams`] in [`crate::Config::law`]; issue 70): what a configuration
//! carries on every wire. What a law declares about them, and the check of
//! one against the other, is [`crate::law_spec`].

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Values a configuration holds for a law's own parameters.
pub const LAW_PARAMS: usize = 8;
/// Bytes of a law's name (ASCII).
pub const LAW_NAME_BYTES: usize = 16;

/// A law's name: 1 to [`LAW_NAME_BYTES`] ASCII letters, digits, `-` or `_`;
/// empty for the paper's laws ([`LawName::PAPER`]). Serialised as a string.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct LawName([u8; LAW_NAME_BYTES]);

impl LawName {
    /// The paper's laws (the configuration's `controller` chooses PID or hybrid).
    pub const PAPER: Self = Self([0; LAW_NAME_BYTES]);

    /// `name` as a law's name; `None` if it is longer than [`LAW_NAME_BYTES`] or
    /// holds another character than an ASCII letter, digit, `-` or `_`.
    pub const fn new(name: &str) -> Option<Self> {
        Self::from_bytes(name.as_bytes())
    }

    /// [`LawName::new`] of bytes.
    pub const fn from_bytes(b: &[u8]) -> Option<Self> {
        if b.len() > LAW_NAME_BYTES {
            return None;
        }
        let mut out = [0u8; LAW_NAME_BYTES];
        let mut i = 0;
        while i < b.len() {
            let c = b[i];
            if !(c.is_ascii_alphanumeric() || c == b'-' || c == b'_') {
                return None;
            }
            out[i] = c;
            i += 1;
        }
        Some(Self(out))
    }

    /// The name (empty for the paper's laws).
    pub fn as_str(&self) -> &str {
        // `new` and `Deserialize` admit ASCII only.
        core::str::from_utf8(self.as_bytes()).unwrap_or("")
    }

    /// The name's ASCII bytes (empty for the paper's laws).
    pub fn as_bytes(&self) -> &[u8] {
        let len = self.0.iter().position(|&c| c == 0).unwrap_or(LAW_NAME_BYTES);
        &self.0[..len]
    }

    /// Whether this is [`LawName::PAPER`].
    pub fn is_paper(&self) -> bool {
        self.0[0] == 0
    }
}

impl core::fmt::Debug for LawName {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

impl core::fmt::Display for LawName {
    /// The name, or `the paper's laws` for [`LawName::PAPER`].
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.is_paper() { f.write_str("the paper's laws") } else { f.write_str(self.as_str()) }
    }
}

impl Serialize for LawName {
    /// A string in a human-readable format (JSON, TOML); its bytes otherwise
    /// (postcard: the same length and bytes as a string, without the MCU
    /// linking a UTF-8 check).
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if s.is_human_readable() { s.serialize_str(self.as_str()) } else { s.serialize_bytes(self.as_bytes()) }
    }
}

impl<'de> Deserialize<'de> for LawName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = LawName;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("a law's name: up to 16 ASCII letters, digits, `-` or `_`")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<LawName, E> {
                self.visit_bytes(v.as_bytes())
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<LawName, E> {
                LawName::from_bytes(v).ok_or_else(|| E::invalid_value(serde::de::Unexpected::Bytes(v), &self))
            }
        }
        if d.is_human_readable() { d.deserialize_str(Visitor) } else { d.deserialize_bytes(Visitor) }
    }
}

/// The law a configuration is for and its parameters' values
/// ([`crate::Config::law`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LawParams {
    /// The law ([`LawName::PAPER`]: the paper's laws).
    pub name: LawName,
    /// Its parameters in the order of its [`LawSpec::params`], in their
    /// declared units; 0 beyond them.
    #[serde(with = "values")]
    pub values: [f32; LAW_PARAMS],
}

/// `[f32; LAW_PARAMS]` as a tuple, read in a loop: serde's own array impl
/// unrolls the eight reads (about 600 bytes more flash on the MCU images).
mod values {
    use serde::{
        Deserializer, Serializer,
        de::{Error, SeqAccess, Visitor},
        ser::SerializeTuple,
    };

    use super::LAW_PARAMS;

    pub(super) fn serialize<S: Serializer>(v: &[f32; LAW_PARAMS], s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(LAW_PARAMS)?;
        for x in v {
            t.serialize_element(x)?;
        }
        t.end()
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[f32; LAW_PARAMS], D::Error> {
        struct Values;
        impl<'de> Visitor<'de> for Values {
            type Value = [f32; LAW_PARAMS];
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("8 numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = [0.0; LAW_PARAMS];
                for (i, v) in out.iter_mut().enumerate() {
                    *v = seq.next_element()?.ok_or_else(|| A::Error::invalid_length(i, &self))?;
                }
                Ok(out)
            }
        }
        d.deserialize_tuple(LAW_PARAMS, Values)
    }
}

impl LawParams {
    /// The paper's laws: no name, no values.
    pub const PAPER: Self = Self { name: LawName::PAPER, values: [0.0; LAW_PARAMS] };
}

impl Default for LawParams {
    /// [`LawParams::PAPER`].
    fn default() -> Self {
        Self::PAPER
    }
}
