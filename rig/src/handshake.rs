//! The handshake before period 0 (docs/rig.md "Handshake"): the firmware
//! announces the configuration it will run (`firmware::announce`), the plant
//! compares it, field by field, with the one its scenario asks for
//! ([`crate::setup::firmware_config`]) and refuses any difference, so a firmware
//! started by hand with other settings (`sil-host firmware --controller pid`
//! under a hybrid plant) is never run against a plant that believes otherwise.
//! `summary.json` records the firmware's own announcement.

use firmware::{
    Config, LawSpec,
    announce::{configuration, law_bytes},
};
use serde::Serialize;
use shared::wire::FirmwareAnnouncement;

use crate::law::{LawDescription, LawError, LawTable, bind};

/// The firmware's announcement as the run records it (`firmware_announcement` in
/// `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Announced {
    /// `shared::wire::WIRE_VERSION` of the firmware's build.
    pub wire_version: u32,
    /// CRC-64/XZ of the encoded configuration, 16 hex digits.
    pub config_hash: String,
    /// The configuration the firmware runs.
    pub config: Config,
    /// What its law declares (left out for the paper's laws).
    #[serde(skip_serializing_if = "LawDescription::is_paper")]
    pub law: LawDescription,
}

/// Why the plant refuses the firmware at the handshake (exit 2 from `sil-host run`).
#[derive(Debug, thiserror::Error)]
pub enum HandshakeError {
    /// The announcement cannot be read: another wire version, or a configuration
    /// this build cannot decode.
    #[error("handshake: {0}")]
    Announcement(#[from] firmware::announce::AnnounceError),
    /// The scenario's `[law]` table does not fit the law the firmware declares.
    #[error("handshake: {0}")]
    Law(#[from] LawError),
    /// The firmware runs another configuration than the scenario asks for: every
    /// differing setting.
    #[error(
        "the firmware on rig `{rig}` is configured differently from this scenario: {}; start it with the same scenario and flags",
        differences.iter().map(ToString::to_string).collect::<Vec<_>>().join("; ")
    )]
    ConfigMismatch {
        /// The rig name.
        rig: String,
        /// What differs.
        differences: Vec<Difference>,
    },
}

/// One setting on which the firmware and the scenario differ.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Difference {
    /// The setting's path in `firmware::Config` (`controller`, `hybrid.kp`, `params.mu`, ...).
    pub field: String,
    /// The firmware's value (JSON).
    pub firmware: String,
    /// The scenario's value (JSON).
    pub scenario: String,
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: firmware {}, scenario {}", self.field, self.firmware, self.scenario)
    }
}

/// Every setting on which `firmware` differs from `scenario`, in `Config`'s field
/// order (nested fields by their dotted path, arrays compared whole).
pub fn differences(firmware: &Config, scenario: &Config) -> Vec<Difference> {
    fn walk(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<Difference>) {
        use serde_json::Value::Object;
        match (a, b) {
            (Object(x), Object(y)) => {
                for (key, va) in x {
                    let sub = if path.is_empty() { key.clone() } else { format!("{path}.{key}") };
                    walk(&sub, va, y.get(key).unwrap_or(&serde_json::Value::Null), out);
                }
            }
            _ if a != b => out.push(Difference { field: path.to_string(), firmware: a.to_string(), scenario: b.to_string() }),
            _ => {}
        }
    }
    // serde_json keeps Config's field order (feature preserve_order) or sorts it:
    // either way both sides walk the same keys.
    let value = |c: &Config| serde_json::to_value(c).unwrap_or(serde_json::Value::Null);
    let mut out = Vec::new();
    walk("", &value(firmware), &value(scenario), &mut out);
    out
}

/// Checks the firmware's announcement against the configuration a scenario
/// asks for: `scenario` (`crate::setup::RunSetup::firmware`) with its `[law]`
/// table `law` bound to the law's announced declaration first
/// ([`crate::law::bind`]), then field by field.
///
/// # Errors
/// [`HandshakeError::Announcement`] for another wire version or an undecodable
/// configuration; [`HandshakeError::Law`] for an undecodable declaration or a
/// `[law]` table that does not fit it; [`HandshakeError::ConfigMismatch`]
/// naming every differing setting.
pub fn check(
    announcement: &FirmwareAnnouncement,
    scenario: &Config,
    law: Option<&LawTable>,
    rig: &str,
) -> Result<Announced, HandshakeError> {
    let config = configuration(announcement)?;
    let declared = LawDescription::decode(law_bytes(announcement)?)?;
    let scenario = Config { law: bind(law, &declared)?, ..*scenario };
    check_config(announcement, config, declared, &scenario, rig)
}

/// `differences` with a difference of `law.values` (the law's parameter slots) told
/// per declared parameter of `law`, by name and with its unit: `law.k_t: firmware
/// 2000 N/m, scenario 8000 N/m`. A difference only in undeclared slots (a build that
/// fills them) stays as the raw slots.
fn named_law_values(mut differences: Vec<Difference>, firmware: &Config, scenario: &Config, law: &LawDescription) -> Vec<Difference> {
    let Some(at) = differences.iter().position(|d| d.field == "law.values") else { return differences };
    let (a, b) = (&firmware.law.values, &scenario.law.values);
    let named: Vec<Difference> = law
        .params
        .iter()
        .zip(a.iter().zip(b))
        .filter(|(_, (x, y))| x.to_bits() != y.to_bits())
        .map(|(p, (x, y))| Difference {
            field: format!("law.{}", p.name),
            firmware: format!("{x} {}", p.unit),
            scenario: format!("{y} {}", p.unit),
        })
        .collect();
    let undeclared = a.iter().zip(b).skip(law.params.len()).any(|(x, y)| x.to_bits() != y.to_bits());
    if !named.is_empty() && !undeclared {
        differences.splice(at..=at, named);
    }
    differences
}

/// [`check`] once the scenario's configuration is bound: compares and records.
fn check_config(
    a: &FirmwareAnnouncement,
    config: Config,
    law: LawDescription,
    scenario: &Config,
    rig: &str,
) -> Result<Announced, HandshakeError> {
    let differences = named_law_values(differences(&config, scenario), &config, scenario, &law);
    if !differences.is_empty() {
        return Err(HandshakeError::ConfigMismatch { rig: rig.to_string(), differences });
    }
    Ok(Announced { wire_version: a.wire_version, config_hash: format!("{:016x}", a.config_hash), config, law })
}

/// The announcement of a firmware linked in (in-process runs): its own
/// configuration, run by the law that declares `law`.
///
/// # Errors
/// [`HandshakeError::Announcement`] if the configuration or the declaration
/// does not fit the message (a build error).
pub fn of_config(config: &Config, law: &LawSpec) -> Result<Announced, HandshakeError> {
    firmware::announce::announce(config, law)?;
    of_described(config, LawDescription::of(law))
}

/// [`of_config`] for a law known by its declaration (an MCU image's,
/// [`LawDescription::from_elf`]).
///
/// # Errors
/// As [`of_config`] (for the configuration).
pub fn of_described(config: &Config, law: LawDescription) -> Result<Announced, HandshakeError> {
    let a = firmware::announce::announce(config, &LawSpec::PAPER)?;
    Ok(Announced { wire_version: a.wire_version, config_hash: format!("{:016x}", a.config_hash), config: *config, law })
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::{
        ControllerKind,
        announce::{AnnounceError, announce as announce_law},
        config::HybridGains,
    };

    fn announce(c: &Config) -> Result<FirmwareAnnouncement, AnnounceError> {
        announce_law(c, &LawSpec::PAPER)
    }

    /// [`check`] against a configuration rather than a run's setup.
    fn check(a: &FirmwareAnnouncement, scenario: &Config, rig: &str) -> Result<Announced, HandshakeError> {
        let config = configuration(a)?;
        let law = LawDescription::decode(law_bytes(a)?)?;
        check_config(a, config, law, scenario, rig)
    }

    const IMPEDANCE: LawSpec = LawSpec {
        name: "impedance",
        source: "Hogan 1985",
        params: &[firmware::ParamSpec { name: "stiffness", unit: "N/m", min: 0.0, max: 5000.0, default: 2000.0 }],
    };

    /// A law's firmware announces its declaration; the plant binds the
    /// scenario's `[law]` table with it and compares; a table that does not fit
    /// is refused at the handshake with the law's declaration.
    #[test]
    fn a_laws_declaration_binds_the_scenarios_table_at_the_handshake() {
        let mut s = crate::scenario::Scenario::default_scenario();
        s.law = Some(crate::law::LawTable { name: "impedance".into(), params: [("stiffness".to_string(), 1500.0)].into() });
        let setup = crate::setup::RunSetup::new(s.clone()).unwrap();
        let mut fw = *setup.firmware();
        fw.law.values[0] = 1500.0;
        let a = announce_law(&fw, &IMPEDANCE).unwrap();
        let ok = super::check(&a, setup.firmware(), setup.scenario().law.as_ref(), "r").unwrap();
        assert_eq!((ok.config.law.values[0], ok.law.name.as_str()), (1500.0, "impedance"));
        // Another value on the firmware's side is a difference of that parameter,
        // named with its unit (issue 84: not the raw slots of `law.values`).
        let mut other = fw;
        other.law.values[0] = 1000.0;
        let e = super::check(&announce_law(&other, &IMPEDANCE).unwrap(), setup.firmware(), setup.scenario().law.as_ref(), "r").unwrap_err();
        assert!(
            matches!(&e, HandshakeError::ConfigMismatch { differences, .. } if differences.len() == 1 && differences[0].field == "law.stiffness"),
            "{e}"
        );
        assert!(e.to_string().contains("law.stiffness: firmware 1000 N/m, scenario 1500 N/m"), "{e}");
        // An undeclared parameter, or the paper's firmware, is refused before any comparison.
        s.law.as_mut().unwrap().params.insert("damping".into(), 1.0);
        let e = super::check(&a, setup.firmware(), s.law.as_ref(), "r").unwrap_err();
        assert!(e.to_string().contains("has no parameter `damping`"), "{e}");
        let e = super::check(&announce(&Config::default()).unwrap(), setup.firmware(), setup.scenario().law.as_ref(), "r").unwrap_err();
        assert!(matches!(e, HandshakeError::Law(LawError::WrongLaw { .. })), "{e}");
    }

    #[test]
    fn the_same_configuration_passes_and_is_recorded() {
        let c = Config::default();
        let a = check(&announce(&c).unwrap(), &c, "r").unwrap();
        assert_eq!(a.config, c);
        assert_eq!(a.config_hash.len(), 16);
        assert_eq!(a, of_config(&c, &LawSpec::PAPER).unwrap());
    }

    #[test]
    fn every_differing_setting_is_named_with_both_values() {
        let scenario = Config::default();
        let mut fw = Config { controller: ControllerKind::Pid, target_z_t: 0.05, ..scenario };
        fw.hybrid = HybridGains { kp: 800.0, ..scenario.hybrid };
        fw.params.mu = 0.3;
        fw.pid.kp[1] = 1.0;
        let Err(HandshakeError::ConfigMismatch { differences, rig }) = check(&announce(&fw).unwrap(), &scenario, "lab") else {
            panic!("a mismatch passed");
        };
        assert_eq!(rig, "lab");
        let mut fields: Vec<_> = differences.iter().map(|d| d.field.as_str()).collect();
        fields.sort_unstable();
        assert_eq!(fields, ["controller", "hybrid.kp", "params.mu", "pid.kp", "target_z_t"]);
        let controller = differences.iter().find(|d| d.field == "controller").unwrap();
        assert_eq!((controller.firmware.as_str(), controller.scenario.as_str()), ("\"pid\"", "\"hybrid\""));
        // Each single change is found alone (no false differences).
        assert_eq!(super::differences(&Config { move_time_s: 1.0, ..scenario }, &scenario).len(), 1);
    }

    #[test]
    fn another_wire_version_is_refused_before_the_configuration_is_read() {
        let mut a = announce(&Config::default()).unwrap();
        a.wire_version += 1;
        let e = check(&a, &Config::default(), "r").unwrap_err();
        assert!(matches!(e, HandshakeError::Announcement(AnnounceError::WireVersion { .. })), "{e}");
    }
}
