//! A closed-loop experiment's scenario as the fronts give it: a TOML file (or
//! standard input, or the embedded default) with `--set` overrides, then the
//! flags of [`ScenarioArgs`]; a key is set in one place only.

use crate::{error::Error, settings::ScenarioArgs};
use rig::{
    overrides::{self, Override},
    scenario::Scenario,
};

/// Reads a scenario (`path`; `-` is standard input; `None`: the embedded
/// default) with the `--set` overrides applied to its TOML document.
///
/// # Errors
/// [`crate::error::Error::BadInput`] for a file that cannot be read, is not a regular
/// file or is over [`tables::input::SCENARIO`]'s bound (standard input too);
/// [`crate::error::Error::Analysis`] naming the key (exit 2).
pub fn read_scenario(path: Option<&std::path::Path>, set: &[Override]) -> Result<Scenario, Error> {
    let text = match path {
        // Standard input, bounded as a file is (`cat /dev/zero | ... --scenario -`).
        Some(path) if path.as_os_str() == "-" => {
            tables::input::read_stream_to_string(std::io::stdin(), std::path::Path::new("standard input"), tables::input::SCENARIO)?
        }
        Some(path) => tables::input::read_to_string(path, tables::input::SCENARIO)?,
        None => return Ok(Scenario::from_toml_with(rig::scenario::DEFAULT_TOML, set)?),
    };
    Ok(Scenario::from_toml_with(&text, set)?)
}

/// Loads the scenario with the `--set` overrides and the flags applied to its
/// TOML document before it is read and validated, the flags as overrides of
/// their keys (`--duration 15` is `timing.duration_s = 15.0`), so a flag acts as
/// the `--set` of its key does: a file's fault past its own `duration_s` is
/// reached by `--duration` as by `--set timing.duration_s` (issue 66). `--seed`
/// is set after the read (any `u64`, which a TOML integer cannot hold; no check
/// depends on it). A key set both by a flag and by `--set` is refused (exit 2):
/// a key is set in one place.
///
/// # Errors
/// [`crate::error::Error::Analysis`] (exit 2) naming the key.
pub fn load_scenario(args: &ScenarioArgs) -> Result<Scenario, Error> {
    let flags = [
        ("controller.kind", "--controller", args.controller.is_some()),
        ("plant.x0", "--x0", args.x0.is_some()),
        ("controller.target_z_t", "--target-zt", args.target_zt.is_some()),
        ("timing.duration_s", "--duration", args.duration.is_some()),
        ("sensors.seed", "--seed", args.seed.is_some()),
        ("plant.iwc", "--iwc", args.iwc.is_some()),
    ];
    let given: Vec<(&str, &str)> = flags.iter().filter(|f| f.2).map(|f| (f.0, f.1)).collect();
    overrides::check_keys(&args.set, &given).map_err(rig::scenario::ScenarioError::from)?;
    let mut set = args.set.clone();
    set.extend(flag_override("controller.kind", args.controller)?);
    set.extend(flag_override("plant.x0", args.x0)?);
    set.extend(flag_override("controller.target_z_t", args.target_zt)?);
    set.extend(flag_override("timing.duration_s", args.duration)?);
    set.extend(flag_override("plant.iwc", args.iwc)?);
    let mut s = read_scenario(args.scenario.as_deref(), &set)?;
    if let Some(seed) = args.seed {
        s.sensors.seed = seed;
        s.validate()?;
    }
    Ok(s)
}

/// The override of `key` a flag's `value` makes (`None` when the flag is not
/// given): the value as the scenario file writes it.
///
/// # Errors
/// [`crate::error::Error::Analysis`] (exit 2) if the value has no TOML form (none known).
fn flag_override<T: serde::Serialize>(key: &str, value: Option<T>) -> Result<Option<Override>, Error> {
    let Some(value) = value else { return Ok(None) };
    let value = toml::Value::try_from(value).map_err(|e| Error::bad_input(format!("{key}: {e}")))?;
    let text = value.to_string();
    Ok(Some(Override { key: key.into(), value, text }))
}

/// The scenario tables that describe a board: its devices (`[board]`, the board
/// twin's and the emulated board's physical truth) and the firmware's calibration
/// of them (`[calibration]`). Only a run with a board reads them (`run --link
/// twin`, `run --link emulator`, `board-twin`); elsewhere they do nothing.
pub const BOARD_TABLES: [&str; 2] = ["board", "calibration"];

/// Refuses the `--set` overrides of a board table (`board.*`, `calibration.*`,
/// [`BOARD_TABLES`]) where they would do nothing: `on` says what runs instead of
/// a board (`the in-process link`, `a sweep`).
///
/// # Errors
/// [`Error`] (bad input, exit 2) naming the first such key.
pub fn refuse_board_overrides(set: &[Override], on: &str) -> Result<(), Error> {
    match set.iter().find(|o| BOARD_TABLES.iter().any(|t| o.key.split('.').next() == Some(t))) {
        Some(o) => Err(Error::bad_input(format!(
            "--set {}: `{}` describes a board and does nothing on {on}: only the runs of `sil-host run` \
             on the twin or emulator link have a board",
            o.key, o.key
        ))),
        None => Ok(()),
    }
}

/// A warning when the scenario's board tables ([`BOARD_TABLES`], from its file)
/// differ from the reference board's but `on` has no board: they are checked and
/// then ignored. `None` when they are the reference board's.
pub fn board_tables_note(s: &Scenario, on: &str) -> Option<String> {
    let reference = Scenario::default_scenario();
    let differ: Vec<&str> = [("board", s.board != reference.board), ("calibration", s.calibration != reference.calibration)]
        .into_iter()
        .filter_map(|(t, d)| d.then_some(t))
        .collect();
    (!differ.is_empty()).then(|| {
        format!(
            "the scenario's [{}] describes a board (the board twin, the emulated board), which {on} does not have: it is ignored",
            differ.join("] and [")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(key: &str, value: &str) -> Override {
        format!("{key}={value}").parse().unwrap()
    }

    /// A board key is refused where there is no board, naming it; other keys pass.
    #[test]
    fn board_keys_are_refused_without_a_board() {
        let e = refuse_board_overrides(&[set("plant.mu", "0.5"), set("board.pwm_max_duty", "0.5")], "the in-process link").unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("board.pwm_max_duty") && e.to_string().contains("the in-process link"), "{e}");
        assert!(refuse_board_overrides(&[set("calibration.theta1_zero_count", "1")], "a sweep").is_err());
        assert!(refuse_board_overrides(&[set("plant.mu", "0.5"), set("boardx.y", "1")], "a sweep").is_ok());
    }

    /// The default scenario, no flag given.
    fn no_flags() -> ScenarioArgs {
        ScenarioArgs { scenario: None, controller: None, x0: None, target_zt: None, duration: None, seed: None, iwc: None, set: Vec::new() }
    }

    /// Issue 66: `--duration` acts before the scenario is checked, as `--set
    /// timing.duration_s` does: a fault a file places past its own duration is
    /// reached by a longer `--duration`, and refused (exit 2) by a shorter one;
    /// the other flags land on their keys.
    #[test]
    fn the_flags_act_before_the_scenario_is_checked() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("late.toml");
        let text = rig::scenario::DEFAULT_TOML.to_string()
            + "\n[[faults]]\nkind = \"stuck_sensor\"\nsignal = \"theta1\"\nat_s = 12.0\nduration_s = 1.0\n";
        std::fs::write(&path, text).unwrap();
        let args = |duration: Option<f64>, set: &[Override]| ScenarioArgs {
            scenario: Some(path.clone()),
            duration,
            set: set.to_vec(),
            ..no_flags()
        };
        let e = load_scenario(&args(None, &[])).unwrap_err();
        assert_eq!(e.exit_code(), 2, "past the file's own 10 s: {e}");
        let by_set = load_scenario(&args(None, &[set("timing.duration_s", "15")])).unwrap();
        let by_flag = load_scenario(&args(Some(15.0), &[])).unwrap();
        assert_eq!(by_flag.timing.duration_s, 15.0);
        assert_eq!(by_flag, by_set, "the flag and the --set give the same scenario");
        let e = load_scenario(&args(Some(11.0), &[])).unwrap_err();
        assert!(e.to_string().contains("12"), "a fault past an 11 s run is still refused: {e}");
        let e = load_scenario(&args(Some(15.0), &[set("timing.duration_s", "15")])).unwrap_err();
        assert!(e.to_string().contains("--duration"), "a key in one place: {e}");
        let s = load_scenario(&ScenarioArgs {
            controller: Some(firmware::ControllerKind::Pid),
            x0: Some(plant::initial::PaperX0::U),
            target_zt: Some(-0.05),
            seed: Some(u64::MAX),
            iwc: Some(plant::impact::IwcRule::Plastic),
            ..no_flags()
        })
        .unwrap();
        assert_eq!(
            (s.controller.kind, s.plant.x0, s.controller.target_z_t),
            (firmware::ControllerKind::Pid, plant::initial::PaperX0::U, -0.05)
        );
        assert_eq!((s.sensors.seed, s.plant.iwc), (u64::MAX, plant::impact::IwcRule::Plastic));
        let e = load_scenario(&ScenarioArgs { duration: Some(f64::NAN), ..no_flags() }).unwrap_err();
        assert!(e.to_string().contains("timing.duration_s") && e.exit_code() == 2, "{e}");
    }

    /// The note names the tables that differ from the reference board's, and
    /// says nothing for the default scenario.
    #[test]
    fn a_scenario_board_table_is_noted() {
        let s = Scenario::default_scenario();
        assert_eq!(board_tables_note(&s, "a sweep"), None);
        let s = read_scenario(None, &[set("board.pwm_max_duty", "4000")]).unwrap();
        let note = board_tables_note(&s, "a sweep").unwrap();
        assert!(note.contains("[board]") && !note.contains("[calibration]"), "{note}");
    }
}
