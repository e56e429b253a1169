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
