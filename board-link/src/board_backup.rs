//! A board's configuration and calibration as a TOML file (`sil-host board backup
//! FILE` and `restore FILE`; docs/board.md "Backup and restore"), in the manner of
//! odrivetool's `backup-config` and `restore-config`.
//!
//! The file holds what the settings record in flash holds (`arm_app::record::Stored`):
//! the calibration (`arm_app::bringup::CalibrationRecord`: the encoders' zeros and
//! directions, the load cell's zeros and gains, the belt's scale, the bring-up steps
//! done) and the firmware's configuration (`firmware::Config`), read over the
//! bring-up protocol (`GetCalibration`, `GetConfig`). It is restored with one
//! request, `Restore`, which the firmware validates as it validates the record at
//! reset and takes whole or not at all. Floats are written so that they read back
//! to the same `f32` bits.
//!
//! Reading a file here checks its form: TOML, the format version, every key
//! known, present and of its type (the error names the key). [`validate`] then
//! checks its values with the firmware's own rules (`firmware::Config::validate`,
//! the runaway limits on, the encoders' zeros, `drivers::load_cell::Calibration::validate`,
//! `drivers::belt::scale`: the rules the scenario files' path calls too), and the
//! bring-up protocol it was made with, naming the key; the firmware checks them
//! again when it takes the file.

use std::path::Path;

use arm_app::{bringup::CalibrationRecord, record::Stored};
use firmware::Config;
use serde::{Deserialize, Serialize};

/// The file's format version (`format = 1`): a file of another version is refused.
pub const BACKUP_FORMAT: u32 = 1;

/// A backup file's content.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Backup {
    /// [`BACKUP_FORMAT`].
    pub format: u32,
    /// The bring-up protocol the board spoke (`arm_app::bringup::BRINGUP_PROTOCOL`),
    /// for the record: a restore needs the protocol of this sil-host.
    pub protocol: u16,
    /// The calibration in force when backed up.
    pub calibration: CalibrationRecord,
    /// The firmware configuration in force when backed up.
    pub config: Config,
}

impl Backup {
    /// The settings record's content (`Request::Restore`'s payload).
    pub fn stored(&self) -> Stored {
        Stored { calibration: self.calibration, config: self.config }
    }
}

/// Why a backup file was not read or written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BackupError {
    /// The file could not be read or written.
    #[error("{0}")]
    Io(String),
    /// Not TOML, a key unknown, missing or of the wrong type, or another format
    /// version: the message names the key.
    #[error("{0}")]
    Parse(String),
}

/// The file's text: a comment header, then [`Backup`] as TOML.
///
/// # Errors
/// [`BackupError::Parse`] when a value has no TOML form (never for a board's
/// settings: every float is finite after the firmware's checks, and a NaN is
/// written as `nan`).
pub fn to_toml(b: &Backup) -> Result<String, BackupError> {
    let body = toml::to_string(b).map_err(|e| BackupError::Parse(format!("the backup has no TOML form: {e}")))?;
    Ok(format!(
        "# A board's calibration and firmware configuration: `sil-host board backup`.\n\
         # Restore it with `sil-host board restore FILE` (docs/board.md \"Backup and restore\");\n\
         # the firmware checks every value and takes the file whole or not at all.\n\
         # Each setting's unit is a comment at the end of its line.\n{}",
        crate::setting_units::annotate_toml(&body)
    ))
}

/// Writes `b` to `path` whole (a temporary file renamed over it).
///
/// # Errors
/// [`BackupError::Io`] naming the path.
pub fn write(path: &Path, b: &Backup) -> Result<(), BackupError> {
    let text = to_toml(b)?;
    let tmp = path.with_extension("toml.partial");
    // Made new, never through a link left at its name.
    rig::private_files::write_new(&tmp, text.as_bytes())
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| BackupError::Io(format!("cannot write the backup {}: {e}", path.display())))
}

/// Reads a backup file's text.
///
/// # Errors
/// [`BackupError::Parse`]: not TOML, a key unknown, missing or of the wrong type
/// (named, with its path: `config.pid.kp`), another [`BACKUP_FORMAT`].
pub fn parse(text: &str) -> Result<Backup, BackupError> {
    let doc: toml::Table = text.parse().map_err(|e| BackupError::Parse(format!("not a TOML backup: {e}")))?;
    match doc.get("format") {
        Some(toml::Value::Integer(v)) if *v == i64::from(BACKUP_FORMAT) => {}
        Some(v) => {
            return Err(BackupError::Parse(format!(
                "backup format {v}: this sil-host reads format {BACKUP_FORMAT} (make the backup again with this version)"
            )));
        }
        None => return Err(BackupError::Parse("backup key `format` is missing: not a `sil-host board backup` file".into())),
    }
    let backup: Backup = serde_path_to_error::deserialize(toml::Value::Table(doc.clone())).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        let inner = inner.lines().next().unwrap_or_default();
        if path == "." {
            BackupError::Parse(format!("backup: {inner}"))
        } else {
            BackupError::Parse(format!("backup key `{path}`: {inner}"))
        }
    })?;
    // Keys the structures ignore (the nested ones have no deny_unknown_fields):
    // anything the canonical form lacks.
    let canonical = toml::Table::try_from(backup).map_err(|e| BackupError::Parse(e.to_string()))?;
    if let Some(key) = unknown_key(&doc, &canonical, "") {
        return Err(BackupError::Parse(format!("backup key `{key}`: unknown (a misspelt key, or a file of another version?)")));
    }
    Ok(backup)
}

/// Reads the backup file at `path`.
///
/// # Errors
/// [`BackupError::Io`] naming the path (a file that cannot be read, is not a
/// regular file or is over `tables::input::BACKUP`'s bound, 1 MiB), or
/// [`parse`]'s, with the path.
pub fn read(path: &Path) -> Result<Backup, BackupError> {
    let text = tables::input::read_to_string(path, tables::input::BACKUP).map_err(|e| BackupError::Io(e.to_string()))?;
    parse(&text).map_err(|e| BackupError::Parse(format!("{}: {e}", path.display())))
}

/// The first key of `doc` (dotted path) that `canonical` lacks.
fn unknown_key(doc: &toml::Table, canonical: &toml::Table, prefix: &str) -> Option<String> {
    for (k, v) in doc {
        let path = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
        match (v, canonical.get(k)) {
            (_, None) => return Some(path),
            (toml::Value::Table(d), Some(toml::Value::Table(c))) => {
                if let Some(p) = unknown_key(d, c, &path) {
                    return Some(p);
                }
            }
            _ => {}
        }
    }
    None
}

/// Checks `b` before it is sent, naming the key of the first value refused:
/// its `protocol` (a backup of another bring-up protocol is refused, both
/// named), its control period (one the image runs: `arm_app::rate`), then each value by the firmware's own rule, as the firmware checks
/// its flash record at reset and `Restore` (the configuration by
/// `firmware::Config::validate` and the runaway limits on, the encoders' zeros
/// below 2^14, the load cell's calibration by `drivers::load_cell::Calibration::validate`,
/// the belt's scale by `drivers::belt::scale` at the configuration's period).
///
/// # Errors
/// `"backup key `config.f_n_ref` = 100: ..."`, in words.
pub fn validate(b: &Backup) -> Result<(), String> {
    let protocol = arm_app::bringup::BRINGUP_PROTOCOL;
    if b.protocol != protocol {
        return Err(format!(
            "backup key `protocol` = {}: the backup was made with bring-up protocol {}, this sil-host speaks protocol {protocol} \
             (make the backup again with this version, or restore it with the sil-host of protocol {})",
            b.protocol, b.protocol, b.protocol
        ));
    }
    rig::board_protection::check_protection(&b.config, "backup key `config.runaway_limits`")?;
    // The rates the image runs (`arm_app::rate`), named by the file's key.
    if !arm_app::rate::supported(b.config.period) {
        return Err(format!(
            "backup key `config.period` = {}: the image runs control periods of {}",
            b.config.period.as_us(),
            arm_app::rate::RANGE_WORDS
        ));
    }
    match b.config.validate() {
        Ok(()) => {}
        Err(firmware::config::ConfigError::OutOfRange { name, value, expected }) => {
            return Err(format!("backup key `config.{name}` = {value}: out of range ({expected})"));
        }
        Err(firmware::config::ConfigError::Params(e)) => return Err(format!("backup key `config.params`: {e}")),
        Err(e) => return Err(format!("backup key `config`: {e}")),
    }
    let c = &b.calibration;
    for (i, z) in c.zero_counts.iter().enumerate() {
        if *z >= 1 << 14 {
            return Err(format!("backup key `calibration.zero_counts[{i}]` = {z}: must be below 16384 (14-bit encoder counts)"));
        }
    }
    let load = drivers::load_cell::Calibration { zero_counts: c.load_zero_counts, newtons_per_count: c.load_newtons_per_count };
    let key = |e: String| format!("backup key {e}");
    rig::calibration::check_load_cell(&load, "calibration.load_zero_counts", "calibration.load_newtons_per_count").map_err(key)?;
    rig::calibration::check_belt("calibration.belt_metres_per_count", c.belt_metres_per_count, b.config.period.as_secs_f32()).map_err(key)
}

/// Which of `b`'s values the firmware refuses, in words ([`validate`]'s
/// message), for the message of a refused restore. `None` when all pass.
pub fn explain_invalid(b: &Backup) -> Option<String> {
    validate(b).err()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn backup() -> Backup {
        let cal = rig::calibration::CalibrationSection::default().arm_calibration();
        Backup {
            format: BACKUP_FORMAT,
            protocol: arm_app::bringup::BRINGUP_PROTOCOL,
            calibration: CalibrationRecord::brought_up(&cal),
            config: Config::default(),
        }
    }

    #[test]
    fn every_f32_reads_back_to_its_bits_and_a_bad_file_is_named() {
        let mut b = backup();
        // Values with no short decimal form, a subnormal, the largest f32.
        b.calibration.load_newtons_per_count = [f32::from_bits(0x3C48_0001), -f32::MIN_POSITIVE / 3.0];
        b.calibration.belt_metres_per_count = f32::MAX;
        b.config.target_z_t = 0.1 + f32::EPSILON;
        let text = to_toml(&b).unwrap();
        let back = parse(&text).unwrap();
        assert_eq!(back, b);
        assert_eq!(back.calibration.load_newtons_per_count.map(f32::to_bits), b.calibration.load_newtons_per_count.map(f32::to_bits));

        let err = |t: &str| parse(t).unwrap_err().to_string();
        assert!(err("format = 2").contains("backup format 2"), "{}", err("format = 2"));
        assert!(err("protocol = 5").contains("`format` is missing"));
        assert!(err("[[x").contains("not a TOML backup"));
        let e = err(&text.replace("[config.hybrid]", "[config.hybrid]\nkx = 1.0"));
        assert!(e.contains("`config.hybrid.kx`: unknown"), "{e}");
        let e = err(&text.replace("tared = true", "tared = 1"));
        assert!(e.contains("`calibration.tared`"), "{e}");
        let e = err(&text.replace("controller = \"hybrid\"", "controller = \"lqr\""));
        assert!(e.contains("`config.controller`"), "{e}");
    }

    #[test]
    fn the_firmware_s_checks_are_named_by_their_keys() {
        assert_eq!(validate(&backup()), Ok(()));
        let refused = |f: &dyn Fn(&mut Backup)| {
            let mut b = backup();
            f(&mut b);
            validate(&b).unwrap_err()
        };
        let e = refused(&|b| b.config.torque_limit = 50.0);
        assert!(e.contains("`config.torque_limit` = 50"), "{e}");
        let e = refused(&|b| b.calibration.zero_counts[1] = 16384);
        assert!(e.contains("`calibration.zero_counts[1]` = 16384"), "{e}");
        let e = refused(&|b| b.calibration.load_zero_counts[0] = f32::NAN);
        assert!(e.contains("`calibration.load_zero_counts[0]` = NaN"), "{e}");
        let e = refused(&|b| b.calibration.belt_metres_per_count = 0.0);
        assert!(e.contains("`calibration.belt_metres_per_count` = 0"), "{e}");
        // Issue 52: what the scenario path refused, a backup took.
        let e = refused(&|b| b.config.f_n_ref = 100.0);
        assert!(e.contains("`config.f_n_ref` = 100") && e.contains("[0, 20] N"), "{e}");
        let e = refused(&|b| b.calibration.load_newtons_per_count[0] = 1e-45);
        assert!(e.contains("`calibration.load_newtons_per_count[0]` = 1e-45") && e.contains("factor 4"), "{e}");
        let e = refused(&|b| b.calibration.load_newtons_per_count[1] = -0.012);
        assert!(e.contains("`calibration.load_newtons_per_count[1]` = -1.2e-2") && e.contains("positive"), "{e}");
        let e = refused(&|b| b.config.runaway_limits = false);
        assert!(e.contains("`config.runaway_limits` = false") && e.contains("cannot be turned off on a board"), "{e}");
        // Issue 56: a period the image does not run, named with the range; one
        // of 0 us (a corrupt file: no `Period` has it) read and refused too.
        for us in [99, 4001, 1_000_000] {
            let e = refused(&|b| b.config.period = shared::time::Period::from_us(us).unwrap());
            assert!(e.contains(&format!("`config.period` = {us}")) && e.contains("100 to 4000 us"), "{e}");
        }
        let text = to_toml(&backup()).unwrap();
        assert!(text.contains("period = 1000"), "{text}");
        let zero = parse(&text.replace("period = 1000", "period = 0")).unwrap();
        let e = validate(&zero).unwrap_err();
        assert!(e.contains("`config.period` = 0") && e.contains("100 to 4000 us"), "{e}");
        assert!(parse(&text.replace("period = 1000", "period = -5")).unwrap_err().to_string().contains("config.period"));
        let e = refused(&|b| b.protocol = 5);
        assert!(e.contains("protocol 5") && e.contains(&format!("protocol {}", arm_app::bringup::BRINGUP_PROTOCOL)), "{e}");
    }
}
