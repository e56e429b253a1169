//! A closed-loop experiment's scenario as the fronts give it: a TOML file (or
//! standard input, or the embedded default) with `--set` overrides, then the
//! flags of [`ScenarioArgs`]; a key is set in one place only.

use crate::{Error as CliError, settings::ScenarioArgs};
use rig::{
    overrides::{self, Override},
    scenario::Scenario,
};

/// Reads a scenario (`path`; `-` is standard input; `None`: the embedded
/// default) with the `--set` overrides applied to its TOML document.
///
/// # Errors
/// [`crate::Error::Analysis`] (an unreadable file) or [`crate::Error::Analysis`] naming
/// the key (exit 2).
pub fn read_scenario(path: Option<&std::path::Path>, set: &[Override]) -> Result<Scenario, CliError> {
    let text = match path {
        Some(path) if path.as_os_str() == "-" => std::io::read_to_string(std::io::stdin())
            .map_err(|e| CliError::bad_input(format!("cannot read the scenario from stdin: {e}")))?,
        Some(path) => {
            std::fs::read_to_string(path).map_err(|e| CliError::bad_input(format!("cannot read scenario {}: {e}", path.display())))?
        }
        None => return Ok(Scenario::from_toml_with(rig::scenario::DEFAULT_TOML, set)?),
    };
    Ok(Scenario::from_toml_with(&text, set)?)
}

/// Loads the scenario, applies the `--set` overrides, then the flags. A key set
/// both by a flag and by `--set` is refused (exit 2): a key is set in one place.
///
/// # Errors
/// [`crate::Error::Analysis`] or [`crate::Error::Analysis`] (exit 2).
pub fn load_scenario(args: &ScenarioArgs) -> Result<Scenario, CliError> {
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
    let mut s = read_scenario(args.scenario.as_deref(), &args.set)?;
    if let Some(c) = args.controller {
        s.controller.kind = c;
    }
    if let Some(x0) = args.x0 {
        s.plant.x0 = x0;
    }
    if let Some(z) = args.target_zt {
        s.controller.target_z_t = z;
    }
    if let Some(d) = args.duration {
        s.timing.duration_s = d;
    }
    if let Some(seed) = args.seed {
        s.sensors.seed = seed;
    }
    if let Some(iwc) = args.iwc {
        s.plant.iwc = iwc;
    }
    s.validate()?;
    Ok(s)
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
/// [`CliError`] (bad input, exit 2) naming the first such key.
pub fn refuse_board_overrides(set: &[Override], on: &str) -> Result<(), CliError> {
    match set.iter().find(|o| BOARD_TABLES.iter().any(|t| o.key.split('.').next() == Some(t))) {
        Some(o) => Err(CliError::bad_input(format!(
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
