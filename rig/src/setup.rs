//! From a scenario to the two sides of the loop: the plant at `t = 0` and the
//! firmware's configuration.

use firmware::{Config, config::HybridGains};
use shared::Params;

use super::scenario::Scenario;
use plant::{Plant, SimConfig, SimError, initial};

/// The firmware configuration a scenario asks for.
pub fn firmware_config(s: &Scenario) -> Config {
    let c = &s.controller;
    let mut params = Params::<f32>::paper();
    params.mu = c.mu_hat as f32;
    params.v_belt = s.plant.v_belt as f32;
    let base = Config::default();
    Config {
        params,
        controller: c.kind,
        period: s.timing.period(),
        target_z_t: c.target_z_t as f32,
        move_time_s: c.move_time_s as f32,
        f_n_ref: c.f_n_ref as f32,
        hybrid: HybridGains { ki: c.hybrid_ki as f32, ..base.hybrid },
        friction: c.friction,
        ..base
    }
}

/// The plant a scenario asks for, at `t = 0`.
///
/// # Errors
/// [`SimError`] for bad parameters or initial conditions.
pub fn plant_for(s: &Scenario) -> Result<Plant, SimError> {
    let params = Params::new(s.plant.mu, s.plant.v_belt)?;
    let sim = SimConfig {
        rtol: s.plant.rtol,
        atol: s.plant.atol,
        impact_law: s.plant.impact_law,
        e_n: s.plant.e_n,
        iwc: s.plant.iwc,
        ..SimConfig::default()
    };
    Plant::new(params, sim, initial::deg_to_state(s.plant.x0.condition().deg), 0.0, [0.0, 0.0])
}
