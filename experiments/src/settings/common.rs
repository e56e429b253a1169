//! The arguments several commands share: the output folder and `--json`
//! ([`OutputArgs`]), `--strict` ([`StrictArgs`]), and a closed-loop run's scenario
//! with its overrides ([`ScenarioArgs`]).

use std::path::PathBuf;

/// Options shared by every command's output.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct OutputArgs {
    /// Folder for the files the command writes (created if missing).
    #[cfg_attr(feature = "clap", arg(long, default_value = "out", value_name = "DIR"))]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[cfg_attr(feature = "clap", arg(long))]
    pub json: bool,
}

/// `--strict`, on every command that simulates.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct StrictArgs {
    /// Exit 1 if any result violates the model (an energy-creating impact, a
    /// friction-cone violation, an integrator failure); everything is still written
    /// and the violations are listed. Without it they are reported, and exit is 0.
    #[cfg_attr(feature = "clap", arg(long))]
    pub strict: bool,
}

/// The scenario of a run and its command-line overrides.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ScenarioArgs {
    /// Scenario file (TOML, see scenarios/), `-` for standard input; default: the
    /// embedded default scenario (hybrid from x0d, mu 0.6, v_belt -0.4 m/s, f_n* 10 N,
    /// z_t* 0.10 m over 2 s, 10 s, 1 kHz).
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE.toml"))]
    pub scenario: Option<PathBuf>,
    /// Override the controller.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub controller: Option<firmware::ControllerKind>,
    /// Override the initial condition.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub x0: Option<plant::initial::PaperX0>,
    /// Override the tangential target z_t*, m.
    #[cfg_attr(feature = "clap", arg(long))]
    pub target_zt: Option<f64>,
    /// Override the run length, s.
    #[cfg_attr(feature = "clap", arg(long))]
    pub duration: Option<f64>,
    /// Override the sensor-noise seed.
    #[cfg_attr(feature = "clap", arg(long))]
    pub seed: Option<u64>,
    /// Override the impact-without-collision rule (scenario `plant.iwc`):
    /// `restitution` (the tip is thrown off the belt) or `plastic` (left stuck, v_n = 0).
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub iwc: Option<plant::impact::IwcRule>,
    /// Change one scenario key, e.g. `--set plant.m=0.24 --set controller.pid.kp=[150,0]`
    /// (repeatable). KEY is the scenario file's dotted key path (docs/rig.md), VALUE a
    /// TOML value (a bare word such as `pid` is a string). Applied to the file before
    /// it is read, so a bad key or value is an error naming it (exit 2). A key also
    /// set by a flag here (`--x0` and `plant.x0`, ...) is refused.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    pub set: Vec<rig::overrides::Override>,
}
