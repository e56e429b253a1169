//! A law's own configuration (issue 70): what a [`crate::ControlLaw`] declares
//! about its settings ([`LawSpec`], one [`ParamSpec`] per parameter: name,
//! unit, range, default) and the values a configuration carries for it
//! ([`LawParams`] in [`crate::Config::law`]).
//!
//! A configuration names the law it is for ([`LawName`]; empty for the paper's
//! laws, which the configuration's `controller` chooses), and holds up to
//! [`LAW_PARAMS`] values in the order of the law's [`LawSpec::params`].
//! [`crate::Firmware::with_law`] refuses a configuration for another law
//! ([`ConfigError::WrongLaw`]) and a value out of its declared range
//! ([`ConfigError::LawParam`]), before the law's own
//! [`crate::ControlLaw::validate`].
//!
//! The spec travels to the plant in postcard's encoding ([`LawSpec::encode`]):
//! in the SIL rig's handshake (`shared::wire::FirmwareAnnouncement::law`) and,
//! in an MCU image, as the symbol `PAINLEVE_LAW_SPEC`; the plant maps a
//! scenario's `[law]` table onto the values by the declared names and checks
//! the ranges with the same rule ([`LawSpec::check`]). A board's image tells
//! its bring-up line and its PIL line only the encoding's digest
//! ([`LawSpec::digest`], 4 bytes of flash): the host reads the declaration
//! from the ELF that was flashed and holds it to the board's digest.

use serde::Serialize;

use crate::config::ConfigError;
pub use crate::law_params::{LAW_NAME_BYTES, LAW_PARAMS, LawName, LawParams};

/// Bytes the encoded [`LawSpec`] may take (the handshake's buffer,
/// `shared::wire::ANNOUNCEMENT_LAW_BYTES`, and the images' symbol).
pub const LAW_SPEC_BYTES: usize = shared::wire::ANNOUNCEMENT_LAW_BYTES;

/// One parameter a law declares.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamSpec {
    /// Its name in a scenario's `[law]` table (`stiffness`).
    pub name: &'static str,
    /// Its unit (`N/m`), for messages and tables.
    pub unit: &'static str,
    /// Least value admitted, in `unit`.
    pub min: f32,
    /// Largest value admitted, in `unit`.
    pub max: f32,
    /// Its value when a scenario leaves it out, in `unit` (within `[min, max]`).
    pub default: f32,
}

/// What a law declares about its configuration: its name and parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LawSpec {
    /// Its name ([`LawName`]'s rule; empty for the paper's laws).
    pub name: &'static str,
    /// Where it comes from (a paper, a book), for `summary.json` and messages.
    pub source: &'static str,
    /// Its parameters, at most [`LAW_PARAMS`].
    pub params: &'static [ParamSpec],
}

impl LawSpec {
    /// The paper's laws: configured by the rest of [`crate::Config`], no parameters here.
    pub const PAPER: Self = Self { name: "", source: "Marchese et al., ECC 2019, eqs. 8 to 11", params: &[] };

    /// Whether the spec is well formed: its name a [`LawName`], at most
    /// [`LAW_PARAMS`] parameters, each with `min <= default <= max` (all finite)
    /// and a name of its own. `Firmware::with_law` asserts it at compile time.
    pub const fn is_valid(&self) -> bool {
        if LawName::new(self.name).is_none() || self.params.len() > LAW_PARAMS {
            return false;
        }
        let mut i = 0;
        while i < self.params.len() {
            let p = &self.params[i];
            if !(p.min.is_finite() && p.max.is_finite() && p.min <= p.default && p.default <= p.max) || p.name.is_empty() {
                return false;
            }
            let mut j = 0;
            while j < i {
                if str_eq(self.params[j].name, p.name) {
                    return false;
                }
                j += 1;
            }
            i += 1;
        }
        true
    }

    /// The law's name as a configuration holds it.
    pub const fn law_name(&self) -> LawName {
        match LawName::new(self.name) {
            Some(n) => n,
            None => LawName::PAPER,
        }
    }

    /// Its name with every parameter at its default.
    pub const fn defaults(&self) -> LawParams {
        let mut values = [0.0; LAW_PARAMS];
        let mut i = 0;
        while i < self.params.len() && i < LAW_PARAMS {
            values[i] = self.params[i].default;
            i += 1;
        }
        LawParams { name: self.law_name(), values }
    }

    /// Checks that `p` is for this law and every value is in its range.
    ///
    /// # Errors
    /// [`ConfigError::WrongLaw`] for another law's name,
    /// [`ConfigError::LawParam`] for the first value out of its declared range
    /// (or not finite), [`ConfigError::OutOfRange`] (`law.values`) for a value
    /// other than 0 beyond the declared parameters.
    #[inline(never)]
    pub fn check(&self, p: &LawParams) -> Result<(), ConfigError> {
        if p.name != self.law_name() {
            return Err(ConfigError::WrongLaw { built: self.law_name(), asked: p.name });
        }
        for (i, &value) in p.values.iter().enumerate() {
            match self.params.get(i) {
                Some(s) if !(value >= s.min && value <= s.max) => {
                    return Err(ConfigError::LawParam { name: s.name, unit: s.unit, value, min: s.min, max: s.max });
                }
                None if value != 0.0 => {
                    return Err(ConfigError::OutOfRange { name: "law.values", value, expected: "0 beyond the law's declared parameters" });
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The spec in postcard's encoding into `buf` (what the plant decodes);
    /// `None` if it does not fit.
    pub fn encode<'b>(&self, buf: &'b mut [u8]) -> Option<&'b mut [u8]> {
        postcard::to_slice(self, buf).ok()
    }

    /// The 32-bit FNV-1a digest of [`LawSpec::encode`]'s output, computed at
    /// compile time where it is a constant ([`digest_of`] of the same bytes):
    /// what an image tells its bring-up line (`arm_app::bringup::Status::law_digest`)
    /// and its PIL line (`crate::pil::Uplink::Hello`), so that the host can
    /// check that the declaration it read from an ELF is the one the board
    /// runs. Any change of a name, unit, range or default changes it (an
    /// accident of equal digests between two laws would need 2^32 of them).
    pub const fn digest(&self) -> u32 {
        let mut h = FNV_OFFSET;
        h = digest_str(h, self.name);
        h = digest_str(h, self.source);
        h = digest_varint(h, self.params.len());
        let mut i = 0;
        while i < self.params.len() {
            let p = &self.params[i];
            h = digest_str(h, p.name);
            h = digest_str(h, p.unit);
            h = digest_bytes(h, &p.min.to_le_bytes());
            h = digest_bytes(h, &p.max.to_le_bytes());
            h = digest_bytes(h, &p.default.to_le_bytes());
            i += 1;
        }
        h
    }

    /// Bytes of [`LawSpec::encode`]'s output, as a constant (the length of an
    /// image's `PAINLEVE_LAW_SPEC`, [`crate::law_spec_symbol`]).
    pub const fn encoded_len(&self) -> usize {
        let mut n = str_len(self.name) + str_len(self.source) + varint_len(self.params.len());
        let mut i = 0;
        while i < self.params.len() {
            n += str_len(self.params[i].name) + str_len(self.params[i].unit) + 12;
            i += 1;
        }
        n
    }

    /// [`LawSpec::encode`]'s bytes computed at compile time (postcard's format:
    /// a string as its varint length and bytes, a slice as its varint length
    /// and elements, an `f32` as 4 little-endian bytes), `N` =
    /// [`LawSpec::encoded_len`] (a different `N` does not compile where it is
    /// a constant). A test holds them equal to postcard's.
    pub const fn encoded<const N: usize>(&self) -> [u8; N] {
        let mut out = [0u8; N];
        let mut at = put_str(&mut out, 0, self.name);
        at = put_str(&mut out, at, self.source);
        at = put_varint(&mut out, at, self.params.len());
        let mut i = 0;
        while i < self.params.len() {
            let p = &self.params[i];
            at = put_str(&mut out, at, p.name);
            at = put_str(&mut out, at, p.unit);
            at = put_f32(&mut out, at, p.min);
            at = put_f32(&mut out, at, p.max);
            at = put_f32(&mut out, at, p.default);
            i += 1;
        }
        assert!(at == N, "LawSpec::encoded: N must be encoded_len()");
        out
    }
}

const FNV_OFFSET: u32 = 0x811c_9dc5;
const FNV_PRIME: u32 = 0x0100_0193;

/// The 32-bit FNV-1a digest of `bytes`: [`LawSpec::digest`] of the spec they
/// encode (the host's side, from a declaration's bytes).
pub const fn digest_of(bytes: &[u8]) -> u32 {
    digest_bytes(FNV_OFFSET, bytes)
}

const fn digest_bytes(mut h: u32, bytes: &[u8]) -> u32 {
    let mut i = 0;
    while i < bytes.len() {
        h = (h ^ bytes[i] as u32).wrapping_mul(FNV_PRIME);
        i += 1;
    }
    h
}

const fn digest_varint(mut h: u32, mut x: usize) -> u32 {
    while x >= 0x80 {
        h = (h ^ ((x as u8 & 0x7f) | 0x80) as u32).wrapping_mul(FNV_PRIME);
        x >>= 7;
    }
    (h ^ x as u32).wrapping_mul(FNV_PRIME)
}

const fn digest_str(h: u32, s: &str) -> u32 {
    digest_bytes(digest_varint(h, s.len()), s.as_bytes())
}

const fn varint_len(mut x: usize) -> usize {
    let mut n = 1;
    while x >= 0x80 {
        x >>= 7;
        n += 1;
    }
    n
}

const fn str_len(s: &str) -> usize {
    varint_len(s.len()) + s.len()
}

const fn put_varint(out: &mut [u8], mut at: usize, mut x: usize) -> usize {
    while x >= 0x80 {
        out[at] = (x as u8 & 0x7f) | 0x80;
        x >>= 7;
        at += 1;
    }
    out[at] = x as u8;
    at + 1
}

const fn put_str(out: &mut [u8], at: usize, s: &str) -> usize {
    let mut at = put_varint(out, at, s.len());
    let b = s.as_bytes();
    let mut i = 0;
    while i < b.len() {
        out[at] = b[i];
        at += 1;
        i += 1;
    }
    at
}

const fn put_f32(out: &mut [u8], at: usize, x: f32) -> usize {
    let b = x.to_bits().to_le_bytes();
    out[at] = b[0];
    out[at + 1] = b[1];
    out[at + 2] = b[2];
    out[at + 3] = b[3];
    at + 4
}

const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: LawSpec = LawSpec {
        name: "test-law",
        source: "a test",
        params: &[
            ParamSpec { name: "k", unit: "N/m", min: 0.0, max: 1000.0, default: 400.0 },
            ParamSpec { name: "d", unit: "N s/m", min: 0.0, max: 100.0, default: 40.0 },
        ],
    };

    #[test]
    fn names_admit_only_short_ascii_words_and_round_trip() {
        assert_eq!(LawName::new("impedance").unwrap().as_str(), "impedance");
        assert_eq!(LawName::new("").unwrap(), LawName::PAPER);
        assert!(LawName::new("a-name_that_is_17").is_none());
        assert!(LawName::new("sixteen_chars_ok").is_some());
        for bad in ["with space", "é", "a.b", "a\0"] {
            assert!(LawName::new(bad).is_none(), "{bad:?}");
        }
        let p = SPEC.defaults();
        let json = serde_json::to_string(&p).unwrap();
        assert!(json.starts_with(r#"{"name":"test-law","values":[400.0,40.0,0.0"#), "{json}");
        assert_eq!(serde_json::from_str::<LawParams>(&json).unwrap(), p);
        let mut buf = [0u8; 64];
        let bytes = postcard::to_slice(&p, &mut buf).unwrap();
        assert_eq!(postcard::from_bytes::<LawParams>(bytes).unwrap(), p);
        assert!(serde_json::from_str::<LawParams>(&json.replace("test-law", "bad name")).is_err());
    }

    #[test]
    fn check_refuses_another_law_a_value_out_of_range_and_a_stray_value() {
        assert!(SPEC.is_valid() && LawSpec::PAPER.is_valid());
        SPEC.check(&SPEC.defaults()).unwrap();
        LawSpec::PAPER.check(&LawParams::PAPER).unwrap();
        assert_eq!(LawSpec::PAPER.check(&SPEC.defaults()), Err(ConfigError::WrongLaw { built: LawName::PAPER, asked: SPEC.law_name() }));
        assert!(matches!(SPEC.check(&LawParams::PAPER), Err(ConfigError::WrongLaw { .. })));
        for (i, bad) in [(0, -1.0), (0, 1000.5), (1, f32::NAN), (1, f32::INFINITY)] {
            let mut p = SPEC.defaults();
            p.values[i] = bad;
            let e = SPEC.check(&p).unwrap_err();
            assert!(matches!(e, ConfigError::LawParam { name, .. } if name == SPEC.params[i].name), "{e}");
        }
        let mut p = SPEC.defaults();
        p.values[5] = 1.0;
        assert!(matches!(SPEC.check(&p), Err(ConfigError::OutOfRange { name: "law.values", .. })));
    }

    /// The digest computed from the spec at compile time is the digest of its
    /// encoding's bytes (what the host computes from an ELF's declaration), and
    /// any change of a name, unit, range or default moves it.
    #[test]
    fn the_digest_is_the_encodings_and_moves_with_any_change() {
        const D: u32 = SPEC.digest();
        let mut buf = [0u8; LAW_SPEC_BYTES];
        assert_eq!(D, digest_of(SPEC.encode(&mut buf).unwrap()));
        assert_eq!(LawSpec::PAPER.digest(), digest_of(LawSpec::PAPER.encode(&mut buf).unwrap()));
        let p = SPEC.params;
        let leak = |v: Vec<ParamSpec>| -> &'static [ParamSpec] { v.leak() };
        let (one, swapped) = (leak(vec![p[0]]), leak(vec![p[1], p[0]]));
        let (unit, max, default) = (
            leak(vec![ParamSpec { unit: "N/mm", ..p[0] }, p[1]]),
            leak(vec![ParamSpec { max: 1000.5, ..p[0] }, p[1]]),
            leak(vec![p[0], ParamSpec { default: 41.0, ..p[1] }]),
        );
        let changed = [
            LawSpec { name: "test-lax", ..SPEC },
            LawSpec { source: "a tesT", ..SPEC },
            LawSpec { params: one, ..SPEC },
            LawSpec { params: swapped, ..SPEC },
            LawSpec { params: unit, ..SPEC },
            LawSpec { params: max, ..SPEC },
            LawSpec { params: default, ..SPEC },
        ];
        for c in changed {
            assert_ne!(c.digest(), D, "{c:?}");
        }
    }

    #[test]
    fn the_compile_time_encoding_is_postcards() {
        const N: usize = SPEC.encoded_len();
        const BYTES: [u8; N] = SPEC.encoded();
        let mut buf = [0u8; 512];
        assert_eq!(&BYTES[..], &*SPEC.encode(&mut buf).unwrap());
        const P: usize = LawSpec::PAPER.encoded_len();
        assert_eq!(&LawSpec::PAPER.encoded::<P>()[..], &*LawSpec::PAPER.encode(&mut buf).unwrap());
        // A long name (two-byte varint length) too.
        const LONG: LawSpec = LawSpec {
            source: concat!(
                "a source of more than one hundred and twenty-eight bytes, so that its length ",
                "takes two bytes of varint in postcard's format; a source of more than one hundred ",
                "and twenty-eight bytes"
            ),
            ..SPEC
        };
        const L: usize = LONG.encoded_len();
        assert!(LONG.source.len() >= 128);
        assert_eq!(&LONG.encoded::<L>()[..], &*LONG.encode(&mut buf).unwrap());
    }

    #[test]
    fn a_malformed_spec_is_not_valid() {
        const fn p(name: &'static str, min: f32, max: f32, default: f32) -> ParamSpec {
            ParamSpec { name, unit: "", min, max, default }
        }
        static MIN_ABOVE_MAX: [ParamSpec; 1] = [p("k", 1.0, 0.0, 0.5)];
        static DEFAULT_OUTSIDE: [ParamSpec; 1] = [p("k", 0.0, 1.0, 2.0)];
        static UNBOUNDED: [ParamSpec; 1] = [p("k", 0.0, f32::INFINITY, 1.0)];
        static TWICE: [ParamSpec; 2] = [p("k", 0.0, 1.0, 0.5), p("k", 0.0, 1.0, 0.5)];
        static UNNAMED: [ParamSpec; 1] = [p("", 0.0, 1.0, 0.5)];
        static NINE: [ParamSpec; 9] = [
            p("a", 0.0, 1.0, 0.5),
            p("b", 0.0, 1.0, 0.5),
            p("c", 0.0, 1.0, 0.5),
            p("d", 0.0, 1.0, 0.5),
            p("e", 0.0, 1.0, 0.5),
            p("f", 0.0, 1.0, 0.5),
            p("g", 0.0, 1.0, 0.5),
            p("h", 0.0, 1.0, 0.5),
            p("i", 0.0, 1.0, 0.5),
        ];
        for params in [&MIN_ABOVE_MAX[..], &DEFAULT_OUTSIDE, &UNBOUNDED, &TWICE, &UNNAMED, &NINE] {
            assert!(!LawSpec { params, ..SPEC }.is_valid(), "{params:?}");
        }
        assert!(LawSpec { params: &NINE[..8], ..SPEC }.is_valid());
        assert!(!LawSpec { name: "no spaces", ..SPEC }.is_valid());
    }
}
