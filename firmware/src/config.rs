//! Firmware configuration: controller choice, gains, references, estimator,
//! lift-off detector and fault limits. Defaults: docs/model.md experiments 5 and 6
//! and docs/hardware.md.

use shared::{ElbowBranch, Params, Period};

/// Which control law runs (docs/model.md experiments 5 and 6): the firmware's
/// configuration, scenario files (`controller.kind = "pid" | "hybrid"`), the
/// analyses and the command line (`--controller`) all use this one type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ControllerKind {
    /// Joint-space PID on `q' = [theta1, theta2 - theta1]` (paper eq. 8).
    Pid,
    /// Hybrid force/motion control (paper eqs. 9 to 11).
    Hybrid,
}

impl core::fmt::Display for ControllerKind {
    /// [`Self::name`].
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

impl ControllerKind {
    /// `pid` or `hybrid` (as in scenario files, JSON and on the command line).
    pub fn name(self) -> &'static str {
        match self {
            Self::Pid => "pid",
            Self::Hybrid => "hybrid",
        }
    }
}

/// The friction term `f_t` of the hybrid law (paper eq. 9: `-J^T i_x f_t`).
///
/// In sliding, `z_n_ddot = Q_21 (f_t - f_t_hat) + Q_22 (f_n - a_f) = 0` with
/// `f_t = -mu s f_n`, so `p f_n = Q_22 a_f + Q_21 f_t_hat`. With a one-period-old
/// measurement `f_t_hat(k) = f_t(k-1) = -mu s f_n(k-1)` this is the discrete loop
/// `f_n(k) = g f_n(k-1) + ...` with `g = -mu s Q_21 / p`: it is stable only if
/// `|g| < 1`, i.e. `p > Q_22 / 2` (`mu s Q_21 < Q_22 / 2`), and near the Painlevé
/// boundary (`p -> 0+`) `|g|` grows without bound and `f_n` flips sign every
/// period. The same holds for the model-based term with the measured `f_n`.
/// With the commanded normal force, `f_t_hat = -mu_hat s a_f`, there is no loop
/// and `f_n = a_f` exactly when `mu_hat = mu`: that is the default.
///
/// The robust variant, `f_t_hat = -mu_est s a_f`, keeps the commanded normal force
/// (no loop through `f_n`) and replaces `mu_hat` by an online estimate from the
/// ratio `-s f_t / f_n` the load cell measures while the tip slides
/// ([`crate::mu_estimate`]): Coulomb's law makes that ratio `mu` whatever the law
/// commands, so the estimate feeds no loop back, and a wrong `mu_hat` leaves no
/// steady-state error once it has converged.
///
/// Scenario files name it `controller.friction`: `measured`, `measured_normal`,
/// `commanded`, `none` or `estimated`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum FrictionCompensation {
    /// The measured tangential force (one period old).
    #[serde(rename = "measured")]
    Measured,
    /// `-mu_hat sign(z_r_dot) f_n` with the measured normal force (one period old).
    #[serde(rename = "measured_normal")]
    #[cfg_attr(feature = "clap", value(name = "measured_normal"))]
    ModelMeasuredNormal,
    /// `-mu_hat sign(z_r_dot) a_f` with the commanded normal force (default).
    #[serde(rename = "commanded")]
    #[cfg_attr(feature = "clap", value(name = "commanded"))]
    ModelCommandedNormal,
    /// No friction term.
    #[serde(rename = "none")]
    None,
    /// `-mu_est s a_f` with the commanded normal force and `mu_est` estimated online
    /// from the measured `f_t / f_n` while sliding ([`crate::mu_estimate`]): the
    /// robust variant for an arm whose friction is not known.
    #[serde(rename = "estimated")]
    #[cfg_attr(feature = "clap", value(name = "estimated"))]
    Estimated,
}

/// PID gains per joint of `q' = [theta1, theta2 - theta1]` (paper eq. 8).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PidGains {
    /// `K_P`, N m/rad.
    pub kp: [f32; 2],
    /// `K_I`, N m/(rad s).
    pub ki: [f32; 2],
    /// `K_D`, N m s/rad.
    pub kd: [f32; 2],
}

/// Hybrid force/motion gains (paper eqs. 10 and 11).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HybridGains {
    /// `K'_P`, 1/s^2.
    pub kp: f32,
    /// `K'_D`, 1/s.
    pub kd: f32,
    /// `K'_I`, 1/s (650 from `x0d`, 0 from `x0u` in the paper).
    pub ki: f32,
}

/// Firmware configuration.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Config {
    /// The arm's parameters as the firmware knows them (`mu` is `mu_hat`).
    pub params: Params<f32>,
    /// Control law.
    pub controller: ControllerKind,
    /// Control period `Ts`, whole microseconds (docs/hardware.md "Timing": 1 ms,
    /// from 0.1 ms to 4 ms); the firmware derives its `f32` step from it once.
    pub period: Period,
    /// Tangential target `z_t*`, m.
    pub target_z_t: f32,
    /// Duration of the quintic move from the initial tip position to the target, s.
    pub move_time_s: f32,
    /// Normal force reference `f_n*`, N (hybrid law): within the load cell's
    /// range, `[0, 25]` N (`shared::wire::LOAD_FULL_SCALE_N`, docs/hardware.md).
    pub f_n_ref: f32,
    /// Bumpless start of the hybrid law, s: `f_n*` ramps (quintic) from the normal
    /// force measured at the first frame to `f_n_ref` over this time (0: a step).
    /// Not in the paper, whose simulations start at the reference.
    pub force_ramp_s: f32,
    /// PID gains.
    pub pid: PidGains,
    /// Hybrid gains.
    pub hybrid: HybridGains,
    /// Friction term of the hybrid law.
    pub friction: FrictionCompensation,
    /// Torque limit per motor, N m (the command saturates here; docs/hardware.md: 5 N m).
    pub torque_limit: f32,
    /// Bandwidth of the joint-velocity observer, rad/s.
    pub observer_bandwidth: f32,
    /// Lift-off: normal force below which the tip may be off the belt, N.
    pub lift_off_force: f32,
    /// Lift-off: tip height above the belt (from the encoders) that declares lift-off, m.
    pub lift_off_height: f32,
    /// Lift-off: consecutive periods of low force needed to declare lift-off.
    pub lift_off_confirm: u8,
    /// Touchdown (end of lift-off): normal force above which contact is back, N.
    pub touchdown_force: f32,
    /// Sensor consistency ([`crate::consistency`]): normal force above which the
    /// load cell says the tip presses on the belt, N.
    pub sensor_contact_force: f32,
    /// Sensor consistency: largest tip height `|z_n + H|` from the encoders still
    /// on the belt, m (the two 14-bit encoders are good to about 0.2 mm).
    pub sensor_height_tolerance: f32,
    /// Sensor consistency: consecutive inconsistent periods that latch the safe
    /// state ([`crate::SafeReason::SensorFault`]).
    pub sensor_fault_confirm: u8,
    /// Innovation check ([`crate::consistency::InnovationMonitor`]): observer
    /// innovation that counts as unexplained, rad (default 3 encoder counts).
    pub innovation_threshold: f32,
    /// Innovation check: consecutive same-sign unexplained periods that latch the
    /// safe state ([`crate::SafeReason::SensorFault`]).
    pub innovation_confirm: u16,
    /// Innovation check: periods after a touchdown during which it is off.
    pub innovation_settle: u16,
    /// The runaway limits ([`crate::runaway`]: a joint's speed past 20 rad/s, the
    /// load cell at full scale for 10 ms) and the wiring checks ([`crate::wiring`],
    /// [`crate::tracking`]) latch the safe state. On by default and on every
    /// board; off only to study what the arm would do without them (the paper's
    /// persistent bouncing beyond `Z_t,sliding`).
    pub runaway_limits: bool,
    /// Consecutive deadline misses that latch the safe state.
    pub deadline_miss_limit: u16,
    /// Consecutive bad frames that latch the safe state.
    pub bad_frame_limit: u16,
    /// Elbow branch for the PID's inverse kinematics; `None`: the branch of the first frame.
    pub branch: Option<ElbowBranch>,
    /// Resolution of both joint encoders, bits per revolution (docs/hardware.md: 14 on
    /// the reference board; 10 to 16, `shared::wire::ENCODER_BITS_RANGE`). The sensor
    /// side must send counts of the same resolution.
    pub encoder_bits: u8,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            params: Params::paper(),
            controller: ControllerKind::Hybrid,
            period: Period::MILLISECOND,
            target_z_t: 0.10,
            move_time_s: 2.0,
            f_n_ref: 10.0,
            force_ramp_s: 0.25,
            pid: PidGains { kp: [200.0, 0.0], ki: [25.0, 0.0], kd: [2.0, 0.0] },
            hybrid: HybridGains { kp: 900.0, kd: 900.0, ki: 650.0 },
            friction: FrictionCompensation::ModelCommandedNormal,
            torque_limit: shared::wire::TORQUE_FULL_SCALE_NM,
            observer_bandwidth: 2.0 * core::f32::consts::PI * 40.0,
            lift_off_force: 0.5,
            lift_off_height: 1e-3,
            lift_off_confirm: 2,
            touchdown_force: 1.0,
            sensor_contact_force: 2.0,
            sensor_height_tolerance: 2e-3,
            sensor_fault_confirm: 3,
            innovation_threshold: 3.0 * core::f32::consts::TAU / 16384.0,
            innovation_confirm: 20,
            innovation_settle: 50,
            runaway_limits: true,
            deadline_miss_limit: 3,
            bad_frame_limit: 3,
            branch: None,
            encoder_bits: shared::wire::ENCODER_BITS,
        }
    }
}

/// Why a [`Config`] was rejected.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// A parameter of the arm is invalid.
    #[error(transparent)]
    Params(#[from] shared::ParamError),
    /// A setting is out of range.
    #[error("setting `{name}` = {value} is out of range ({expected})")]
    OutOfRange {
        /// Field name.
        name: &'static str,
        /// The value.
        value: f32,
        /// What is allowed.
        expected: &'static str,
    },
}

impl Config {
    /// Checks every setting. The runaway limits may be off here (a study without a
    /// board); a board's application refuses that itself (`arm_app`, docs/board.md
    /// "Runaway limits").
    ///
    /// # Errors
    /// [`ConfigError`] naming the first bad field (its name as in the struct,
    /// `pid.kp` for a nested one).
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.params.validate()?;
        let check = |name: &'static str, value: f32, ok: bool, expected: &'static str| {
            if ok && value.is_finite() { Ok(()) } else { Err(ConfigError::OutOfRange { name, value, expected }) }
        };
        let us = self.period.as_us();
        check("period_us", us as f32, (100..=4000).contains(&us), "100 to 4000 us (250 Hz to 10 kHz)")?;
        check("target_z_t", self.target_z_t, self.target_z_t.abs() < 2.0 * self.params.l, "|z_t*| < 2 l")?;
        check("move_time_s", self.move_time_s, self.move_time_s > 0.0, "> 0")?;
        check(
            "f_n_ref",
            self.f_n_ref,
            (0.0..=shared::wire::LOAD_FULL_SCALE_N).contains(&self.f_n_ref),
            "[0, 25] N (the load cell's range)",
        )?;
        check("force_ramp_s", self.force_ramp_s, self.force_ramp_s >= 0.0, ">= 0")?;
        for (name, v) in [("pid.kp", self.pid.kp), ("pid.ki", self.pid.ki), ("pid.kd", self.pid.kd)] {
            check(name, v[0], v[0] >= 0.0 && v[1] >= 0.0 && v[1].is_finite(), ">= 0")?;
        }
        for (name, v) in [("hybrid.kp", self.hybrid.kp), ("hybrid.kd", self.hybrid.kd), ("hybrid.ki", self.hybrid.ki)] {
            check(name, v, v >= 0.0, ">= 0")?;
        }
        check("torque_limit", self.torque_limit, self.torque_limit > 0.0 && self.torque_limit <= 5.0, "(0, 5] N m")?;
        check(
            "observer_bandwidth",
            self.observer_bandwidth,
            self.observer_bandwidth > 0.0 && self.observer_bandwidth * self.period.as_secs_f32() <= 3.0,
            "> 0 and <= 3/Ts",
        )?;
        check("lift_off_force", self.lift_off_force, self.lift_off_force >= 0.0, ">= 0")?;
        check("lift_off_height", self.lift_off_height, self.lift_off_height > 0.0, "> 0")?;
        check("touchdown_force", self.touchdown_force, self.touchdown_force >= self.lift_off_force, ">= lift_off_force")?;
        check("lift_off_confirm", self.lift_off_confirm as f32, self.lift_off_confirm >= 1, ">= 1")?;
        check("sensor_contact_force", self.sensor_contact_force, self.sensor_contact_force >= 0.0, ">= 0")?;
        check("sensor_height_tolerance", self.sensor_height_tolerance, self.sensor_height_tolerance > 0.0, "> 0")?;
        check("sensor_fault_confirm", self.sensor_fault_confirm as f32, self.sensor_fault_confirm >= 1, ">= 1")?;
        check("innovation_threshold", self.innovation_threshold, self.innovation_threshold > 0.0, "> 0")?;
        check("innovation_confirm", self.innovation_confirm as f32, self.innovation_confirm >= 1, ">= 1")?;
        check("deadline_miss_limit", self.deadline_miss_limit as f32, self.deadline_miss_limit >= 1, ">= 1")?;
        check("bad_frame_limit", self.bad_frame_limit as f32, self.bad_frame_limit >= 1, ">= 1")?;
        let (lo, hi) = shared::wire::ENCODER_BITS_RANGE;
        check("encoder_bits", f32::from(self.encoder_bits), (lo..=hi).contains(&self.encoder_bits), "10 to 16 bits")?;
        Ok(())
    }
}
