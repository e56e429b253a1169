//! The firmware's announcement of its configuration (the SIL rig's handshake
//! before period 0, docs/rig.md "Handshake"): its [`Config`] in postcard's
//! encoding inside a fixed-size [`FirmwareAnnouncement`], the CRC-64 that
//! names it, and its law's declaration ([`LawSpec`], postcard). The plant maps
//! its scenario's `[law]` table with the declaration, then compares the
//! configuration, field by field, with the one its scenario asks for. No heap:
//! the encodings go into the message's own buffers.

use crc::{CRC_64_XZ, Crc};
use shared::wire::{FirmwareAnnouncement, WIRE_VERSION};

use crate::{config::Config, law_spec::LawSpec};

const CRC64: Crc<u64> = Crc::<u64>::new(&CRC_64_XZ);

/// Why an announcement cannot be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum AnnounceError {
    /// The firmware speaks another wire version (another build's layouts).
    #[error("the firmware speaks wire version {firmware}, this plant {plant}: rebuild both from the same sources")]
    WireVersion {
        /// The firmware's version.
        firmware: u32,
        /// This build's [`WIRE_VERSION`].
        plant: u32,
    },
    /// The configuration does not decode, or its hash does not match its bytes
    /// (a firmware built with another `Config` layout, or a corrupted message).
    #[error("the firmware's configuration cannot be decoded ({0}): rebuild both sides from the same sources")]
    Undecodable(&'static str),
    /// The configuration does not fit the message (a build error: `Config` grew).
    #[error("the configuration does not fit the announcement's {0} bytes")]
    TooLong(usize),
    /// The law's declaration does not fit the message (names and units too long).
    #[error("the law's declaration does not fit the announcement's {0} bytes: shorten its parameters' names and units")]
    LawTooLong(usize),
}

/// The CRC-64/XZ of `bytes` (the announcement's `config_hash`).
pub fn config_hash(bytes: &[u8]) -> u64 {
    CRC64.checksum(bytes)
}

/// The announcement of `config`, run by the law that declares `law`, at this
/// build's [`WIRE_VERSION`].
///
/// # Errors
/// [`AnnounceError::TooLong`] if the configuration's encoding exceeds the
/// message's buffer (`shared::wire::ANNOUNCEMENT_CONFIG_BYTES`; a test pins the
/// margin), [`AnnounceError::LawTooLong`] if the law's does
/// (`shared::wire::ANNOUNCEMENT_LAW_BYTES`).
pub fn announce(config: &Config, law: &LawSpec) -> Result<FirmwareAnnouncement, AnnounceError> {
    let mut a = FirmwareAnnouncement::default();
    let len = postcard::to_slice(config, &mut a.config).map_err(|_| AnnounceError::TooLong(shared::wire::ANNOUNCEMENT_CONFIG_BYTES))?.len();
    a.config_len = len as u32;
    a.config_hash = config_hash(&a.config[..len]);
    a.law_len = law.encode(&mut a.law).ok_or(AnnounceError::LawTooLong(shared::wire::ANNOUNCEMENT_LAW_BYTES))?.len() as u32;
    Ok(a)
}

/// The law's encoded declaration an announcement carries (postcard's
/// encoding of a [`LawSpec`]; the host decodes it into owned strings).
///
/// # Errors
/// [`AnnounceError::Undecodable`] when its length runs past the buffer.
pub fn law_bytes(a: &FirmwareAnnouncement) -> Result<&[u8], AnnounceError> {
    a.law.get(..a.law_len as usize).ok_or(AnnounceError::Undecodable("the law's length beyond the buffer"))
}

/// The configuration an announcement carries.
///
/// # Errors
/// [`AnnounceError::WireVersion`] for another wire version (checked first: the
/// rest of the message is then not trusted), [`AnnounceError::Undecodable`]
/// when the bytes do not match their hash or do not decode to exactly one
/// [`Config`].
pub fn configuration(a: &FirmwareAnnouncement) -> Result<Config, AnnounceError> {
    if a.wire_version != WIRE_VERSION {
        return Err(AnnounceError::WireVersion { firmware: a.wire_version, plant: WIRE_VERSION });
    }
    let len = a.config_len as usize;
    let bytes = a.config.get(..len).ok_or(AnnounceError::Undecodable("length beyond the buffer"))?;
    if config_hash(bytes) != a.config_hash {
        return Err(AnnounceError::Undecodable("hash mismatch"));
    }
    match postcard::take_from_bytes::<Config>(bytes) {
        Ok((c, [])) => Ok(c),
        Ok(_) => Err(AnnounceError::Undecodable("bytes left over")),
        Err(_) => Err(AnnounceError::Undecodable("not a configuration of this build")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{ControllerKind, HybridGains};

    #[test]
    fn announcement_round_trips_and_fits_with_margin() {
        for controller in [ControllerKind::Pid, ControllerKind::Hybrid] {
            let c = Config { controller, branch: Some(shared::ElbowBranch::Up), ..Config::default() };
            let a = announce(&c, &LawSpec::PAPER).unwrap();
            assert_eq!(configuration(&a).unwrap(), c);
            // Room to grow: a Config twice as long still fits.
            assert!(2 * a.config_len as usize <= a.config.len(), "{} bytes", a.config_len);
        }
    }

    #[test]
    fn a_changed_setting_changes_the_hash_and_a_corrupted_byte_is_refused() {
        let a = announce(&Config::default(), &LawSpec::PAPER).unwrap();
        let b = announce(&Config { hybrid: HybridGains { kp: 901.0, ..Config::default().hybrid }, ..Config::default() }, &LawSpec::PAPER)
            .unwrap();
        assert_ne!(a.config_hash, b.config_hash);
        for i in 0..a.config_len as usize {
            let mut bad = a;
            bad.config[i] ^= 0x10;
            assert_eq!(configuration(&bad), Err(AnnounceError::Undecodable("hash mismatch")), "byte {i}");
        }
        let mut long = a;
        long.config_len = 10_000;
        assert!(configuration(&long).is_err());
    }

    #[test]
    fn another_wire_version_is_refused_first() {
        let mut a = announce(&Config::default(), &LawSpec::PAPER).unwrap();
        a.wire_version = WIRE_VERSION + 1;
        a.config_hash ^= 1;
        assert_eq!(configuration(&a), Err(AnnounceError::WireVersion { firmware: WIRE_VERSION + 1, plant: WIRE_VERSION }));
    }
}
