//! The unit of each setting a board holds, by its dotted key as `configure`
//! echoes it and a backup file writes it (`config.f_n_ref`,
//! `calibration.belt_metres_per_count`): issue 69, "configure's echo and the
//! backup file carry no units". The units are the fields' own, as their
//! definitions document them: `firmware::Config` (firmware/src/config.rs),
//! `shared::Params` (paper Table I, SI, angles in radians) and
//! `arm_app::record::CalibrationRecord`.

/// `(key, unit)`: every numeric setting with a unit; counts of periods say so;
/// dimensionless settings (`mu`) and flags are absent.
const UNITS: &[(&str, &str)] = &[
    ("config.params.m", "kg"),
    ("config.params.l", "m"),
    ("config.params.sigma", "N m s/rad"),
    ("config.params.k", "N m/rad"),
    ("config.params.h", "m"),
    ("config.params.alpha0", "rad"),
    ("config.params.g", "m/s^2"),
    ("config.params.v_belt", "m/s"),
    ("config.period", "us"),
    ("config.target_z_t", "m"),
    ("config.move_time_s", "s"),
    ("config.f_n_ref", "N"),
    ("config.force_ramp_s", "s"),
    ("config.pid.kp", "N m/rad"),
    ("config.pid.ki", "N m/(rad s)"),
    ("config.pid.kd", "N m s/rad"),
    ("config.hybrid.kp", "1/s^2"),
    ("config.hybrid.kd", "1/s"),
    ("config.hybrid.ki", "1/s"),
    ("config.torque_limit", "N m"),
    ("config.observer_bandwidth", "rad/s"),
    ("config.lift_off_force", "N"),
    ("config.lift_off_height", "m"),
    ("config.lift_off_confirm", "periods"),
    ("config.touchdown_force", "N"),
    ("config.sensor_contact_force", "N"),
    ("config.sensor_height_tolerance", "m"),
    ("config.sensor_fault_confirm", "periods"),
    ("config.innovation_threshold", "rad"),
    ("config.innovation_confirm", "periods"),
    ("config.innovation_settle", "periods"),
    ("config.deadline_miss_limit", "periods"),
    ("config.bad_frame_limit", "periods"),
    ("config.encoder_bits", "bits per revolution"),
    // A law of one's own's parameters, each in the unit its declaration gives
    // (`firmware::LawSpec`; issue 70).
    ("config.law.values", "the law's declared units"),
    ("calibration.zero_counts", "encoder counts"),
    ("calibration.load_zero_counts", "ADC counts"),
    ("calibration.load_newtons_per_count", "N per ADC count"),
    ("calibration.belt_metres_per_count", "m per count"),
];

/// The unit of the setting at dotted `key` (`config.f_n_ref`: `N`), or `None`
/// for a dimensionless one, a flag or a choice.
pub fn unit_of(key: &str) -> Option<&'static str> {
    UNITS.iter().find(|(k, _)| *k == key).map(|(_, u)| *u)
}

/// `toml` (a backup file's text: tables `[calibration]`, `[config]`,
/// `[config.pid]`, ...) with each setting's unit as a comment at the end of its
/// line (`f_n_ref = 10.0  # N`); other lines as they are. The values are
/// untouched, so the file reads back the same.
pub fn annotate_toml(toml: &str) -> String {
    let mut table = String::new();
    let mut out = String::with_capacity(toml.len() + toml.len() / 4);
    for line in toml.lines() {
        let trimmed = line.trim();
        if let Some(name) = trimmed.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            table = name.trim().to_string();
        } else if let Some((key, _)) = trimmed.split_once('=').filter(|_| !trimmed.starts_with('#')) {
            let dotted = if table.is_empty() { key.trim().to_string() } else { format!("{table}.{}", key.trim()) };
            if let Some(unit) = unit_of(&dotted) {
                out.push_str(line);
                out.push_str("  # ");
                out.push_str(unit);
                out.push('\n');
                continue;
            }
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every numeric leaf of a configuration and a calibration has a unit or is
    /// one of the dimensionless ones; no unit names a key that does not exist.
    #[test]
    fn every_numeric_setting_has_its_unit_and_every_unit_a_setting() {
        let config = toml::Value::try_from(firmware::Config::default()).unwrap();
        let arm = rig::calibration::CalibrationSection::default().arm_calibration();
        let cal = toml::Value::try_from(arm_app::record::CalibrationRecord::uncalibrated(&arm)).unwrap();
        let mut leaves = Vec::new();
        fn walk(prefix: &str, v: &toml::Value, out: &mut Vec<(String, bool)>) {
            let number = |x: &toml::Value| x.is_float() || x.is_integer();
            match v {
                toml::Value::Table(m) => m.iter().for_each(|(k, v)| walk(&format!("{prefix}.{k}"), v, out)),
                toml::Value::Array(a) => out.push((prefix.to_string(), a.iter().all(number))),
                v => out.push((prefix.to_string(), number(v))),
            }
        }
        walk("config", &config, &mut leaves);
        walk("calibration", &cal, &mut leaves);
        let dimensionless = ["config.params.mu"];
        for (key, numeric) in &leaves {
            if *numeric && !dimensionless.contains(&key.as_str()) {
                assert!(unit_of(key).is_some(), "{key} has no unit");
            }
        }
        for (key, _) in UNITS {
            assert!(leaves.iter().any(|(k, _)| k == key), "{key} is not a setting");
        }
    }

    /// The annotated text reads back to the same values, each unit after its line.
    #[test]
    fn annotated_toml_reads_back_the_same() {
        let text = "format = 1\n[config]\nf_n_ref = 10.0\nrunaway_limits = true\n[config.pid]\nkp = [200.0, 0.0]\n";
        let a = annotate_toml(text);
        assert!(a.contains("f_n_ref = 10.0  # N\n") && a.contains("kp = [200.0, 0.0]  # N m/rad\n"), "{a}");
        assert!(a.contains("runaway_limits = true\n") && a.contains("format = 1\n"), "{a}");
        let (x, y): (toml::Table, toml::Table) = (text.parse().unwrap(), a.parse().unwrap());
        assert_eq!(x, y);
    }
}
