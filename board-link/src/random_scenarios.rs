//! Random admissible scenarios, reproducible: the wiring faults' sample
//! (issue 52, `board-link/tests/board/twin.rs`) and the control handler's
//! bound over random scenarios and rates on the flashed image (issue 56,
//! `board-link/tests/board/emulator_bound.rs`, `sil-host bench --only
//! emulator`).

use firmware::config::FrictionCompensation;
use rig::scenario::{DEFAULT_TOML, Scenario};

/// A reproducible uniform source in [0, 1) (xorshift64).
pub struct Uniform(u64);

impl Uniform {
    /// The source seeded with `seed` (any value but 0), its first draws skipped.
    pub fn new(seed: u64) -> Self {
        let mut r = Self(seed.max(1));
        for _ in 0..5 {
            r.draw();
        }
        r
    }

    /// The next draw.
    pub fn draw(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Random admissible scenario `i` under `kind` (`pid` or `hybrid`), `duration`
/// seconds: the paper's arm and gains from `x0d` or `x0u`, `mu` 0.3 to 0.8 (and
/// `mu_hat = mu`), `v_belt` -1 to -0.1 m/s, `f_n*` 3 to 10 N, `z_t*` -0.05 to
/// 0.14 m (below the hybrid law's `Z_t,sliding`, 0.148 m from `x0d`), any seed.
///
/// # Panics
/// For a `kind` the scenario files do not name.
pub fn random_admissible(i: u64, kind: &str, duration: f64) -> Scenario {
    let mut r = Uniform(0x9E37_79B9_7F4A_7C15 ^ (i * 7919 + 1));
    for _ in 0..5 {
        r.draw();
    }
    let x0 = if r.draw() < 0.5 { "d" } else { "u" };
    let sets = [
        format!("controller.kind={kind}"),
        format!("plant.x0={x0}"),
        format!("plant.mu={}", 0.3 + 0.5 * r.draw()),
        format!("plant.v_belt={}", -1.0 + 0.9 * r.draw()),
        format!("controller.f_n_ref={}", 3.0 + 7.0 * r.draw()),
        format!("controller.target_z_t={}", -0.05 + 0.19 * r.draw()),
        format!("sensors.seed={}", 100 + i),
        format!("timing.duration_s={duration}"),
    ];
    let overrides: Vec<_> = sets.iter().map(|a| a.parse().unwrap()).collect();
    let mut s = Scenario::from_toml_with(DEFAULT_TOML, &overrides).unwrap();
    s.controller.mu_hat = s.plant.mu;
    s
}

/// The hybrid law's friction terms (`controller.friction`), in the order a
/// sample takes them.
pub const FRICTIONS: [FrictionCompensation; 5] = [
    FrictionCompensation::ModelCommandedNormal,
    FrictionCompensation::Estimated,
    FrictionCompensation::Measured,
    FrictionCompensation::ModelMeasuredNormal,
    FrictionCompensation::None,
];

/// `f` as scenario files name it.
pub fn friction_name(f: FrictionCompensation) -> &'static str {
    match f {
        FrictionCompensation::ModelCommandedNormal => "commanded",
        FrictionCompensation::Estimated => "estimated",
        FrictionCompensation::Measured => "measured",
        FrictionCompensation::ModelMeasuredNormal => "measured_normal",
        FrictionCompensation::None => "none",
    }
}

/// The fastest belt the emulated board's counted mode runs at every rate,
/// m/s: the board drives the belt encoder's edges in the last tenth of each
/// period (its runs stop at 90 % of it), one every
/// [`board_emulator::belt::ROUND_EDGE_SPACING_TICKS`] core ticks in the
/// counted mode (0.2 us: TIM4 sees an edge only where a scheduler round is
/// cut), so at the reference board's 1e6 counts per metre a belt past about
/// 0.44 m/s (0.1 x 168 ticks/us / 34 ticks, less the lead) is refused by name
/// at every rate ("the belt moves N quadrature counts in one period: more than
/// the emulated encoder's M edges before the next tick"). A limit of the
/// counted mode, not of the image (the functional mode takes 1.4 m/s).
pub const COUNTED_BELT_SPEED_MAX: f64 = 0.4;

/// The command's delay `timing.delta_s` of the default scenario (0.2 ms) at
/// `rate_hz`, or half the period where that is not within it: the plant
/// applies a command `delta` after its sample only when `delta` is shorter
/// than the period (`rig::period_loop`; `Scenario::validate` refuses the
/// rest). The image's command leaves 15 to 20 us after the tick (the
/// acquisition's frames, then the step's start), within half of a 100 us
/// period, so the image and the twin stay equal at any rate.
pub fn delay_within(rate_hz: f64) -> f64 {
    0.0002_f64.min(0.5 / rate_hz)
}

/// A command delay `timing.delta_s` drawn uniform over what the validator
/// accepts with the protection on at a period of `ts` seconds (issue 80):
/// `[0, min(0.95 ts, MAX_PROTECTED_DELAY_S)]`, s
/// (`rig::scenario::TimingSection::MAX_PROTECTED_DELAY_S`, 0.4 ms), from
/// source `seed`.
pub fn accepted_delay(seed: u64, ts: f64) -> f64 {
    let top = (0.95 * ts).min(rig::scenario::TimingSection::MAX_PROTECTED_DELAY_S);
    top * Uniform::new(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0xd1b5_4a32_d192_ed03).draw()
}

/// A period of the image's range drawn log-uniform in `lo..=hi` us (each
/// decade as likely).
pub fn log_uniform_period_us(r: &mut Uniform, lo: u64, hi: u64) -> u64 {
    let (lo, hi) = (lo as f64, hi as f64);
    (lo * (hi / lo).powf(r.draw())).round() as u64
}

/// `s` at period `us` (an exact rate), `duration_s` long, the delay within
/// the period ([`delay_within`]).
///
/// # Panics
/// For a period the rate does not give back (none from 100 to 4 000 us).
pub fn at_period(s: &mut Scenario, us: u64, duration_s: f64) {
    s.timing.rate_hz = 1e6 / us as f64;
    s.timing.delta_s = delay_within(s.timing.rate_hz);
    s.timing.duration_s = duration_s;
    assert_eq!(s.timing.period().as_us(), us, "the rate gives the period back");
}

/// Random admissible scenario `seed` ([`random_admissible`]) under `kind`,
/// `friction` its friction term, at period `us` for `duration_s`, its belt's
/// speed mapped from -1..-0.1 m/s onto the counted mode's
/// (-[`COUNTED_BELT_SPEED_MAX`]..-0.1; the belt's speed changes no path of
/// the control handler: the count is read and differenced the same).
pub fn counted_admissible(seed: u64, kind: &str, friction: FrictionCompensation, us: u64, duration_s: f64) -> Scenario {
    let mut s = random_admissible(seed, kind, duration_s);
    s.plant.v_belt = -0.1 + (s.plant.v_belt + 0.1) * (COUNTED_BELT_SPEED_MAX - 0.1) / 0.9;
    at_period(&mut s, us, duration_s);
    s.controller.friction = friction;
    s
}

/// The paper's arm's least effective inertias `[base, elbow]`, kg m^2: the
/// PID's sampled loop on joint `j` is stable while `K_D,j Ts` stays below twice
/// it (docs/hardware.md "The envelope").
pub const PID_INERTIA_KG_M2: [f64; 2] = [0.0031, 0.00039];

/// Random PID gains of the envelope at period `ts` (s), per joint of
/// `[theta1, theta2 - theta1]`: `K_D,j` log-uniform over 5 to 80 % of its
/// sampled-loop bound `2 I_j / Ts` ([`PID_INERTIA_KG_M2`]), the base's at most
/// 10 N m s/rad; `K_P,j = K_D,j w` with `w` log-uniform over 5 to 100 1/s,
/// and `K_P,j Ts^2 <= I_j / 4`; `K_I,j = K_P,j r` with `r` log-uniform over 0.02
/// to 0.5 1/s; the elbow's gains all zero half the time (as the paper's).
pub fn random_pid_gains(r: &mut Uniform, ts: f64) -> rig::scenario::PidSection {
    let log = |r: &mut Uniform, lo: f64, hi: f64| lo * (hi / lo).powf(r.draw());
    let mut g = rig::scenario::PidSection { kp: [0.0; 2], ki: [0.0; 2], kd: [0.0; 2] };
    let elbow = r.draw() < 0.5;
    for (j, inertia) in PID_INERTIA_KG_M2.iter().enumerate().take(if elbow { 2 } else { 1 }) {
        let bound = 2.0 * inertia / ts;
        let kd = (log(r, 0.05, 0.8) * bound).min(10.0);
        let kp = (kd * log(r, 5.0, 100.0)).min(0.25 * inertia / (ts * ts));
        g.kd[j] = kd;
        g.kp[j] = kp;
        g.ki[j] = kp * log(r, 0.02, 0.5);
    }
    g
}

/// Random scenario `i` of the envelope the firmware accepts on a board
/// (docs/hardware.md "The envelope", issue 66) under `kind` (`pid` or
/// `hybrid`), `duration` seconds: `x0d` or `x0u`, `mu` 0.2 to 1.0, `mu_hat`
/// within 25 % of it (`mu_hat = mu (1 + e)`, `|e| <= 0.25`), `v_belt` -1 to
/// -0.1 m/s, `f_n*` 2 to 20 N, `z_t*` -0.05 to 0.14 m, any seed, the control
/// period log-uniform over 100 to 4 000 us (the delay within it,
/// [`delay_within`]); the hybrid law with any friction term and, half the time,
/// the paper's gains where `K'_D Ts <= 1` allows them, else random gains of
/// the validator's ranges (`K'_D` log-uniform from 30 to `min(2000, 1/Ts)`,
/// `K'_P` log-uniform from `K'_D / 10` to `min(K'_D^2, 0.25 / Ts^2)`); the PID,
/// half the time, with the paper's gains where `K_D,1 Ts` is below twice the
/// base's least effective inertia, else with random gains of the envelope
/// ([`random_pid_gains`]). Returns the scenario and a line that says what it is.
///
/// # Panics
/// For a `kind` the scenario files do not name.
pub fn random_envelope(i: u64, kind: &str, duration: f64) -> (Scenario, String) {
    let mut r = Uniform::new(0xE4F1_0000_0000 ^ (i * 104_729 + 17));
    let x0 = if r.draw() < 0.5 { "d" } else { "u" };
    let mu = 0.2 + 0.8 * r.draw();
    let mu_hat = mu * (1.0 + 0.5 * (r.draw() - 0.5));
    let sets = [
        format!("controller.kind={kind}"),
        format!("plant.x0={x0}"),
        format!("plant.mu={mu}"),
        format!("plant.v_belt={}", -1.0 + 0.9 * r.draw()),
        format!("controller.f_n_ref={}", 2.0 + 18.0 * r.draw()),
        format!("controller.target_z_t={}", -0.05 + 0.19 * r.draw()),
        format!("sensors.seed={}", 1000 + i),
        format!("timing.duration_s={duration}"),
    ];
    let overrides: Vec<_> = sets.iter().map(|a| a.parse().unwrap()).collect();
    let mut s = Scenario::from_toml_with(DEFAULT_TOML, &overrides).unwrap();
    s.controller.mu_hat = mu_hat;
    let us = log_uniform_period_us(&mut r, 100, 4000);
    at_period(&mut s, us, duration);
    let ts = us as f64 * 1e-6;
    let mut what = format!(
        "{kind} from x0{x0}, {us} us, mu {mu:.3}, mu_hat {mu_hat:.3} ({:+.0} %), v_belt {:.2}, f_n* {:.1} N, z_t* {:.3} m",
        100.0 * (mu_hat / mu - 1.0),
        s.plant.v_belt,
        s.controller.f_n_ref,
        s.controller.target_z_t
    );
    if kind == "hybrid" {
        let friction = FRICTIONS[(r.draw() * FRICTIONS.len() as f64) as usize];
        s.controller.friction = friction;
        let paper = r.draw() < 0.5 && 900.0 * ts <= 1.0;
        // The paper's K'_I (650 from x0d, 0 from x0u) where K'_I Ts <= 1 allows it,
        // else within it.
        if s.controller.hybrid.ki.unwrap_or(rig::scenario::paper_hybrid_ki(s.plant.x0)) * ts > 1.0 {
            s.controller.hybrid.ki = Some(r.draw() / ts);
        }
        if !paper {
            let kd_max = (1.0 / ts).min(2000.0);
            let kd = 30.0 * (kd_max / 30.0).powf(r.draw());
            let kp_max = (kd * kd).min(0.25 / (ts * ts));
            let kp = (kd / 10.0) * (kp_max / (kd / 10.0)).powf(r.draw());
            s.controller.hybrid.kp = kp;
            s.controller.hybrid.kd = kd;
        }
        what += &format!(", {}, K'_P {:.0}, K'_D {:.0}", friction_name(friction), s.controller.hybrid.kp, s.controller.hybrid.kd);
    } else {
        let paper = r.draw() < 0.5 && s.controller.pid.kd[0] * ts < 2.0 * PID_INERTIA_KG_M2[0];
        if !paper {
            s.controller.pid = random_pid_gains(&mut r, ts);
        }
        let g = s.controller.pid;
        what += &format!(", K_P {:.1?}, K_I {:.1?}, K_D {:.3?}", g.kp, g.ki, g.kd);
    }
    (s, what)
}
