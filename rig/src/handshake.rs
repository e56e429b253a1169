//! The handshake before period 0 (docs/rig.md "Handshake"): the firmware
//! announces the configuration it will run (`firmware::announce`), the plant
//! compares it, field by field, with the one its scenario asks for
//! ([`crate::setup::firmware_config`]) and refuses any difference, so a firmware
//! started by hand with other settings (`sil-host firmware --controller pid`
//! under a hybrid plant) is never run against a plant that believes otherwise.
//! `summary.json` records the firmware's own announcement.

use firmware::{Config, announce::configuration};
use serde::Serialize;
use shared::wire::FirmwareAnnouncement;

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
}

/// Why the plant refuses the firmware at the handshake (exit 2 from `sil-host run`).
#[derive(Debug, thiserror::Error)]
pub enum HandshakeError {
    /// The announcement cannot be read: another wire version, or a configuration
    /// this build cannot decode.
    #[error("handshake: {0}")]
    Announcement(#[from] firmware::announce::AnnounceError),
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

/// Checks the firmware's announcement against the configuration the scenario
/// asks for.
///
/// # Errors
/// [`HandshakeError::Announcement`] for another wire version or an undecodable
/// configuration; [`HandshakeError::ConfigMismatch`] naming every differing setting.
pub fn check(announcement: &FirmwareAnnouncement, scenario: &Config, rig: &str) -> Result<Announced, HandshakeError> {
    let config = configuration(announcement)?;
    let differences = differences(&config, scenario);
    if !differences.is_empty() {
        return Err(HandshakeError::ConfigMismatch { rig: rig.to_string(), differences });
    }
    Ok(Announced { wire_version: announcement.wire_version, config_hash: format!("{:016x}", announcement.config_hash), config })
}

/// The announcement of a firmware linked in (in-process runs): its own configuration.
///
/// # Errors
/// [`HandshakeError::Announcement`] if the configuration does not fit the message (a build error).
pub fn of_config(config: &Config) -> Result<Announced, HandshakeError> {
    let a = firmware::announce::announce(config)?;
    Ok(Announced { wire_version: a.wire_version, config_hash: format!("{:016x}", a.config_hash), config: *config })
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::{
        ControllerKind,
        announce::{AnnounceError, announce},
        config::HybridGains,
    };

    #[test]
    fn the_same_configuration_passes_and_is_recorded() {
        let c = Config::default();
        let a = check(&announce(&c).unwrap(), &c, "r").unwrap();
        assert_eq!(a.config, c);
        assert_eq!(a.config_hash.len(), 16);
        assert_eq!(a, of_config(&c).unwrap());
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
