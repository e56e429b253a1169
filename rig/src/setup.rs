//! From a scenario to the two sides of the loop: the plant at `t = 0` and the
//! firmware's configuration, and [`RunSetup`], the run made of them once.

use firmware::{
    Config, LawName, LawParams,
    config::{HybridGains, PidGains},
};
use shared::Params;

use super::{
    faults::FaultPlan,
    law::{LawDescription, bind},
    record::RunError,
    scenario::Scenario,
};
use plant::{Plant, SimConfig, SimError, initial};

/// The plant's parameters (paper Table I, `mu`, `v_belt`) a scenario asks for:
/// its `[plant]` section.
pub fn plant_params(s: &Scenario) -> Params<f64> {
    s.plant.params()
}

/// The parameters the firmware models the arm with, in `f64`: the plant's
/// (`[plant]`), with the keys of `[controller.model]` replacing theirs when that
/// table is given (a deliberate mismatch), `mu = controller.mu_hat` and the
/// plant's `v_belt`.
pub fn firmware_params(s: &Scenario) -> Params<f64> {
    let plant = plant_params(s);
    let model = s.controller.model.map_or(plant, |m| m.over(plant));
    Params { mu: s.controller.mu_hat, ..model }
}

/// The firmware configuration a scenario asks for: the model of
/// [`firmware_params`] in `f32`, the controller, the period, the references and
/// the gains (paper eqs. 8 to 11; `K'_I` by [`crate::scenario::ControllerSection::hybrid_ki`]);
/// the rest the firmware's defaults at the scenario's period ([`Config::default_at`]:
/// the detectors' confirmations in time, not in periods). A `[law]` table's
/// name goes into `law.name`; its values need the law's declaration and are
/// bound by [`RunSetup::firmware_for`] (here they are 0).
pub fn firmware_config(s: &Scenario) -> Config {
    let c = &s.controller;
    let f = |v: [f64; 2]| v.map(|x| x as f32);
    // The detectors' confirmations hold their times at the scenario's rate.
    let base = Config::default_at(s.timing.period());
    Config {
        params: firmware_params(s).cast(),
        controller: c.kind,
        period: s.timing.period(),
        target_z_t: c.target_z_t as f32,
        move_time_s: c.move_time_s as f32,
        f_n_ref: c.f_n_ref as f32,
        pid: PidGains { kp: f(c.pid.kp), ki: f(c.pid.ki), kd: f(c.pid.kd) },
        hybrid: HybridGains { kp: c.hybrid.kp as f32, kd: c.hybrid.kd as f32, ki: c.hybrid_ki(s.plant.x0) as f32 },
        friction: c.friction,
        torque_limit: c.torque_limit_nm.map_or(base.torque_limit, |t| t as f32),
        runaway_limits: c.runaway_limits,
        encoder_bits: s.sensors.encoder_bits,
        // The innovation check's threshold is 3 encoder counts (docs/hardware.md).
        innovation_threshold: base.innovation_threshold * (1u32 << shared::wire::ENCODER_BITS) as f32
            / (1u32 << s.sensors.encoder_bits.min(16)) as f32,
        law: LawParams {
            name: s.law.as_ref().and_then(|t| LawName::new(&t.name)).unwrap_or(LawName::PAPER),
            values: [0.0; firmware::law_spec::LAW_PARAMS],
        },
        ..base
    }
}

/// The plant a scenario asks for, at `t = 0`.
///
/// # Errors
/// [`SimError`] for bad parameters or initial conditions.
pub fn plant_for(s: &Scenario) -> Result<Plant, SimError> {
    let params = plant_params(s);
    params.validate()?;
    let sim = SimConfig {
        rtol: s.plant.rtol,
        atol: s.plant.atol,
        impact_law: s.plant.impact_law,
        e_n: s.plant.e_n,
        iwc: s.plant.iwc,
        max_step: s.plant.max_step,
        singular: s.plant.singular,
        ..SimConfig::default()
    };
    Plant::new(params, sim, initial::deg_to_state(s.plant.x0.condition().deg), 0.0, [0.0, 0.0])
}

/// A closed-loop run as its scenario asks for it, made once and handed to the
/// period loop and to the link (whichever of the five): the scenario, the plant
/// at `t = 0` ([`plant_for`]), the firmware's configuration ([`firmware_config`],
/// validated), and the plan of the scenario's faults over its control period.
/// Each side takes what it needs from here, so that the plant, the firmware and
/// the faults are built from the scenario in one place.
#[derive(Debug, Clone)]
pub struct RunSetup {
    scenario: Scenario,
    plant: Plant,
    firmware: Config,
    faults: FaultPlan,
}

impl RunSetup {
    /// The run scenario `scenario` asks for.
    ///
    /// # Errors
    /// [`RunError::Scenario`] for a scenario out of its ranges
    /// ([`Scenario::validate`], the check the command line makes when it reads one:
    /// a scenario built in code gets it here too, e.g. a `timing.delta_s` of a
    /// period or more, which would drop every command as late);
    /// [`RunError::Sim`] for bad plant parameters or initial conditions;
    /// [`RunError::Firmware`] for a firmware configuration the firmware refuses
    /// (`firmware::Config::validate`).
    pub fn new(scenario: Scenario) -> Result<Self, RunError> {
        scenario.validate()?;
        let plant = plant_for(&scenario)?;
        let firmware = firmware_config(&scenario);
        firmware.validate()?;
        let faults = FaultPlan::new(&scenario.faults, scenario.timing.period());
        Ok(Self { scenario, plant, firmware, faults })
    }

    /// The scenario.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The plant at `t = 0`, at the scenario's initial state with zero torque (each
    /// run steps its own copy).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The firmware's configuration (validated), a `[law]` table's values not
    /// yet bound (0: [`RunSetup::firmware_for`] binds them).
    pub fn firmware(&self) -> &Config {
        &self.firmware
    }

    /// The firmware's configuration for the law `law` declares: the scenario's
    /// `[law]` table bound to its parameters ([`crate::law::bind`]); for the
    /// paper's laws and no table, [`RunSetup::firmware`].
    ///
    /// # Errors
    /// [`RunError::Law`] when the table is for another law, names a parameter
    /// the law does not declare or a value out of its range.
    pub fn firmware_for(&self, law: &LawDescription) -> Result<Config, RunError> {
        Ok(Config { law: bind(self.scenario.law.as_ref(), law)?, ..self.firmware })
    }

    /// The scenario's faults over its control period.
    pub fn faults(&self) -> &FaultPlan {
        &self.faults
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::DEFAULT_TOML;

    /// A scenario built in code is checked as one read from a file: a command delay
    /// of one period or more (every command late, dropped) is refused naming the key,
    /// at 1 kHz and at 10 kHz where the default 0.2 ms is two periods; within the
    /// period it is taken.
    #[test]
    fn a_scenario_built_in_code_is_validated() {
        let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
        assert!(RunSetup::new(s.clone()).is_ok());
        s.timing.rate_hz = 10_000.0;
        let e = RunSetup::new(s.clone()).unwrap_err();
        assert!(matches!(e, RunError::Scenario(_)), "{e}");
        assert!(e.to_string().contains("timing.delta_s"), "{e}");
        s.timing.delta_s = 0.000_05;
        assert!(RunSetup::new(s.clone()).is_ok());
        s.timing.rate_hz = 1_000.0;
        s.timing.delta_s = 0.001;
        assert!(RunSetup::new(s).unwrap_err().to_string().contains("timing.delta_s"));
    }
}
