//! The ranges a scenario's values must lie in, checked after it is read: each
//! key against its range, the arm's parameters and the gains, what the
//! firmware's `f32` can hold, and faults that could act within the run.

use shared::{ParamError, Params};

use super::{
    error::ScenarioError,
    sections::{ARM_KEYS, Scenario, TimingSection},
};

/// `Err(OutOfRange)` for `key` unless `ok`.
fn check(ok: bool, key: &str, value: impl std::fmt::Display, expected: &str) -> Result<(), ScenarioError> {
    if ok { Ok(()) } else { Err(ScenarioError::OutOfRange { key: key.into(), value: value.to_string(), expected: expected.into() }) }
}

/// Checks the arm's parameters of paper Table I under the key prefix `prefix`
/// (`plant` or `controller.model`): `m`, `l`, `h`, `g` finite and > 0; `sigma`,
/// `k` finite and >= 0; `alpha0` finite and within [-pi, pi] (radians); `h < 2 l`
/// (the belt within reach); then
/// [`Params::validate`].
///
/// # Errors
/// [`ScenarioError::OutOfRange`] naming the first bad key (`plant.m`) and its value.
pub fn validate_arm(prefix: &str, p: &Params<f64>) -> Result<(), ScenarioError> {
    let key = |name: &str| format!("{prefix}.{name}");
    for (name, v) in [("m", p.m), ("l", p.l), ("h", p.h), ("g", p.g)] {
        check(v.is_finite() && v > 0.0, &key(name), v, "a finite value > 0")?;
    }
    for (name, v) in [("sigma", p.sigma), ("k", p.k)] {
        check(v.is_finite() && v >= 0.0, &key(name), v, "a finite value >= 0")?;
    }
    check(
        p.alpha0.is_finite() && p.alpha0.abs() <= std::f64::consts::PI,
        &key("alpha0"),
        p.alpha0,
        &format!(
            "an angle in radians within [-pi, pi] (paper Table I's 13.72 degrees is 0.2395 rad; {} read as degrees is {} rad)",
            p.alpha0,
            p.alpha0.to_radians()
        ),
    )?;
    check(p.h < 2.0 * p.l, &key("h"), p.h, &format!("a base height below the arm's reach 2 l = {} m", 2.0 * p.l))?;
    p.validate().map_err(|e| ScenarioError::Parse(format!("scenario key `{prefix}`: {e}")))
}

/// Checks gains: each finite and >= 0, and finite in the firmware's f32 (at most
/// 3.4e38), named `key`.
fn validate_gains(key: &str, v: &[f64]) -> Result<(), ScenarioError> {
    let ok = v.iter().all(|g| g.is_finite() && *g >= 0.0 && (*g as f32).is_finite());
    let shown = if v.len() == 1 { v[0].to_string() } else { format!("[{}]", v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ")) };
    check(ok, key, shown, if v.len() == 1 { "a finite gain >= 0, at most 3.4e38" } else { "finite gains >= 0, at most 3.4e38" })
}

impl Scenario {
    /// Longest scenario name, characters (it names files and the rig's outputs).
    pub const MAX_NAME_CHARS: usize = 64;
    /// Most `[[faults]]` in one scenario.
    pub const MAX_FAULTS: usize = 1000;
}

impl Scenario {
    /// Checks ranges.
    ///
    /// # Errors
    /// [`ScenarioError::OutOfRange`] naming the first bad key.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let finite = |x: f64| x.is_finite();
        check(
            !self.name.is_empty()
                && self.name.chars().count() <= Self::MAX_NAME_CHARS
                && !self.name.chars().any(|c| c.is_control() || is_format(c) || is_noncharacter(c)),
            "name",
            // Debug-quoted: a control character shows as an escape, never reaches the terminal raw.
            format!("{:?}", self.name.chars().take(40).collect::<String>()),
            "1 to 64 characters, none a control character, a format character (Unicode category Cf: the bidirectional \
             controls such as U+202E that reorder what a terminal shows, zero-width characters) or a Unicode noncharacter \
             such as U+FFFE (it titles figures, which XML 1.0 must be able to hold, and terminal lines)",
        )?;
        check(self.faults.len() <= Self::MAX_FAULTS, "faults", self.faults.len(), "at most 1000 [[faults]]")?;
        let p = &self.plant;
        check(finite(p.mu) && (0.0..=10.0).contains(&p.mu), "plant.mu", p.mu, "a value in [0, 10]")?;
        check(finite(p.v_belt) && p.v_belt.abs() <= 5.0, "plant.v_belt", p.v_belt, "a finite speed within +-5 m/s")?;
        validate_arm("plant", &p.params())?;
        check(finite(p.e_n) && (0.0..=1.0).contains(&p.e_n), "plant.e_n", p.e_n, "a value in [0, 1]")?;
        for (key, v) in [("plant.rtol", p.rtol), ("plant.atol", p.atol)] {
            check(finite(v) && (1e-14..=0.1).contains(&v), key, v, "a value in [1e-14, 0.1]")?;
        }
        if let Some(h) = p.max_step {
            check(finite(h) && plant::MAX_STEP_RANGE.contains(&h), "plant.max_step", h, "a step in [1e-7, 1e3] s")?;
        }
        let c = &self.controller;
        let reach = 2.0 * p.l;
        check(
            finite(c.target_z_t) && c.target_z_t.abs() < reach,
            "controller.target_z_t",
            c.target_z_t,
            &format!("a finite position within the arm's reach (|z_t*| < 2 l = {reach} m)"),
        )?;
        check(
            finite(c.move_time_s) && c.move_time_s > 0.0 && c.move_time_s <= 1e5,
            "controller.move_time_s",
            c.move_time_s,
            "a value in (0, 1e5] s",
        )?;
        check(
            finite(c.f_n_ref) && (0.0..=f64::from(firmware::runaway::MAX_F_N_REF)).contains(&c.f_n_ref),
            "controller.f_n_ref",
            c.f_n_ref,
            "a value in [0, 20] N (2 N below the firmware's press check at 22 N, of the load cell's 25 N range)",
        )?;
        check(finite(c.mu_hat) && (0.0..=10.0).contains(&c.mu_hat), "controller.mu_hat", c.mu_hat, "a value in [0, 10]")?;
        if let Some(limit) = c.torque_limit_nm {
            check(
                finite(limit) && limit > 0.0 && limit <= f64::from(shared::wire::TORQUE_FULL_SCALE_NM),
                "controller.torque_limit_nm",
                limit,
                "a value in (0, 5] N m (the wire's and the drivers' full scale)",
            )?;
        }
        validate_gains("controller.pid.kp", &c.pid.kp)?;
        validate_gains("controller.pid.ki", &c.pid.ki)?;
        validate_gains("controller.pid.kd", &c.pid.kd)?;
        validate_gains("controller.hybrid.kp", &[c.hybrid.kp])?;
        validate_gains("controller.hybrid.kd", &[c.hybrid.kd])?;
        if let Some(ki) = c.hybrid.ki {
            validate_gains("controller.hybrid.ki", &[ki])?;
        }
        if let Some(model) = &c.model {
            let m = model.over(p.params());
            validate_arm("controller.model", &m)?;
            check(
                c.target_z_t.abs() < 2.0 * m.l,
                "controller.target_z_t",
                c.target_z_t,
                &format!("a position within the modelled arm's reach (|z_t*| < 2 controller.model.l = {} m)", 2.0 * m.l),
            )?;
        }
        // The firmware reads its model, the reference and the gains in f32
        // (crate::setup::firmware_config): they must hold there too, or a run would
        // stop at the firmware's configuration (found by the `scenario` fuzzing
        // harness, docs/fuzzing.md): beyond 3.4e38 is infinite in f32, a positive
        // value below 1.4e-45 is 0, and `h` or `z_t*` just under `2 l` round onto it.
        let model_section = c.model.unwrap_or_default();
        let model = model_section.over(p.params());
        let fw: Params<f32> = Params { mu: c.mu_hat, ..model }.cast();
        if let Err(e) = fw.validate() {
            let name = match e {
                ParamError::NonFinite { name, .. }
                | ParamError::NotPositive { name, .. }
                | ParamError::Negative { name, .. }
                | ParamError::AngleOutOfRange { name, .. } => name,
                ParamError::TooLarge { name, .. } => name.trim_matches('|'),
                ParamError::BeltOutOfReach { .. } => "h",
            };
            let at = ARM_KEYS.iter().position(|k| *k == name);
            let from_model = at.is_some_and(|i| model_section.values()[i].is_some());
            let key = match (name, from_model) {
                ("mu", _) => "controller.mu_hat".to_string(),
                (_, true) => format!("controller.model.{name}"),
                (_, false) => format!("plant.{name}"),
            };
            let all = [model.m, model.l, model.sigma, model.k, model.h, model.alpha0, model.g];
            check(false, &key, at.map_or(c.mu_hat, |i| all[i]), &format!("a value the firmware's f32 model holds ({e})"))?;
        }
        check(
            (c.target_z_t as f32).abs() < 2.0 * fw.l,
            "controller.target_z_t",
            c.target_z_t,
            "a position within the reach in the firmware's f32 (|z_t*| < 2 l)",
        )?;
        check((c.move_time_s as f32) > 0.0, "controller.move_time_s", c.move_time_s, "a value the firmware's f32 holds (>= 1.4e-45 s)")?;
        let t = &self.timing;
        let (lo, hi) = TimingSection::RATE_RANGE_HZ;
        check(finite(t.rate_hz) && (lo..=hi).contains(&t.rate_hz), "timing.rate_hz", t.rate_hz, "250 to 10000 Hz (docs/hardware.md)")?;
        check(
            finite(t.delta_s) && t.delta_s >= 0.0 && t.delta_s < t.period().as_secs_f64(),
            "timing.delta_s",
            t.delta_s,
            "a value in [0, one period)",
        )?;
        check(
            !self.controller.runaway_limits || t.delta_s <= TimingSection::MAX_PROTECTED_DELAY_S,
            "timing.delta_s",
            t.delta_s,
            "at most 0.4 ms with controller.runaway_limits on: the firmware's wiring and tracking checks model the command as acting at its sample, and a longer delay stops healthy arms (docs/rig.md \"Timing\"); turn the limits off to study longer delays",
        )?;
        check(
            finite(t.duration_s) && t.duration_s > 0.0 && t.duration_s <= 1e5,
            "timing.duration_s",
            t.duration_s,
            "a value in (0, 1e5] s",
        )?;
        let noise = self.sensors.load_noise_n;
        check(finite(noise) && (0.0..=25.0).contains(&noise), "sensors.load_noise_n", noise, "a value in [0, 25] N rms")?;
        let bits = self.sensors.encoder_bits;
        let (lo, hi) = shared::wire::ENCODER_BITS_RANGE;
        check((lo..=hi).contains(&bits), "sensors.encoder_bits", f64::from(bits), "10 to 16 bits")?;
        let r = &self.rig;
        check(
            finite(r.connect_timeout_s) && r.connect_timeout_s > 0.0 && r.connect_timeout_s <= 600.0,
            "rig.connect_timeout_s",
            r.connect_timeout_s,
            "a value in (0, 600] s",
        )?;
        check(
            finite(r.command_timeout_s) && r.command_timeout_s > 0.0 && r.command_timeout_s <= 60.0,
            "rig.command_timeout_s",
            r.command_timeout_s,
            "a value in (0, 60] s",
        )?;
        check(
            finite(r.stall_limit_s) && r.stall_limit_s > 0.0 && r.stall_limit_s <= 600.0,
            "rig.stall_limit_s",
            r.stall_limit_s,
            "a value in (0, 600] s",
        )?;
        check(finite(r.spin_us) && (0.0..=1e6).contains(&r.spin_us), "rig.spin_us", r.spin_us, "a value in [0, 1e6] us")?;
        check(
            finite(r.peer_check_s) && r.peer_check_s > 0.0 && r.peer_check_s <= 60.0,
            "rig.peer_check_s",
            r.peer_check_s,
            "a value in (0, 60] s",
        )?;
        check(r.max_consecutive_timeouts >= 1, "rig.max_consecutive_timeouts", r.max_consecutive_timeouts, ">= 1")?;
        if let Err(want) = r.realtime_pin() {
            check(false, "rig.realtime_cpu", format!("{:?}", r.realtime_cpu), want)?;
        }
        check(r.realtime_fifo_priority <= 99, "rig.realtime_fifo_priority", r.realtime_fifo_priority, "0 (normal scheduler) or 1 to 99")?;
        for (i, f) in self.faults.iter().enumerate() {
            if let Err(what) = f.check() {
                return Err(ScenarioError::Fault { index: i, what });
            }
            // The rule the run applies (Fault::periods): a fault whose first period
            // is past the run's last never acts, even one within the run's last half
            // period in seconds.
            let (first, periods) = (f.periods(t.period()).start, t.periods());
            if first >= periods {
                let what = format!(
                    "at_s = {} acts from period {first} (t = {} s, the first sample time at or after at_s), but the run's last \
                     period is {} (t = {} s): it would never act",
                    f.at_s,
                    t.period().sample(first).as_secs_f64(),
                    periods.saturating_sub(1),
                    t.period().sample(periods.saturating_sub(1)).as_secs_f64()
                );
                return Err(ScenarioError::Fault { index: i, what });
            }
        }
        // The firmware's own check of the configuration this scenario makes (one
        // rule, one place: `firmware::Config::validate`, which a board's
        // `Configure` and `Restore` run too), its field named by the scenario's key.
        if let Err(firmware::config::ConfigError::OutOfRange { name, value, expected }) = crate::setup::firmware_config(self).validate() {
            return Err(ScenarioError::OutOfRange {
                key: scenario_key(name),
                value: value.to_string(),
                expected: format!("{expected} (the firmware's check)"),
            });
        }
        self.board.check().map_err(ScenarioError::Board)?;
        self.calibration.check(self.timing.period().as_secs_f32()).map_err(ScenarioError::Board)?;
        // A law of one's own: its name as the firmware holds it, its values
        // numbers (their ranges are the law's, checked against its declaration
        // when the firmware announces it: `crate::law::bind`).
        if let Some(law) = &self.law {
            if law.name.is_empty() || firmware::LawName::new(&law.name).is_none() {
                return Err(ScenarioError::OutOfRange {
                    key: "law.name".into(),
                    value: format!("{:?}", law.name),
                    expected: "a law's name: 1 to 16 ASCII letters, digits, `-` or `_`".into(),
                });
            }
            if let Some((k, v)) = law.params.iter().find(|(_, v)| !v.is_finite()) {
                return Err(ScenarioError::OutOfRange {
                    key: format!("law.{k}"),
                    value: v.to_string(),
                    expected: "a finite number".into(),
                });
            }
        }
        Ok(())
    }
}

/// The scenario key that sets the firmware configuration's field `name` (as
/// `firmware::config::ConfigError` names it); the fields a scenario does not set
/// are named under `controller`.
fn scenario_key(name: &str) -> String {
    match name {
        "period_us" => "timing.rate_hz".into(),
        "torque_limit" => "controller.torque_limit_nm".into(),
        "encoder_bits" | "innovation_threshold" => "sensors.encoder_bits".into(),
        other => format!("controller.{other}"),
    }
}

/// A Unicode noncharacter (U+FDD0 to U+FDEF, and the last two code points of
/// every plane: U+FFFE, U+FFFF, ...): U+FFFE and U+FFFF are not XML 1.0
/// characters at all (an SVG holding one is ill-formed), and none is text.
/// Whether `c` is a format character (Unicode general category Cf, as of Unicode
/// 16): invisible characters that change how text around them shows, such as
/// the bidirectional overrides U+202A..U+202E and isolates U+2066..U+2069 (a
/// name with U+202E shows its end reversed), zero-width spaces and joiners, the
/// byte-order mark and the tag characters.
pub fn is_format(c: char) -> bool {
    matches!(
        u32::from(c),
        0xAD | 0x600..=0x605
            | 0x61C
            | 0x6DD
            | 0x70F
            | 0x890..=0x891
            | 0x8E2
            | 0x180E
            | 0x200B..=0x200F
            | 0x202A..=0x202E
            | 0x2060..=0x2064
            | 0x2066..=0x206F
            | 0xFEFF
            | 0xFFF9..=0xFFFB
            | 0x110BD
            | 0x110CD
            | 0x13430..=0x1343F
            | 0x1BCA0..=0x1BCA3
            | 0x1D173..=0x1D17A
            | 0xE0001
            | 0xE0020..=0xE007F
    )
}

fn is_noncharacter(c: char) -> bool {
    let u = u32::from(c);
    (0xFDD0..=0xFDEF).contains(&u) || u & 0xFFFE == 0xFFFE
}
