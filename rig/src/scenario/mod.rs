//! Scenario files (TOML): the plant, the controller, timing and sensor models of
//! one run. Unknown keys and out-of-range values are errors naming the key.
//!
//! The arm's parameters (paper Table I) and the controller's gains (paper eqs. 8
//! to 11) are optional keys whose defaults are the paper's values
//! ([`shared::Params::paper`], [`firmware::Config::default`]). A scenario can be
//! changed key by key before it is read ([`Scenario::from_toml_with`] and
//! [`crate::overrides`], the command line's `--set KEY=VALUE`).

mod error;
mod load;
mod sections;
mod validate;

pub use error::ScenarioError;
pub use load::DEFAULT_TOML;
pub use sections::{
    ARM_KEYS, ControllerSection, CpuPin, HybridSection, ModelSection, PidSection, PlantSection, REALTIME_CPU_FORMS, RigSection, Scenario,
    SensorSection, TimingSection, paper_hybrid_ki,
};
pub use validate::validate_arm;

#[cfg(test)]
mod tests;
