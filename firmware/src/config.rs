//! Firmware configuration: controller choice, gains, references, estimator,
//! lift-off detector and fault limits. Defaults: docs/model.md experiments 5 and 6
//! and docs/hardware.md.

use shared::{ElbowBranch, Params, Period};

use crate::law_params::{LawName, LawParams};

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
    /// Lift-off: consecutive periods of low force needed to declare lift-off
    /// ([`LIFT_OFF_CONFIRM`] at the period: [`Config::default_at`]).
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
    /// state ([`crate::SafeReason::SensorFault`]; [`SENSOR_FAULT_CONFIRM`]).
    pub sensor_fault_confirm: u8,
    /// Innovation check ([`crate::consistency::InnovationMonitor`]): observer
    /// innovation that counts as unexplained, rad (default 3 encoder counts).
    pub innovation_threshold: f32,
    /// Innovation check: consecutive same-sign unexplained periods that latch the
    /// safe state ([`crate::SafeReason::SensorFault`]; [`INNOVATION_CONFIRM`]).
    pub innovation_confirm: u16,
    /// Innovation check: periods after a touchdown during which it is off
    /// ([`INNOVATION_SETTLE`]).
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
    /// The law this configuration is for and its own parameters
    /// ([`crate::law_spec`]): [`LawParams::PAPER`] for the paper's laws (which
    /// `controller` chooses); a law of one's own's name and values otherwise
    /// (checked against what the law declares by `Firmware::with_law`).
    /// Absent from a JSON document (a board backup of before issue 70): the
    /// paper's laws.
    #[serde(default)]
    pub law: LawParams,
}

/// A detector's confirmation as tuned at 1 kHz: the time it must hold, and the
/// samples it needs against noise. [`Config::default_at`] takes the larger of the
/// two at any period: at least the time (10 kHz confirms over 2 ms, not 0.2 ms)
/// and at least the samples (250 Hz confirms over 2 samples, not one: one noisy
/// sample latched `SensorFault` in the default scenario's first periods).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Confirmation {
    /// The time, s.
    pub seconds: f32,
    /// The samples, periods.
    pub periods: u16,
}

impl Confirmation {
    /// In periods of `ts` seconds: `max(periods_of(seconds, ts), periods)`
    /// ([`crate::runaway::periods_of`]: whole periods, rounded up).
    pub fn at(self, ts: f32) -> u16 {
        crate::runaway::periods_of(self.seconds, ts).max(self.periods)
    }
}

/// Lift-off: the normal force low for 2 ms (two periods at 1 kHz, as tuned).
pub const LIFT_OFF_CONFIRM: Confirmation = Confirmation { seconds: 0.002, periods: 2 };
/// Sensor consistency: the encoders and the load cell disagreeing for 3 ms (three
/// periods at 1 kHz).
pub const SENSOR_FAULT_CONFIRM: Confirmation = Confirmation { seconds: 0.003, periods: 3 };
/// Innovation check: an unexplained innovation of one sign for 20 ms (20 periods
/// at 1 kHz).
pub const INNOVATION_CONFIRM: Confirmation = Confirmation { seconds: 0.020, periods: 20 };
/// Innovation check: off for 50 ms after a touchdown (50 periods at 1 kHz).
pub const INNOVATION_SETTLE: Confirmation = Confirmation { seconds: 0.050, periods: 50 };

impl Default for Config {
    /// [`Config::default_at`] 1 kHz.
    fn default() -> Self {
        Self::default_at(Period::MILLISECOND)
    }
}

impl Config {
    /// The defaults at the control period `period`: the detectors' confirmation
    /// and settle counts hold their times and their samples as tuned at 1 kHz
    /// ([`LIFT_OFF_CONFIRM`], [`SENSOR_FAULT_CONFIRM`], [`INNOVATION_CONFIRM`],
    /// [`INNOVATION_SETTLE`]; [`Confirmation::at`]), so that a board configured
    /// at 10 kHz confirms a lift-off or a sensor fault over the same time as at
    /// 1 kHz, not a tenth of it (issue 56), and one at 250 Hz over as many
    /// samples. At 1 kHz and below these are 2, 3, 20 and 50 periods; at 10 kHz
    /// 20, 30, 200 and 500. The deadline-miss and bad-frame limits stay counts
    /// of periods: they count events, not a time.
    pub fn default_at(period: Period) -> Self {
        let ts = period.as_secs_f32();
        Self {
            lift_off_confirm: u8::try_from(LIFT_OFF_CONFIRM.at(ts)).unwrap_or(u8::MAX),
            sensor_fault_confirm: u8::try_from(SENSOR_FAULT_CONFIRM.at(ts)).unwrap_or(u8::MAX),
            innovation_confirm: INNOVATION_CONFIRM.at(ts),
            innovation_settle: INNOVATION_SETTLE.at(ts),
            period,
            ..Self::at_1_khz()
        }
    }

    /// The defaults as tuned, at 1 kHz.
    fn at_1_khz() -> Self {
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
            law: LawParams::PAPER,
        }
    }
}

/// The largest `K'_D Ts` of the hybrid law's envelope (docs/hardware.md "The
/// envelope"): the sampled motion loop with its command delay tracks the default
/// scenario at 1.29 and bounces at 1.5; the paper's gains (900) at 1 kHz are 0.9.
/// Beyond it (or beyond [`KP_TS2_MAX`], or without a position or a damping gain)
/// the firmware runs the law, and a trip of its tracking or lift-off check is
/// [`crate::SafeReason::Unstable`]: the law's own failure at that rate.
pub const KD_TS_MAX: f32 = 1.0;
/// The largest `K'_I Ts` of the hybrid law's envelope: the force integrator's
/// sampled loop (the contact answers `a_f` within the period) bounces at the
/// paper's 650 at 250 Hz (2.6) and holds at 0.65 (1 kHz) and at 0.4 (100 at
/// 250 Hz).
pub const KI_TS_MAX: f32 = 1.0;
/// The largest `K'_P Ts^2` of the hybrid law's envelope: the loop's poles within
/// the rate (the paper's gains at 1 kHz: 9e-4).
pub const KP_TS2_MAX: f32 = 0.25;

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
    /// The configuration is for another law than the firmware was built with.
    #[error(
        "the configuration is for {asked}, this firmware runs {built}: build the law's own firmware, or give the scenario its `[law]` table"
    )]
    WrongLaw {
        /// The law the firmware runs.
        built: LawName,
        /// The law the configuration names.
        asked: LawName,
    },
    /// A law's own parameter is out of the range it declares.
    #[error("law parameter `{name}` = {value} {unit} is out of the law's range [{min}, {max}] {unit}")]
    LawParam {
        /// The parameter's declared name.
        name: &'static str,
        /// Its declared unit.
        unit: &'static str,
        /// The value.
        value: f32,
        /// Least value admitted.
        min: f32,
        /// Largest value admitted.
        max: f32,
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
            (0.0..=crate::runaway::MAX_F_N_REF).contains(&self.f_n_ref),
            "[0, 20] N (2 N below the press check at 22 N, of the load cell's 25 N range)",
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_at_1_khz_are_the_counts_the_detectors_were_tuned_with() {
        let c = Config::default();
        assert_eq!(c, Config::default_at(Period::MILLISECOND));
        assert_eq!((c.lift_off_confirm, c.sensor_fault_confirm, c.innovation_confirm, c.innovation_settle), (2, 3, 20, 50));
        assert_eq!(c.period, Period::MILLISECOND);
        c.validate().unwrap();
    }

    #[test]
    fn every_period_a_board_runs_confirms_over_at_least_the_time_and_the_samples_tuned_at_1_khz() {
        // Every whole microsecond of the image's range (100 to 4000 us, 10 kHz to
        // 250 Hz: arm_app::rate): each count n holds its time t, n Ts >= t (never a
        // shorter confirmation than at 1 kHz, to the thousandth of a period
        // `periods_of` rounds off), and its samples, n >= n0; and it is the least
        // such count: (n - 1) Ts < t or n = n0. The rest as at 1 kHz; valid.
        let base = Config::default();
        for us in 100..=4000u32 {
            let period = Period::from_us(us).unwrap();
            let c = Config::default_at(period);
            let ts = f64::from(us) * 1e-6;
            for (name, n, rule) in [
                ("lift_off_confirm", u32::from(c.lift_off_confirm), LIFT_OFF_CONFIRM),
                ("sensor_fault_confirm", u32::from(c.sensor_fault_confirm), SENSOR_FAULT_CONFIRM),
                ("innovation_confirm", u32::from(c.innovation_confirm), INNOVATION_CONFIRM),
                ("innovation_settle", u32::from(c.innovation_settle), INNOVATION_SETTLE),
            ] {
                let (t, n0) = (f64::from(rule.seconds), u32::from(rule.periods));
                assert!(n >= n0, "{us} us: {name} = {n} periods, fewer samples than {n0}");
                let n = f64::from(n);
                assert!(n * ts >= t - ts * 1e-3 * (1.0 + 1e-6), "{us} us: {name} = {n} periods is shorter than {t} s");
                assert!(n == f64::from(n0) || (n - 1.0) * ts < t, "{us} us: {name} = {n} periods is a period longer than {t} s");
            }
            assert_eq!(c.period, period);
            let same = Config {
                period: base.period,
                lift_off_confirm: base.lift_off_confirm,
                sensor_fault_confirm: base.sensor_fault_confirm,
                innovation_confirm: base.innovation_confirm,
                innovation_settle: base.innovation_settle,
                ..c
            };
            assert_eq!(same, base, "{us} us: only the period and the counts move");
            c.validate().unwrap_or_else(|e| panic!("{us} us: {e}"));
        }
        let counts = |us| {
            let c = Config::default_at(Period::from_us(us).unwrap());
            (c.lift_off_confirm, c.sensor_fault_confirm, c.innovation_confirm, c.innovation_settle)
        };
        assert_eq!(counts(100), (20, 30, 200, 500));
        assert_eq!(counts(250), (8, 12, 80, 200));
        assert_eq!(counts(4000), (2, 3, 20, 50));
    }
}
