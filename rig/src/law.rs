//! A law of one's own, as the plant sees it (issue 70; docs/board.md "Your own
//! law"): a scenario's `[law]` table ([`LawTable`]), the law's declaration as
//! the firmware announces it ([`LawDescription`], decoded from
//! `firmware::law_spec::LawSpec`'s postcard encoding) and the two put together
//! ([`bind`]): the values `firmware::Config::law` carries, each parameter
//! checked against the range the law declares.
//!
//! ```toml
//! [law]
//! name = "impedance"     # the law the firmware was built with
//! stiffness = 2000.0     # a declared parameter, in its declared unit
//! ```
//!
//! A parameter the table leaves out takes the law's declared default; a name
//! the law does not declare, a value out of its range and a table for another
//! law are refused with the law's own declaration in the message.

use std::collections::BTreeMap;

use firmware::{LawName, LawParams, LawSpec, law_spec::LAW_PARAMS};
use serde::{Deserialize, Serialize};

/// A scenario's `[law]` table: the law's name and its parameters by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LawTable {
    /// The law's declared name (`firmware::ControlLaw::SPEC.name`).
    pub name: String,
    /// Its parameters by declared name, in their declared units.
    #[serde(flatten)]
    pub params: BTreeMap<String, f64>,
}

impl LawTable {
    /// The parameters the table sets, in words, for a run's views (the trace page,
    /// the MCAP's `/log`, Python's `Result.law`): `d_n = 50, k_t = 2500, the rest
    /// at their defaults`, or `every parameter at its default` (by name, in
    /// their declared units; the defaults are the law's declaration's).
    #[must_use]
    pub fn params_in_words(&self) -> String {
        if self.params.is_empty() {
            return "every parameter at its default".to_string();
        }
        let set: Vec<String> = self.params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        format!("{}, the rest at their defaults", set.join(", "))
    }

    /// The law in words: ``law `impedance` (k_t = 2500, the rest at their defaults)``.
    #[must_use]
    pub fn in_words(&self) -> String {
        format!("law `{}` ({})", self.name, self.params_in_words())
    }
}

/// One parameter of a [`LawDescription`] (`firmware::ParamSpec`, owned).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamDescription {
    /// Its name in a `[law]` table.
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Least value admitted.
    pub min: f32,
    /// Largest value admitted.
    pub max: f32,
    /// Its value when the table leaves it out.
    pub default: f32,
}

/// What a law declares about its configuration (`firmware::LawSpec`, owned):
/// decoded from a firmware's announcement or taken from a law linked in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LawDescription {
    /// Its name; empty for the paper's laws.
    pub name: String,
    /// Where it comes from.
    pub source: String,
    /// Its parameters, in the order `firmware::Config::law` holds them.
    pub params: Vec<ParamDescription>,
}

/// Why a `[law]` table and a law's declaration do not fit together, or a
/// declaration cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LawError {
    /// The scenario names a law the firmware was not built with (or none, to a
    /// firmware built with one).
    #[error("the scenario asks for {asked}, the firmware runs {runs}{hint}")]
    WrongLaw {
        /// What the scenario asks for.
        asked: String,
        /// What the firmware runs.
        runs: String,
        /// How to get the right one.
        hint: &'static str,
    },
    /// The table names a parameter the law does not declare.
    #[error("law `{law}` has no parameter `{name}`; it declares {declared}")]
    UnknownParam {
        /// The law.
        law: String,
        /// The name given.
        name: String,
        /// The declared parameters with their units and ranges.
        declared: String,
    },
    /// A value is out of the range the law declares (or not finite).
    #[error("law `{law}`: `{name}` = {value} {unit} is out of its range [{min}, {max}] {unit}")]
    OutOfRange {
        /// The law.
        law: String,
        /// The parameter.
        name: String,
        /// Its unit.
        unit: String,
        /// The value given.
        value: f64,
        /// Least value admitted.
        min: f32,
        /// Largest value admitted.
        max: f32,
    },
    /// The announced declaration does not decode (another build's layout).
    #[error("the firmware's law declaration cannot be decoded ({0}): rebuild both sides from the same sources")]
    Undecodable(String),
    /// The image's file cannot be read: missing, not a regular file, or over
    /// its bound (`tables::input::ELF_IMAGE`); the message names the file and the bound.
    #[error("{0}")]
    Unreadable(String),
    /// The image declares no law (no `PAINLEVE_LAW_SPEC`) where a scenario's law
    /// is bound to it: an image of these sources always declares its law, the
    /// paper's included, so this one is not one of them (issue 80).
    #[error(
        "{0}: the image declares no law (no PAINLEVE_LAW_SPEC symbol): it is not an image of these sources, whose images all \
         declare theirs (the paper's laws too); build it with `cargo arm`/`cargo pil` (docs/board.md \"Your own law\")"
    )]
    NoDeclaration(String),
}

impl LawDescription {
    /// The declaration of a law linked in.
    pub fn of(spec: &LawSpec) -> Self {
        Self {
            name: spec.name.to_string(),
            source: spec.source.to_string(),
            params: spec
                .params
                .iter()
                .map(|p| ParamDescription {
                    name: p.name.to_string(),
                    unit: p.unit.to_string(),
                    min: p.min,
                    max: p.max,
                    default: p.default,
                })
                .collect(),
        }
    }

    /// The paper's laws' declaration ([`LawSpec::PAPER`]).
    pub fn paper() -> Self {
        Self::of(&LawSpec::PAPER)
    }

    /// The digest of this declaration's encoding (`firmware::LawSpec::digest`
    /// of the law it describes): what a board's image reports
    /// (`arm_app::bringup::Status::law_digest`, the PIL line's Hello), to hold
    /// an ELF's declaration to the image the board runs.
    pub fn digest(&self) -> u32 {
        // The layout `decode` reads: postcard of the same fields in the same order.
        let mut buf = [0u8; firmware::law_spec::LAW_SPEC_BYTES];
        postcard::to_slice(self, &mut buf).map_or(0, |b| firmware::law_spec::digest_of(b))
    }

    /// Whether this is the paper's laws' declaration (no name).
    pub fn is_paper(&self) -> bool {
        self.name.is_empty()
    }

    /// Decodes a declaration in postcard's encoding (a firmware's announcement,
    /// an image's `PAINLEVE_LAW_SPEC`).
    ///
    /// # Errors
    /// [`LawError::Undecodable`] for bytes that are not exactly one declaration
    /// of this build's layout.
    pub fn decode(bytes: &[u8]) -> Result<Self, LawError> {
        match postcard::take_from_bytes::<Self>(bytes) {
            Ok((d, [])) => Ok(d),
            Ok(_) => Err(LawError::Undecodable("bytes left over".into())),
            Err(e) => Err(LawError::Undecodable(e.to_string())),
        }
    }

    /// The declaration an MCU image carries in its symbol `PAINLEVE_LAW_SPEC`
    /// (`firmware::law_spec_symbol!`, in postcard's encoding); `None` for an
    /// image without it. The file is read within `tables::input::ELF_IMAGE`'s
    /// bound, a regular file only.
    ///
    /// # Errors
    /// [`LawError::Unreadable`] for a file that cannot be read, is not a
    /// regular file or is over its bound; [`LawError::Undecodable`] for one
    /// that is not an ELF, a symbol outside its section's data, or bytes that
    /// do not decode.
    pub fn from_elf(path: &std::path::Path) -> Result<Option<Self>, LawError> {
        use object::{Object, ObjectSection, ObjectSymbol};
        let bad = |what: String| LawError::Undecodable(format!("{}: {what}", path.display()));
        let data = tables::input::read(path, tables::input::ELF_IMAGE).map_err(|e| LawError::Unreadable(e.to_string()))?;
        let file = object::File::parse(&*data).map_err(|e| bad(format!("not an ELF image ({e})")))?;
        let Some(symbol) = file.symbols().find(|s| s.name() == Ok("PAINLEVE_LAW_SPEC")) else { return Ok(None) };
        let section = symbol
            .section_index()
            .and_then(|i| file.section_by_index(i).ok())
            .ok_or_else(|| bad("PAINLEVE_LAW_SPEC is in no section".into()))?;
        let bytes = section
            .data_range(symbol.address(), symbol.size())
            .ok()
            .flatten()
            .ok_or_else(|| bad("PAINLEVE_LAW_SPEC is outside its section's data".into()))?;
        Self::decode(bytes).map(Some).map_err(|e| bad(e.to_string()))
    }

    /// The law the image at `path` declares, where a scenario's `[law]` table
    /// is bound to it (`board configure --elf`, `pil --image`, the emulated
    /// board's `--elf`): every image of these sources declares its law, the
    /// paper's laws included, so an image without a declaration is refused
    /// rather than taken for the paper's.
    ///
    /// # Errors
    /// As [`LawDescription::from_elf`]; [`LawError::NoDeclaration`] for an
    /// image without `PAINLEVE_LAW_SPEC`.
    pub fn declared_by(path: &std::path::Path) -> Result<Self, LawError> {
        Self::from_elf(path)?.ok_or_else(|| LawError::NoDeclaration(path.display().to_string()))
    }

    /// The declared parameters as a message lists them: `stiffness (N/m, [0, 5000])`.
    pub fn listed(&self) -> String {
        if self.params.is_empty() {
            return "no parameters".into();
        }
        self.params.iter().map(|p| format!("`{}` ({}, [{}, {}])", p.name, p.unit, p.min, p.max)).collect::<Vec<_>>().join(", ")
    }

    /// How a message names it.
    pub fn title(&self) -> String {
        if self.is_paper() { "the paper's laws (PID and hybrid)".into() } else { format!("law `{}`", self.name) }
    }
}

/// The values `firmware::Config::law` carries for `table` under the law `law`
/// declares: its name, and per declared parameter the table's value (`f32`)
/// or the declared default. `None` for the table: the paper's laws.
///
/// # Errors
/// [`LawError::WrongLaw`] when the table names another law than `law` (or
/// none, to a law of one's own, or one to the paper's laws),
/// [`LawError::UnknownParam`] for a name `law` does not declare,
/// [`LawError::OutOfRange`] for a value out of its declared range.
pub fn bind(table: Option<&LawTable>, law: &LawDescription) -> Result<LawParams, LawError> {
    let asked = table.map_or_else(|| "the paper's laws (no `[law]` table)".to_string(), |t| format!("law `{}`", t.name));
    let same = match table {
        None => law.is_paper(),
        Some(t) => !law.is_paper() && t.name == law.name,
    };
    if !same {
        let hint = if law.is_paper() {
            ": run the law's own firmware: its firmware process attached over iceoryx2, its `arm` image on the emulated board or a board, its PIL image (docs/board.md \"Your own law\")"
        } else {
            ": give the scenario the law's `[law]` table, or run the paper's laws' firmware"
        };
        return Err(LawError::WrongLaw { asked, runs: law.title(), hint });
    }
    let Some(table) = table else { return Ok(LawParams::PAPER) };
    let name = LawName::new(&law.name).ok_or_else(|| LawError::Undecodable(format!("law name `{}`", law.name)))?;
    if law.params.len() > LAW_PARAMS {
        return Err(LawError::Undecodable(format!("{} parameters, at most {LAW_PARAMS}", law.params.len())));
    }
    if let Some(unknown) = table.params.keys().find(|k| !law.params.iter().any(|p| &p.name == *k)) {
        return Err(LawError::UnknownParam { law: law.name.clone(), name: unknown.clone(), declared: law.listed() });
    }
    let mut values = [0.0f32; LAW_PARAMS];
    for (v, p) in values.iter_mut().zip(&law.params) {
        let Some(&given) = table.params.get(&p.name) else {
            *v = p.default;
            continue;
        };
        let x = given as f32;
        if !(x >= p.min && x <= p.max && given.is_finite()) {
            return Err(LawError::OutOfRange {
                law: law.name.clone(),
                name: p.name.clone(),
                unit: p.unit.clone(),
                value: given,
                min: p.min,
                max: p.max,
            });
        }
        *v = x;
    }
    Ok(LawParams { name, values })
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::ParamSpec;

    const SPEC: LawSpec = LawSpec {
        name: "impedance",
        source: "Hogan 1985",
        params: &[
            ParamSpec { name: "stiffness", unit: "N/m", min: 0.0, max: 5000.0, default: 2000.0 },
            ParamSpec { name: "damping", unit: "N s/m", min: 0.0, max: 500.0, default: 60.0 },
        ],
    };

    fn table(name: &str, params: &[(&str, f64)]) -> LawTable {
        LawTable { name: name.into(), params: params.iter().map(|(k, v)| ((*k).to_string(), *v)).collect() }
    }

    /// A declaration's digest, taken from its decoded form on the host, is the
    /// one the image computes at compile time from the law linked in.
    #[test]
    fn a_descriptions_digest_is_the_laws() {
        let spec = LawSpec {
            name: "damped",
            source: "a test",
            params: &[firmware::ParamSpec { name: "k", unit: "N/m", min: 0.0, max: 10.0, default: 1.0 }],
        };
        assert_eq!(LawDescription::of(&spec).digest(), spec.digest());
        assert_eq!(LawDescription::paper().digest(), LawSpec::PAPER.digest());
        assert_ne!(LawDescription::of(&spec).digest(), LawDescription::paper().digest());
    }

    #[test]
    fn the_declaration_round_trips_through_its_encoding() {
        let mut buf = [0u8; firmware::law_spec::LAW_SPEC_BYTES];
        for spec in [SPEC, LawSpec::PAPER] {
            let bytes = spec.encode(&mut buf).unwrap();
            assert_eq!(LawDescription::decode(bytes).unwrap(), LawDescription::of(&spec));
        }
        assert!(matches!(LawDescription::decode(&[0xff; 8]), Err(LawError::Undecodable(_))));
    }

    #[test]
    fn a_table_binds_to_its_declared_order_with_defaults_and_the_firmware_agrees() {
        let law = LawDescription::of(&SPEC);
        let p = bind(Some(&table("impedance", &[("damping", 80.0)])), &law).unwrap();
        assert_eq!(p.name.as_str(), "impedance");
        assert_eq!(&p.values[..3], &[2000.0, 80.0, 0.0]);
        SPEC.check(&p).unwrap();
        assert_eq!(bind(Some(&table("impedance", &[])), &law).unwrap(), SPEC.defaults());
        assert_eq!(bind(None, &LawDescription::paper()).unwrap(), LawParams::PAPER);
    }

    #[test]
    fn every_misfit_is_refused_with_the_laws_declaration() {
        let law = LawDescription::of(&SPEC);
        let e = bind(Some(&table("impedance", &[("stifness", 1.0)])), &law).unwrap_err();
        assert_eq!(
            e.to_string(),
            "law `impedance` has no parameter `stifness`; it declares `stiffness` (N/m, [0, 5000]), `damping` (N s/m, [0, 500])"
        );
        let e = bind(Some(&table("impedance", &[("stiffness", 6000.0)])), &law).unwrap_err();
        assert_eq!(e.to_string(), "law `impedance`: `stiffness` = 6000 N/m is out of its range [0, 5000] N/m");
        assert!(matches!(bind(Some(&table("impedance", &[("damping", f64::NAN)])), &law), Err(LawError::OutOfRange { .. })));
        // f64 values that round into the range in f32 are the firmware's verdict too.
        assert!(bind(Some(&table("impedance", &[("damping", 500.000_000_001)])), &law).is_ok());
        for (t, runs) in [(Some(table("pid", &[])), &law), (None, &law), (Some(table("impedance", &[])), &LawDescription::paper())] {
            let e = bind(t.as_ref(), runs).unwrap_err();
            assert!(matches!(e, LawError::WrongLaw { .. }), "{e}");
        }
        let e = bind(Some(&table("impedance", &[])), &LawDescription::paper()).unwrap_err();
        assert!(
            e.to_string().starts_with(
                "the scenario asks for law `impedance`, the firmware runs the paper's laws (PID and hybrid): run the law's own firmware"
            ),
            "{e}"
        );
    }
}

#[cfg(test)]
mod scenario_tests {
    use crate::scenario::{DEFAULT_TOML, Scenario};

    /// A scenario file's `[law]` table reads into its name and parameters,
    /// writes back as it was read, and is checked for a name the firmware can
    /// hold and for numbers.
    #[test]
    fn a_scenarios_law_table_reads_writes_back_and_is_checked() {
        let s = Scenario::from_toml(&format!("{DEFAULT_TOML}\n[law]\nname = \"impedance\"\nstiffness = 1500.0\ndamping = 80\n")).unwrap();
        let law = s.law.as_ref().unwrap();
        assert_eq!((law.name.as_str(), law.params["stiffness"], law.params["damping"]), ("impedance", 1500.0, 80.0));
        let again = Scenario::from_toml(&toml::to_string(&s).unwrap()).unwrap();
        assert_eq!(again.law, s.law);
        assert!(!toml::to_string(&Scenario::default_scenario()).unwrap().contains("[law]"), "no table written for the paper's laws");
        for (table, key) in [("name = \"has space\"", "law.name"), ("name = \"\"", "law.name"), ("name = \"x\"\nk = nan", "law.k")] {
            let e = Scenario::from_toml(&format!("{DEFAULT_TOML}\n[law]\n{table}\n")).unwrap_err();
            assert!(e.to_string().contains(key), "{table}: {e}");
        }
        let e = Scenario::from_toml(&format!("{DEFAULT_TOML}\n[law]\nname = \"x\"\nk = \"stiff\"\n")).unwrap_err();
        assert!(e.to_string().contains("law"), "{e}");
    }
}
