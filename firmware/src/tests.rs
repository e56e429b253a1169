//! Host tests of the step: hand-computed law outputs, deadline monitoring, the
//! safe state, and hostile frames.

use core::cell::Cell;

use nalgebra::Vector2;
use proptest::prelude::*;
use shared::{
    ElbowBranch,
    kinematics::{inverse_kinematics, tip_position},
    time::Instant,
    wire::{self, SensorFrame, status},
};

use crate::{
    TickClock,
    config::{Config, ControllerKind, FrictionCompensation},
    controller::{Firmware, SafeReason},
    law::{self, HybridInput, HybridState, PidState},
    reference::RefPoint,
};

/// A clock that advances by `step` ticks (1 tick = 1 us) at every read.
struct SteppingClock {
    now: Cell<u32>,
    step: u32,
}

impl TickClock for SteppingClock {
    fn ticks(&self) -> u32 {
        let t = self.now.get();
        self.now.set(t.wrapping_add(self.step));
        t
    }
    fn ticks_per_second(&self) -> u32 {
        1_000_000
    }
}

/// A frame of the arm at `q` (rad) with forces `f` (N), period `seq`.
fn frame(seq: u32, q: [f64; 2], f: [f64; 2]) -> SensorFrame {
    SensorFrame {
        t_us: seq as u64 * 1000,
        seq,
        theta1_count: wire::encode_angle(q[0]),
        elbow_count: wire::encode_angle(q[1] - q[0]),
        f_t_code: wire::encode_force(f[0]),
        f_n_code: wire::encode_force(f[1]),
        belt_count: -400,
        flags: 0,
    }
}

fn x0d() -> [f64; 2] {
    let q = inverse_kinematics(0.21, &Vector2::new(-0.16, -0.3775), ElbowBranch::Down).unwrap();
    [q[0], q[1]]
}

#[test]
fn pid_matches_hand_computed_values() {
    let cfg = Config::default();
    let arm = shared::Arm::new(cfg.params);
    let reference = RefPoint { pos: -0.1, vel: 0.0, acc: 0.0, moving: false };
    let q_ref = inverse_kinematics(0.21f32, &Vector2::new(-0.1, -0.3775), ElbowBranch::Down).unwrap();
    // theta1 off by +0.01 rad, theta2 - theta1 unchanged, theta1_dot = 0.5 rad/s.
    let q = q_ref + Vector2::new(0.01, 0.01);
    let qd = Vector2::new(0.5, 0.5);
    let mut st = PidState::default();
    let u = law::pid(&arm, &cfg.pid, ElbowBranch::Down, &reference, q, qd, &mut st, 1e-3, 5.0).unwrap();
    // e1 = -0.01, e1_dot = -0.5, int e1 = -1e-5: u1 = 200 (-0.01) + 25 (-1e-5) + 2 (-0.5).
    assert!((u[0] - (-3.00025)).abs() < 2e-4, "u1 = {}", u[0]);
    assert_eq!(u[1], 0.0, "joint-2 gains are zero");
    // Anti-windup: a huge error saturates and the integral stops growing.
    let mut st = PidState::default();
    let q_far = q_ref + Vector2::new(0.5, 0.5);
    for _ in 0..100 {
        let _ = law::pid(&arm, &cfg.pid, ElbowBranch::Down, &reference, q_far, Vector2::zeros(), &mut st, 1e-3, 5.0).unwrap();
    }
    assert_eq!(st.integral[0], 0.0, "no integration while saturated in the error's direction");
}

#[test]
fn hybrid_matches_hand_computed_values() {
    let cfg = Config::default();
    let arm = shared::Arm::new(cfg.params);
    let (l, m, g, k, a0) = (0.21f32, 0.12f32, 9.81f32, 1.3f32, 13.72f32.to_radians());
    let q = Vector2::new(0.3f32, -0.4f32);
    let z = tip_position(l, &q);
    // At rest, the reference at the tip (a_v = 0), no friction term, integral 0:
    // u_gen = w(q, 0) + J^T [0, -f_n*], motor torques [u_gen_0 + u_gen_1, u_gen_1].
    let reference = RefPoint { pos: z[0], vel: 0.0, acc: 0.0, moving: false };
    let input = HybridInput { q, qd: Vector2::zeros(), f_t: 0.0, f_n: 10.0, v_belt: -0.4 };
    let mut st = HybridState::default();
    let (u, sig) = law::hybrid(&arm, &cfg.hybrid, FrictionCompensation::None, &reference, 10.0, &input, &mut st, 1e-3, false).unwrap();
    let spring = k * (q[1] - q[0] + a0);
    let w1 = 1.5 * m * g * l * q[0].sin() - spring;
    let w2 = 0.5 * m * g * l * q[1].sin() + spring;
    let g0 = w1 - 10.0 * l * q[0].sin();
    let g1 = w2 - 10.0 * l * q[1].sin();
    assert!(sig.a_v.abs() < 1e-3 && (sig.a_f - 10.0).abs() < 1e-6);
    assert!((u[0] - (g0 + g1)).abs() < 1e-4, "u1 {} vs {}", u[0], g0 + g1);
    assert!((u[1] - g1).abs() < 1e-4, "u2 {} vs {}", u[1], g1);
    // The commanded-normal friction term adds J^T [mu s a_f, 0] with s = sign(0 - v_belt) = +1.
    let mut st = HybridState::default();
    let (u_c, _) =
        law::hybrid(&arm, &cfg.hybrid, FrictionCompensation::ModelCommandedNormal, &reference, 10.0, &input, &mut st, 1e-3, false).unwrap();
    let ft = 0.6 * 10.0;
    assert!((u_c[1] - (g1 + ft * l * q[1].cos())).abs() < 1e-4);
    assert!((u_c[0] - (g0 + g1 + ft * l * (q[0].cos() + q[1].cos()))).abs() < 1e-4);
}

#[test]
fn deadline_misses_latch_the_safe_state_until_reset() {
    let cfg = Config { deadline_miss_limit: 3, ..Config::default() };
    let mut fw = Firmware::new(cfg).unwrap();
    let q = x0d();
    let clock = SteppingClock { now: Cell::new(0), step: 50 };
    // On time: the frame is handled at t_k + 100 us and the step takes 50 us.
    for k in 0..5 {
        let c = fw.step(Instant::from_us(k as u64 * 1000 + 100), &frame(k, q, [-1.0, 2.0]), &clock);
        assert_eq!(c.status & (status::DEADLINE_MISS | status::SAFE_STATE), 0);
        assert_eq!(c.step_ticks, 50);
    }
    // Two late periods (handled 990 us late: with the step's 50 us, past the deadline).
    for k in 5..7 {
        let c = fw.step(Instant::from_us(k as u64 * 1000 + 990), &frame(k, q, [-1.0, 2.0]), &clock);
        assert_ne!(c.status & status::DEADLINE_MISS, 0, "miss detected in the period it happens");
        assert_eq!(c.status & status::SAFE_STATE, 0, "two misses are tolerated");
    }
    // An on-time period resets the run of misses.
    let c = fw.step(Instant::from_us(7000 + 100), &frame(7, q, [-1.0, 2.0]), &clock);
    assert_eq!(c.status & status::DEADLINE_MISS, 0);
    assert_eq!(fw.overruns(), 2);
    // Three in a row latch the safe state in the third.
    for k in 8..11 {
        let c = fw.step(Instant::from_us(k as u64 * 1000 + 990), &frame(k, q, [-1.0, 2.0]), &clock);
        assert_eq!(c.status & status::SAFE_STATE != 0, k == 10, "safe state at the 3rd consecutive miss (k = {k})");
    }
    // It stays, with zero torque, even when on time again.
    let c = fw.step(Instant::from_us(11_000 + 100), &frame(11, q, [-1.0, 2.0]), &clock);
    assert_eq!((c.u1_code, c.u2_code), (0, 0));
    assert_eq!(SafeReason::from_status(c.status), Some(SafeReason::DeadlineMisses));
    assert_eq!(c.overruns, 5);
    fw.reset();
    let c = fw.step(Instant::from_us(12_000 + 100), &frame(12, q, [-1.0, 2.0]), &clock);
    assert_eq!(c.status & status::SAFE_STATE, 0, "reset leaves the safe state");
    assert_ne!((c.u1_code, c.u2_code), (0, 0));
}

proptest! {
    /// Our rule for docs/hardware.md "Faults" (which leaves the count open): N consecutive
    /// misses drive the firmware to its safe state within N + 1 periods, for any limit N and any pattern of isolated misses before; the
    /// overrun counter counts every miss, in the period it happens.
    #[test]
    fn n_consecutive_misses_latch_the_safe_state_in_the_nth_and_overruns_count_every_miss(
        limit in 1u16..12,
        isolated in proptest::collection::vec(any::<bool>(), 0..30),
    ) {
        // The frames hold the arm still under the law's torque (a stalled arm): the
        // wiring check would stop it after 5 ms; this property is the deadline rule's alone.
        let mut fw = Firmware::new(Config { deadline_miss_limit: limit, runaway_limits: false, ..Config::default() }).unwrap();
        let q = x0d();
        let clock = SteppingClock { now: Cell::new(0), step: 50 };
        let mut seq = 0u32;
        let mut misses = 0u32;
        let mut step = |late: bool, fw: &mut Firmware<crate::PaperLaws>| {
            let c = fw.step(Instant::from_us(seq as u64 * 1000 + if late { 990 } else { 100 }), &frame(seq, q, [-1.0, 2.0]), &clock);
            seq += 1;
            c
        };
        // Isolated misses (never two in a row when the limit is 2 or more, never one
        // when it is 1) do not latch it.
        for (i, &late) in isolated.iter().enumerate() {
            let late = late && i % 2 == 0 && limit > 1;
            let c = step(late, &mut fw);
            misses += u32::from(late);
            prop_assert_eq!(c.status & status::DEADLINE_MISS != 0, late);
            prop_assert_eq!(c.overruns, misses);
            prop_assert_eq!(c.status & status::SAFE_STATE, 0);
        }
        step(false, &mut fw);
        for n in 1..=limit {
            let c = step(true, &mut fw);
            misses += 1;
            prop_assert_eq!(c.overruns, misses);
            prop_assert_eq!(c.status & status::SAFE_STATE != 0, n == limit, "safe state at miss {} of {}", n, limit);
        }
    }
}

proptest! {
    /// The deadline rule at the edges of the `u64` clock (issue 15): a command is a
    /// miss exactly when `(now - t_k) + elapsed >= Ts`, computed without overflow
    /// (here in `u128`); a clock read before the frame's stamp counts as on time.
    #[test]
    fn the_deadline_rule_holds_at_the_u64_edges(
        t_us in prop_oneof![Just(0u64), Just(u64::MAX), Just(u64::MAX - 999), any::<u64>()],
        late in prop_oneof![Just(0u64), Just(u64::MAX), 0u64..5000, any::<u64>()],
        step in prop_oneof![Just(0u32), Just(u32::MAX), 0u32..3000],
    ) {
        let mut fw = Firmware::new(Config::default()).unwrap();
        let clock = SteppingClock { now: Cell::new(0), step };
        let now_us = t_us.saturating_add(late);
        let f = SensorFrame { t_us, ..frame(1, x0d(), [-1.0, 2.0]) };
        let c = fw.step(Instant::from_us(now_us), &f, &clock);
        // The clock ticks at 1 MHz: one tick is one microsecond.
        let elapsed = u128::from(step);
        let lateness = u128::from(now_us.saturating_sub(t_us));
        let miss = lateness + elapsed >= u128::from(Config::default().period.as_us());
        prop_assert_eq!(c.status & status::DEADLINE_MISS != 0, miss, "t {} now {} step {}", t_us, now_us, step);
        prop_assert_eq!(fw.overruns(), u32::from(miss));
    }
}

#[test]
fn bad_and_stale_frames_are_never_trusted() {
    let mut fw = Firmware::new(Config::default()).unwrap();
    let q = x0d();
    let clock = crate::board::FrozenClock;
    let good = fw.step(Instant::from_us(0), &frame(0, q, [-1.0, 2.0]), &clock);
    let good = fw.step(Instant::from_us(1000), &frame(1, q, [-1.0, 2.0]), &clock).u1_code.max(good.u1_code);
    let _ = good;
    let held = fw.step(Instant::from_us(2000), &frame(2, q, [-1.0, 2.0]), &clock);
    // A repeated sequence number: stale, previous command held.
    let c = fw.step(Instant::from_us(2000), &frame(2, q, [-1.0, 2.0]), &clock);
    assert_ne!(c.status & status::STALE_FRAME, 0);
    assert_eq!((c.u1_code, c.u2_code), (held.u1_code, held.u2_code));
    // A skipped period is accepted and reported.
    let c = fw.step(Instant::from_us(5000), &frame(5, q, [-1.0, 2.0]), &clock);
    assert_ne!(c.status & status::SEQUENCE_GAP, 0);
    assert_eq!(c.status & status::BAD_FRAME, 0);
    // Three corrupt frames in a row latch the safe state.
    for k in 6..9 {
        let mut f = frame(k, q, [-1.0, 2.0]);
        f.theta1_count = 0xFFFF;
        let c = fw.step(Instant::from_us(k as u64 * 1000), &f, &clock);
        assert_ne!(c.status & status::BAD_FRAME, 0);
        assert_eq!(c.status & status::SAFE_STATE != 0, k == 8);
    }
    assert_eq!(fw.safe_state(), Some(SafeReason::BadFrames));
}

#[test]
fn hybrid_near_a_straight_arm_goes_safe_not_nan() {
    let mut fw = Firmware::new(Config::default()).unwrap();
    // theta1 = theta2: the arm is straight, J is singular.
    let c = fw.step(Instant::from_us(0), &frame(0, [0.2, 0.2], [0.0, 5.0]), &crate::board::FrozenClock);
    assert_eq!(SafeReason::from_status(c.status), Some(SafeReason::Singular));
    assert_eq!((c.u1_code, c.u2_code), (0, 0));
}

#[test]
fn pid_with_an_unreachable_target_goes_safe() {
    let cfg = Config { controller: ControllerKind::Pid, target_z_t: 0.3, move_time_s: 0.01, ..Config::default() };
    let mut fw = Firmware::new(cfg).unwrap();
    let q = x0d();
    let mut last = None;
    for k in 0..20 {
        last = Some(fw.step(Instant::from_us(k as u64 * 1000), &frame(k, q, [-1.0, 2.0]), &crate::board::FrozenClock));
    }
    assert_eq!(SafeReason::from_status(last.unwrap().status), Some(SafeReason::Unreachable));
}

#[test]
fn invalid_configurations_are_rejected_with_the_field_named() {
    let bad = Config { period: shared::Period::from_us(100_000).unwrap(), ..Config::default() };
    assert!(matches!(Firmware::new(bad), Err(crate::config::ConfigError::OutOfRange { name: "period_us", .. })));
    let bad = Config { f_n_ref: f32::NAN, ..Config::default() };
    assert!(matches!(Firmware::new(bad), Err(crate::config::ConfigError::OutOfRange { name: "f_n_ref", .. })));
}

proptest! {
    /// Random and hostile frames after a good start: never a panic, codes in range,
    /// and the safe state means zero torque.
    #[test]
    fn hostile_frames_never_panic(frames in proptest::collection::vec(
        (any::<u32>(), any::<u16>(), any::<u16>(), any::<i16>(), any::<i16>(), any::<i16>(), any::<u64>()), 1..60),
        controller_is_pid in any::<bool>(),
    ) {
        let cfg = Config { controller: if controller_is_pid { ControllerKind::Pid } else { ControllerKind::Hybrid }, ..Config::default() };
        let mut fw = Firmware::new(cfg).unwrap();
        let clock = SteppingClock { now: Cell::new(0), step: 7 };
        let _ = fw.step(Instant::from_us(0), &frame(0, x0d(), [-1.0, 2.0]), &clock);
        for (seq, c1, c2, ft, fnn, belt, now) in frames {
            let f = SensorFrame { t_us: seq as u64 * 1000, seq, theta1_count: c1, elbow_count: c2, f_t_code: ft, f_n_code: fnn, belt_count: belt, flags: 0 };
            let c = fw.step(Instant::from_us(now), &f, &clock);
            prop_assert_eq!(c.seq, seq);
            prop_assert!((wire::TORQUE_CODE_MIN..=wire::TORQUE_CODE_MAX).contains(&c.u1_code));
            prop_assert!((wire::TORQUE_CODE_MIN..=wire::TORQUE_CODE_MAX).contains(&c.u2_code));
            if c.status & status::SAFE_STATE != 0 {
                prop_assert_eq!((c.u1_code, c.u2_code), (0, 0));
                prop_assert!(SafeReason::from_status(c.status).is_some());
            }
            let t = fw.telemetry();
            prop_assert!(t.u_raw.iter().all(|u| u.is_finite()));
        }
    }
}

#[test]
fn torque_saturation_is_reported_in_the_status_word() {
    // A PID reference 10 cm away at once (move time one period): u1 saturates.
    let cfg = Config { controller: ControllerKind::Pid, target_z_t: -0.06, move_time_s: 1e-3, ..Config::default() };
    let mut fw = Firmware::new(cfg).unwrap();
    let q = x0d();
    let _ = fw.step(Instant::from_us(0), &frame(0, q, [-1.0, 2.0]), &crate::board::FrozenClock);
    let c = fw.step(Instant::from_us(1000), &frame(1, q, [-1.0, 2.0]), &crate::board::FrozenClock);
    assert_ne!(c.status & status::SATURATED_U1, 0);
    assert_eq!(c.u1_code.abs().max(2047), 2047);
    assert!(c.u1_code == wire::TORQUE_CODE_MAX || c.u1_code == wire::TORQUE_CODE_MIN);
    assert!(fw.telemetry().u_raw[0].abs() > 5.0, "the law asked for more than the motor gives");
}

/// Issue 70: the paper's laws as [`crate::ControlLaw`]s. Each alone runs the
/// step bit for bit as [`crate::PaperLaws`] with the configuration's
/// `controller` naming it (the whole command and telemetry, every period of
/// a sliding arm with noisy forces); a law whose torques are not finite is
/// stopped by the step's own check. (That the tracking check follows what a
/// law declares needs a plant: the rig's tests, with a law of one's own.)
mod control_law {
    use super::*;
    use crate::{ControlLaw, Declares, HybridLaw, LawContext, LawInput, LawOutput, PaperLaws, PidLaw, law::LawError};

    /// Frames of the arm sliding from `x0d` towards `z_t = 0.1` m, with a wobble in
    /// the angles and the forces (deterministic), period by period.
    fn frames(n: u32) -> impl Iterator<Item = SensorFrame> {
        let q0 = x0d();
        (0..n).map(move |k| {
            let t = f64::from(k) * 1e-3;
            let dq = 0.02 * (t * 3.0).sin();
            frame(k, [q0[0] + dq, q0[1] + 0.7 * dq], [-6.0 + (t * 40.0).sin(), 10.0 + 0.5 * (t * 17.0).cos()])
        })
    }

    /// The commands and telemetry of `n` steps of `fw`.
    fn run<L: ControlLaw>(fw: &mut Firmware<L>, n: u32) -> Vec<(wire::ActuatorCommand, [u32; 10])> {
        let clock = SteppingClock { now: Cell::new(0), step: 20 };
        frames(n)
            .map(|f| {
                let c = fw.step(Instant::from_us(f.t_us + 100), &f, &clock);
                let t = fw.telemetry();
                let bits =
                    [t.q[0], t.q[1], t.qd[0], t.qd[1], t.z_t_ref, t.f_n_ref, t.f[0], t.f[1], t.u_raw[0], t.u_raw[1]].map(f32::to_bits);
                (c, bits)
            })
            .collect()
    }

    #[test]
    fn each_paper_law_alone_is_paper_laws_bit_for_bit() {
        for friction in [FrictionCompensation::ModelCommandedNormal, FrictionCompensation::Estimated, FrictionCompensation::Measured] {
            let cfg = Config { controller: ControllerKind::Hybrid, friction, ..Config::default() };
            let (a, b) = (
                run(&mut Firmware::<PaperLaws>::with_law(cfg).unwrap(), 3000),
                run(&mut Firmware::<HybridLaw>::with_law(cfg).unwrap(), 3000),
            );
            assert!(a.iter().any(|(c, _)| c.u1_code != 0), "the law acts");
            assert_eq!(a, b, "{friction:?}");
        }
        let cfg = Config { controller: ControllerKind::Pid, ..Config::default() };
        assert_eq!(
            run(&mut Firmware::<PaperLaws>::with_law(cfg).unwrap(), 3000),
            run(&mut Firmware::<PidLaw>::with_law(cfg).unwrap(), 3000)
        );
    }

    /// A law that answers fixed torques `u` (N m) and declares the hybrid law's
    /// tracking dynamics or none ([`FIXED_U`], set per test under [`FIXED_LOCK`]).
    #[derive(Debug, Clone, Copy)]
    struct Fixed {
        u: [f32; 2],
        disturbance: f32,
    }

    static FIXED_U: std::sync::Mutex<([f32; 2], bool, f32)> = std::sync::Mutex::new(([0.0; 2], false, 0.0));

    impl ControlLaw for Fixed {
        const SPEC: crate::LawSpec = crate::LawSpec {
            name: "fixed",
            source: "a test",
            params: &[crate::ParamSpec { name: "gain", unit: "1", min: 0.0, max: 2.0, default: 1.0 }],
        };
        fn fresh(_cfg: &Config) -> Self {
            let fixed = *FIXED_U.lock().unwrap();
            Self { u: fixed.0, disturbance: fixed.2 }
        }
        fn declares(cfg: &Config) -> Declares {
            let tracking = FIXED_U.lock().unwrap().1.then(|| HybridLaw::declares(cfg).tracking).flatten();
            Declares { tracking, on_belt: tracking.is_some(), uses_reference_acceleration: false }
        }
        fn step(&mut self, _ctx: &LawContext<'_>, _input: &LawInput) -> Result<LawOutput, LawError> {
            Ok(LawOutput { u: self.u, disturbance: self.disturbance })
        }
    }

    /// Runs [`Fixed`] answering `u`, declaring tracking or not; the safe state's reason, if any.
    fn fixed(u: [f32; 2], tracks: bool, n: u32) -> Option<SafeReason> {
        fixed_with(u, 0.0, tracks, n)
    }

    /// [`fixed`] with the disturbance bound `disturbance` (m/s^2).
    fn fixed_with(u: [f32; 2], disturbance: f32, tracks: bool, n: u32) -> Option<SafeReason> {
        let _guard = FIXED_LOCK.lock().unwrap();
        *FIXED_U.lock().unwrap() = (u, tracks, disturbance);
        let mut fw = Firmware::<Fixed>::with_law(Config { law: Fixed::SPEC.defaults(), ..Config::default() }).unwrap();
        run(&mut fw, n);
        fw.safe_state()
    }

    #[test]
    fn a_configuration_for_another_law_or_out_of_the_laws_range_is_refused() {
        use crate::config::ConfigError;
        let own = Config { law: Fixed::SPEC.defaults(), ..Config::default() };
        assert!(matches!(Firmware::<Fixed>::with_law(Config::default()), Err(ConfigError::WrongLaw { .. })));
        assert!(matches!(Firmware::<PaperLaws>::with_law(own), Err(ConfigError::WrongLaw { .. })));
        let e = Firmware::new(own).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the configuration is for fixed, this firmware runs the paper's laws: build the law's own firmware, or give the scenario its `[law]` table"
        );
        for bad in [-0.1, 2.5, f32::NAN] {
            let mut cfg = own;
            cfg.law.values[0] = bad;
            let e = Firmware::<Fixed>::with_law(cfg).unwrap_err();
            assert!(matches!(e, ConfigError::LawParam { name: "gain", .. }), "{bad}: {e}");
        }
        // The firmware's own checks come first.
        let bad = Config { f_n_ref: -1.0, ..own };
        assert!(matches!(Firmware::<Fixed>::with_law(bad), Err(ConfigError::OutOfRange { name: "f_n_ref", .. })));
    }

    static FIXED_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

    /// Whatever a law declares (tracking or not), a non-finite torque or
    /// disturbance bound stops it at the first period it returns one (issue 80:
    /// a law could once declare it checked its own and run at zero torque).
    #[test]
    fn a_law_whose_torques_are_not_finite_is_stopped_by_the_step() {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for tracks in [false, true] {
                assert_eq!(fixed([0.1, bad], tracks, 1), Some(SafeReason::NonFinite), "{bad}, tracks {tracks}");
                assert_eq!(fixed([bad, 0.0], tracks, 1), Some(SafeReason::NonFinite), "{bad}, tracks {tracks}");
                assert_eq!(fixed_with([0.1, 0.0], bad, tracks, 1), Some(SafeReason::NonFinite), "disturbance {bad}, tracks {tracks}");
            }
        }
        assert_eq!(fixed([0.1, -0.1], false, 5), None, "finite torques run");
        assert_eq!(fixed_with([0.1, -0.1], 3.0, true, 5), None, "a finite bound runs");
    }
}
