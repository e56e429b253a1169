//! Target `firmware-step`: [`firmware::Firmware::step`] under arbitrary frames and times.
//!
//! A case is a valid configuration (the default, or one of `scenarios/*.toml` through
//! `rig::setup::firmware_config`, with some settings redrawn within their ranges) and
//! a script of up to [`MAX_OPS`] operations: steps, resets and a lost peer. A step's
//! frame has plausible counts (an arm near the belt, so the laws run), random counts
//! within range, arbitrary bits or edge values (0, the range ends, `MIN`/`MAX`) in
//! every field, any flags; its sequence number goes on, repeats, goes back, jumps or
//! wraps near `u32::MAX`; its stamp `t_us` goes on, back, jumps or sits near
//! `u64::MAX`; the step starts on time, late, before the frame or at any `now_us`,
//! and the step's own clock reads any ticks at any rate (0 Hz included).
//!
//! The wire's `SensorFrame` holds integers only (counts and codes): "NaN" reaches
//! the firmware as a sensor's invalid flag, which the cases set.
//!
//! The property ([`check`]) runs the firmware beside a small model of its frame
//! checks, deadline monitor and safe state (`firmware/src/controller.rs`) and asserts
//! for every command: no panic; it echoes the frame's `seq`; torque codes within the
//! 12-bit range `[-2048, 2047]` and, decoded, finite and within the configured
//! `torque_limit` (plus half a code); only defined status bits; `BAD_FRAME`,
//! `STALE_FRAME` and `SEQUENCE_GAP` exactly when the frame is out of range, flagged
//! invalid, stale or after a gap; a bad frame holds the previous command;
//! `DEADLINE_MISS` exactly when `now_us - t_us` plus the step's time reaches the
//! period, the overrun counter counting exactly these and never decreasing;
//! `t_sent_us`, `step_ticks` and `reserved` as documented; `bad_frame_limit`
//! consecutive bad frames or `deadline_miss_limit` consecutive misses latch the safe
//! state, a law or sensor fault only on a trusted frame; once latched, every command
//! is zero torque with `SAFE_STATE` and the first reason, until a reset.

use std::{cell::Cell, sync::OnceLock};

use firmware::{
    Config, ControllerKind, Firmware, SafeReason, TickClock,
    config::{FrictionCompensation, HybridGains, PidGains},
};
use nalgebra::Vector2;
use proptest::{option, prelude::*};
use shared::{
    ElbowBranch, Period,
    kinematics::inverse_kinematics,
    wire::{self, ActuatorCommand, SensorFrame, frame_flags, status},
};

use crate::ensure;

/// Most operations in one case.
pub const MAX_OPS: usize = 48;

/// Every status bit the firmware defines: bits 0 to 9 and the reason in 24..31.
pub const DEFINED_STATUS_BITS: u32 = 0x3ff | (0xff << status::REASON_SHIFT);

/// The scenarios whose firmware configurations the cases start from (besides the default).
const SCENARIOS: [&str; 5] = [
    include_str!("../../scenarios/default.toml"),
    include_str!("../../scenarios/hybrid-x0d.toml"),
    include_str!("../../scenarios/hybrid-x0u.toml"),
    include_str!("../../scenarios/pid-x0d.toml"),
    include_str!("../../scenarios/pid-x0u.toml"),
];

/// `Config::default()`, then the configurations of [`SCENARIOS`] (parsed once).
fn base_configs() -> &'static [Config] {
    static CONFIGS: OnceLock<Vec<Config>> = OnceLock::new();
    CONFIGS.get_or_init(|| {
        let from_file = SCENARIOS.iter().map(|text| {
            // The files are the repository's own: a parse failure is a build defect.
            let s = rig::scenario::Scenario::from_toml(text).unwrap_or_else(|e| panic!("scenarios/*.toml: {e}"));
            rig::setup::firmware_config(&s)
        });
        std::iter::once(Config::default()).chain(from_file).collect()
    })
}

/// Settings redrawn over a base configuration; `None` keeps the base's.
#[derive(Debug, Clone)]
pub struct Knobs {
    /// 0: `Config::default()`; 1 to 5: `firmware_config` of a scenario file.
    pub base: usize,
    /// The law.
    pub controller: Option<ControllerKind>,
    /// Period, us (100 to 4000).
    pub period_us: Option<u32>,
    /// Torque limit, N m ((0, 5]).
    pub torque_limit: Option<f32>,
    /// Consecutive deadline misses that latch the safe state.
    pub deadline_miss_limit: Option<u16>,
    /// Consecutive bad frames that latch the safe state.
    pub bad_frame_limit: Option<u16>,
    /// Encoder resolution, bits (10 to 16).
    pub encoder_bits: Option<u8>,
    /// Elbow branch of the PID.
    pub branch: Option<Option<ElbowBranch>>,
    /// The hybrid law's friction term.
    pub friction: Option<FrictionCompensation>,
    /// Tangential target as a fraction of the reach `2 l` (|.| < 1).
    pub target_fraction: Option<f32>,
    /// Move time, s.
    pub move_time_s: Option<f32>,
    /// Normal force reference, N.
    pub f_n_ref: Option<f32>,
    /// Force ramp, s.
    pub force_ramp_s: Option<f32>,
    /// Every gain multiplied by this.
    pub gain_scale: Option<f32>,
    /// Observer bandwidth as a fraction of its largest value `3/Ts`.
    pub observer_fraction: Option<f32>,
}

fn knobs() -> impl Strategy<Value = Knobs> {
    let kind = prop_oneof![Just(ControllerKind::Pid), Just(ControllerKind::Hybrid)];
    let friction = prop_oneof![
        Just(FrictionCompensation::Measured),
        Just(FrictionCompensation::ModelMeasuredNormal),
        Just(FrictionCompensation::ModelCommandedNormal),
        Just(FrictionCompensation::None),
    ];
    let branch = option::of(prop_oneof![Just(ElbowBranch::Up), Just(ElbowBranch::Down)]);
    let limit = prop_oneof![4 => 1u16..6, 1 => Just(u16::MAX)];
    (
        (0usize..6, option::of(kind), option::of(100u32..=4000), option::of(0.01f32..=5.0), option::of(limit.clone())),
        (option::of(limit), option::of(10u8..=16), option::of(branch), option::of(friction), option::of(-0.99f32..0.99)),
        (
            option::of(0.001f32..20.0),
            option::of(0.0f32..=25.0),
            option::of(0.0f32..2.0),
            option::of(0.0f32..50.0),
            option::of(0.01f32..0.99),
        ),
    )
        .prop_map(|(a, b, c)| Knobs {
            base: a.0,
            controller: a.1,
            period_us: a.2,
            torque_limit: a.3,
            deadline_miss_limit: a.4,
            bad_frame_limit: b.0,
            encoder_bits: b.1,
            branch: b.2,
            friction: b.3,
            target_fraction: b.4,
            move_time_s: c.0,
            f_n_ref: c.1,
            force_ramp_s: c.2,
            gain_scale: c.3,
            observer_fraction: c.4,
        })
}

impl Knobs {
    /// The configuration: the base with the knobs applied. Valid by construction
    /// ([`check`] fails otherwise: a generator defect).
    pub fn config(&self) -> Config {
        let mut c = base_configs()[self.base % (SCENARIOS.len() + 1)];
        if let Some(k) = self.controller {
            c.controller = k;
        }
        if let Some(us) = self.period_us {
            c.period = Period::from_us(us).unwrap_or(Period::MILLISECOND);
        }
        if let Some(t) = self.torque_limit {
            c.torque_limit = t;
        }
        if let Some(n) = self.deadline_miss_limit {
            c.deadline_miss_limit = n;
        }
        if let Some(n) = self.bad_frame_limit {
            c.bad_frame_limit = n;
        }
        if let Some(b) = self.encoder_bits {
            c.encoder_bits = b;
        }
        if let Some(b) = self.branch {
            c.branch = b;
        }
        if let Some(f) = self.friction {
            c.friction = f;
        }
        if let Some(x) = self.target_fraction {
            c.target_z_t = x * 2.0 * c.params.l;
        }
        if let Some(t) = self.move_time_s {
            c.move_time_s = t;
        }
        if let Some(f) = self.f_n_ref {
            c.f_n_ref = f;
        }
        if let Some(t) = self.force_ramp_s {
            c.force_ramp_s = t;
        }
        if let Some(s) = self.gain_scale {
            let g = c.pid;
            c.pid = PidGains { kp: g.kp.map(|x| x * s), ki: g.ki.map(|x| x * s), kd: g.kd.map(|x| x * s) };
            let h = c.hybrid;
            c.hybrid = HybridGains { kp: h.kp * s, kd: h.kd * s, ki: h.ki * s };
        }
        // Within (0, 3/Ts] at the (possibly new) period.
        let frac = self.observer_fraction.unwrap_or(0.2);
        c.observer_bandwidth = c.observer_bandwidth.min(frac * 3.0 / c.period.as_secs_f32());
        c
    }
}

/// The counts of a frame.
#[derive(Debug, Clone)]
pub enum Counts {
    /// The arm near the belt: the tip moves by `dz_t * 10 um` along it, sits
    /// `dz_n * 20 um` above it, presses with `10 + f_n * 0.05` N; belt `-0.4 + belt` m/s.
    Plausible {
        /// Tangential move, 10 um.
        dz_t: i8,
        /// Height above the belt, 20 um.
        dz_n: i8,
        /// Tangential force beyond `-mu f_n`, 20 mN.
        f_t: i8,
        /// Normal force beyond 10 N, 50 mN.
        f_n: i8,
        /// Belt speed beyond -0.4 m/s, mm/s.
        belt: i8,
    },
    /// Random counts within their ranges (encoders modulo `2^bits`).
    InRange {
        /// Base encoder.
        theta1: u16,
        /// Elbow encoder.
        elbow: u16,
        /// Load cell `f_t`.
        f_t: i16,
        /// Load cell `f_n`.
        f_n: i16,
        /// Belt speed, mm/s.
        belt: i16,
    },
    /// Arbitrary bits.
    Raw {
        /// Base encoder.
        theta1: u16,
        /// Elbow encoder.
        elbow: u16,
        /// Load cell `f_t`.
        f_t: i16,
        /// Load cell `f_n`.
        f_n: i16,
        /// Belt speed, mm/s.
        belt: i16,
    },
    /// Each field at an edge: indices into [`EDGE_U16`] and [`EDGE_I16`].
    Edge {
        /// Base encoder.
        theta1: u8,
        /// Elbow encoder.
        elbow: u8,
        /// Load cell `f_t`.
        f_t: u8,
        /// Load cell `f_n`.
        f_n: u8,
        /// Belt speed.
        belt: u8,
    },
}

/// Edge values of the encoder counts (the ends of the 10- to 16-bit ranges).
pub const EDGE_U16: [u16; 12] = [0, 1, 1023, 1024, 4095, 4096, 16383, 16384, 32767, 32768, 65534, 65535];
/// Edge values of the signed codes (load cell ends, belt limits, `i16` ends).
pub const EDGE_I16: [i16; 14] = [0, 1, -1, 2047, 2048, -2048, -2049, 5000, 5001, -5000, -5001, i16::MAX, i16::MIN, i16::MIN + 1];

/// How a frame's sequence number follows the previous frame's.
#[derive(Debug, Clone)]
pub enum SeqMove {
    /// `+1`.
    Next,
    /// The same again.
    Same,
    /// Back by this much (wrapping).
    Back(u32),
    /// Forward by this much (wrapping): a gap.
    Skip(u32),
    /// This number.
    Set(u32),
    /// `u32::MAX - n`.
    NearWrap(u8),
}

/// How a frame's `t_us` follows the previous frame's.
#[derive(Debug, Clone)]
pub enum TimeMove {
    /// `+Ts`.
    Period,
    /// Back by this much (saturating).
    Back(u64),
    /// Forward by this much (saturating).
    Forward(u64),
    /// This stamp.
    Set(u64),
    /// `u64::MAX - n`.
    NearMax(u16),
}

/// When the step starts (`now_us`), from the frame's `t_us`.
#[derive(Debug, Clone)]
pub enum Start {
    /// `t_us + d` (on time while `d < Ts`).
    Delay(u32),
    /// `t_us - e` (saturating): before the frame was sampled.
    Early(u64),
    /// Any time.
    At(u64),
    /// `u64::MAX - n`.
    NearMax(u16),
}

/// The step's own clock: reads `start`, then `start + elapsed` (wrapping), at `tps` ticks/s.
#[derive(Debug, Clone)]
pub struct Clock {
    /// First reading.
    pub start: u32,
    /// Ticks between the two readings.
    pub elapsed: u32,
    /// Ticks per second (0 included).
    pub tps: u32,
}

/// One operation of a case.
#[derive(Debug, Clone)]
pub enum Op {
    /// One step.
    Step {
        /// Counts.
        counts: Counts,
        /// Frame flags.
        flags: u16,
        /// Sequence number.
        seq: SeqMove,
        /// Stamp.
        t: TimeMove,
        /// Start of the step.
        start: Start,
        /// The step's clock.
        clock: Clock,
    },
    /// `Firmware::reset`.
    Reset,
    /// `Firmware::enter_safe_state(PeerLost)` and the safe command for `seq`.
    PeerLost {
        /// The sequence number answered.
        seq: u32,
        /// Its `now_us`.
        now_us: u64,
    },
}

/// One case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The configuration.
    pub knobs: Knobs,
    /// Where the tip starts along the belt for plausible frames, as a fraction of 0.3 m.
    pub z_t0: f32,
    /// Elbow up for plausible frames.
    pub elbow_up: bool,
    /// The first frame's sequence number.
    pub seq0: u32,
    /// The first frame's stamp `t_us`.
    pub t0: u64,
    /// The script.
    pub ops: Vec<Op>,
}

fn counts() -> impl Strategy<Value = Counts> {
    prop_oneof![
        6 => (any::<i8>(), any::<i8>(), any::<i8>(), any::<i8>(), any::<i8>())
            .prop_map(|(dz_t, dz_n, f_t, f_n, belt)| Counts::Plausible { dz_t, dz_n, f_t, f_n, belt }),
        2 => (any::<u16>(), any::<u16>(), -2048i16..=2047, -2048i16..=2047, -5000i16..=5000)
            .prop_map(|(theta1, elbow, f_t, f_n, belt)| Counts::InRange { theta1, elbow, f_t, f_n, belt }),
        1 => (any::<u16>(), any::<u16>(), any::<i16>(), any::<i16>(), any::<i16>())
            .prop_map(|(theta1, elbow, f_t, f_n, belt)| Counts::Raw { theta1, elbow, f_t, f_n, belt }),
        1 => (any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>())
            .prop_map(|(theta1, elbow, f_t, f_n, belt)| Counts::Edge { theta1, elbow, f_t, f_n, belt }),
    ]
}

fn flags() -> impl Strategy<Value = u16> {
    prop_oneof![
        12 => Just(0u16),
        2 => (0u32..6).prop_map(|b| 1u16 << b),
        1 => Just(frame_flags::END_OF_RUN),
        1 => any::<u16>(),
    ]
}

fn seq_move() -> impl Strategy<Value = SeqMove> {
    prop_oneof![
        20 => Just(SeqMove::Next),
        1 => Just(SeqMove::Same),
        1 => any::<u32>().prop_map(SeqMove::Back),
        1 => (1u32..5).prop_map(SeqMove::Back),
        1 => (2u32..10).prop_map(SeqMove::Skip),
        1 => any::<u32>().prop_map(SeqMove::Skip),
        1 => any::<u32>().prop_map(SeqMove::Set),
        1 => any::<u8>().prop_map(SeqMove::NearWrap),
    ]
}

fn time_move() -> impl Strategy<Value = TimeMove> {
    prop_oneof![
        20 => Just(TimeMove::Period),
        1 => any::<u64>().prop_map(TimeMove::Back),
        1 => (0u64..10_000).prop_map(TimeMove::Forward),
        1 => any::<u64>().prop_map(TimeMove::Forward),
        1 => any::<u64>().prop_map(TimeMove::Set),
        1 => any::<u16>().prop_map(TimeMove::NearMax),
    ]
}

fn start() -> impl Strategy<Value = Start> {
    prop_oneof![
        16 => (0u32..1000).prop_map(Start::Delay),
        3 => (0u32..10_000).prop_map(Start::Delay),
        1 => any::<u32>().prop_map(Start::Delay),
        1 => any::<u64>().prop_map(Start::Early),
        1 => any::<u64>().prop_map(Start::At),
        1 => any::<u16>().prop_map(Start::NearMax),
    ]
}

fn clock() -> impl Strategy<Value = Clock> {
    let elapsed = prop_oneof![8 => 0u32..200, 1 => 0u32..5_000_000, 1 => any::<u32>()];
    let tps = prop_oneof![6 => Just(1_000_000u32), 2 => Just(168_000_000u32), 1 => Just(0u32), 1 => any::<u32>()];
    (any::<u32>(), elapsed, tps).prop_map(|(start, elapsed, tps)| Clock { start, elapsed, tps })
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        40 => (counts(), flags(), seq_move(), time_move(), start(), clock())
            .prop_map(|(counts, flags, seq, t, start, clock)| Op::Step { counts, flags, seq, t, start, clock }),
        1 => Just(Op::Reset),
        1 => (any::<u32>(), any::<u64>()).prop_map(|(seq, now_us)| Op::PeerLost { seq, now_us }),
    ]
}

/// The cases of this target.
pub fn strategy() -> impl Strategy<Value = Case> {
    let seq0 = prop_oneof![Just(0u32), any::<u32>()];
    let t0 = prop_oneof![Just(0u64), any::<u64>()];
    (knobs(), -1.0f32..1.0, any::<bool>(), seq0, t0, proptest::collection::vec(op(), 1..=MAX_OPS))
        .prop_map(|(knobs, z_t0, elbow_up, seq0, t0, ops)| Case { knobs, z_t0, elbow_up, seq0, t0, ops })
}

/// A clock that reads `start`, then `start + elapsed`, then `start + 2 elapsed`, ...
struct ScriptedClock {
    next: Cell<u32>,
    elapsed: u32,
    tps: u32,
}

impl TickClock for ScriptedClock {
    fn ticks(&self) -> u32 {
        let t = self.next.get();
        self.next.set(t.wrapping_add(self.elapsed));
        t
    }
    fn ticks_per_second(&self) -> u32 {
        self.tps
    }
}

/// What the model expects of the firmware across steps (the parts of its state the
/// properties need), reset with it.
#[derive(Debug, Clone, Default)]
struct Model {
    last_seq: Option<u32>,
    bad_run: u16,
    miss_run: u16,
    overruns: u32,
    safe: Option<u32>,
    last_codes: [i16; 2],
}

/// The frame of a step, from the previous frame and the case's moves.
struct FrameMaker {
    seq: u32,
    t_us: u64,
    z_t: f64,
    first: bool,
}

fn edge_u16(i: u8) -> u16 {
    EDGE_U16[i as usize % EDGE_U16.len()]
}

fn edge_i16(i: u8) -> i16 {
    EDGE_I16[i as usize % EDGE_I16.len()]
}

impl FrameMaker {
    fn frame(&mut self, cfg: &Config, elbow_up: bool, counts: &Counts, flags: u16, seq: &SeqMove, t: &TimeMove) -> SensorFrame {
        let period = cfg.period.as_us();
        if self.first {
            self.first = false;
        } else {
            self.seq = match *seq {
                SeqMove::Next => self.seq.wrapping_add(1),
                SeqMove::Same => self.seq,
                SeqMove::Back(n) => self.seq.wrapping_sub(n),
                SeqMove::Skip(n) => self.seq.wrapping_add(n),
                SeqMove::Set(n) => n,
                SeqMove::NearWrap(n) => u32::MAX - u32::from(n),
            };
            self.t_us = match *t {
                TimeMove::Period => self.t_us.saturating_add(period),
                TimeMove::Back(n) => self.t_us.saturating_sub(n),
                TimeMove::Forward(n) => self.t_us.saturating_add(n),
                TimeMove::Set(n) => n,
                TimeMove::NearMax(n) => u64::MAX - u64::from(n),
            };
        }
        let bits = cfg.encoder_bits;
        let mask = (1u32 << bits) - 1;
        let (theta1_count, elbow_count, f_t_code, f_n_code, belt_count) = match *counts {
            Counts::Plausible { dz_t, dz_n, f_t, f_n, belt } => {
                let p = cfg.params;
                let (l, h) = (f64::from(p.l), f64::from(p.h));
                self.z_t = (self.z_t + f64::from(dz_t) * 1e-5).clamp(-1.9 * l, 1.9 * l);
                let z = Vector2::new(self.z_t, -h + f64::from(dz_n) * 2e-5);
                let branch = if elbow_up { ElbowBranch::Up } else { ElbowBranch::Down };
                let q = inverse_kinematics(l, &z, branch).map(|q| [q[0], q[1]]).unwrap_or([0.0, 0.0]);
                let f_n_n = 10.0 + f64::from(f_n) * 0.05;
                let f_t_n = -f64::from(p.mu) * f_n_n + f64::from(f_t) * 0.02;
                (
                    wire::encode_angle_bits(q[0], bits),
                    wire::encode_angle_bits(q[1] - q[0], bits),
                    wire::encode_force(f_t_n),
                    wire::encode_force(f_n_n),
                    -400 + i16::from(belt),
                )
            }
            Counts::InRange { theta1, elbow, f_t, f_n, belt } => {
                ((u32::from(theta1) & mask) as u16, (u32::from(elbow) & mask) as u16, f_t, f_n, belt)
            }
            Counts::Raw { theta1, elbow, f_t, f_n, belt } => (theta1, elbow, f_t, f_n, belt),
            Counts::Edge { theta1, elbow, f_t, f_n, belt } => {
                (edge_u16(theta1), edge_u16(elbow), edge_i16(f_t), edge_i16(f_n), edge_i16(belt))
            }
        };
        SensorFrame { t_us: self.t_us, seq: self.seq, theta1_count, elbow_count, f_t_code, f_n_code, belt_count, flags }
    }
}

/// Whether the firmware must refuse the frame's counts or flags (docs/hardware.md
/// "Sensors": encoders in `[0, 2^bits)`, load cell in `[-2048, 2047]`, belt within
/// +-5 m/s, no invalid flag), written independently of `firmware::decode`.
pub fn out_of_range(frame: &SensorFrame, encoder_bits: u8) -> bool {
    let counts = 1u32 << encoder_bits;
    let load = |c: i16| !(-2048..=2047).contains(&c);
    frame.flags & frame_flags::ANY_INVALID != 0
        || u32::from(frame.theta1_count) >= counts
        || u32::from(frame.elbow_count) >= counts
        || load(frame.f_t_code)
        || load(frame.f_n_code)
        || !(-5000..=5000).contains(&frame.belt_count)
}

/// Reason codes of the safe state a trusted frame may latch in the step itself
/// (the law and the sensor checks).
const LAW_REASONS: [SafeReason; 4] = [SafeReason::NonFinite, SafeReason::Singular, SafeReason::Unreachable, SafeReason::SensorFault];

/// Checks one command of a step against the model and advances it. Public so the
/// tests can show that a wrong command fails it.
///
/// # Errors
/// What is wrong, naming the field.
pub fn check_step(cfg: &Config, model: &mut ModelState, seen: &Observed<'_>) -> Result<(), String> {
    let Observed { frame, now_us, clock, cmd, fw_safe, fw_overruns } = *seen;
    let m = &mut model.0;
    ensure(cmd.seq == frame.seq, || format!("command seq {} does not echo frame seq {}", cmd.seq, frame.seq))?;
    ensure(cmd.status & !DEFINED_STATUS_BITS == 0, || format!("undefined status bits {:#x}", cmd.status & !DEFINED_STATUS_BITS))?;
    let half_code = wire::TORQUE_FULL_SCALE_NM / 2048.0 / 2.0;
    for (name, code) in [("u1_code", cmd.u1_code), ("u2_code", cmd.u2_code)] {
        ensure((wire::TORQUE_CODE_MIN..=wire::TORQUE_CODE_MAX).contains(&code), || format!("{name} = {code} outside [-2048, 2047]"))?;
        let u = wire::decode_torque(code);
        ensure(u.is_finite() && u.abs() <= cfg.torque_limit + half_code, || {
            format!("{name} = {code} decodes to {u} N m, beyond torque_limit {} N m", cfg.torque_limit)
        })?;
    }
    ensure(cmd.reserved == 0, || format!("reserved = {}", cmd.reserved))?;
    // Frame checks.
    let range_bad = out_of_range(frame, cfg.encoder_bits);
    let stale = !range_bad && m.last_seq.is_some_and(|l| frame.seq <= l);
    let bad = range_bad || stale;
    let gap = !bad && m.last_seq.is_some_and(|l| frame.seq > l.wrapping_add(1));
    let bit = |b: u32| cmd.status & b != 0;
    ensure(bit(status::BAD_FRAME) == bad, || {
        format!("BAD_FRAME = {}, expected {bad} (out of range {range_bad}, stale {stale})", bit(status::BAD_FRAME))
    })?;
    ensure(bit(status::STALE_FRAME) == stale, || format!("STALE_FRAME = {}, expected {stale}", bit(status::STALE_FRAME)))?;
    ensure(bit(status::SEQUENCE_GAP) == gap, || {
        format!("SEQUENCE_GAP = {}, expected {gap} (last trusted {:?})", bit(status::SEQUENCE_GAP), m.last_seq)
    })?;
    for (name, b) in [
        ("LIFT_OFF", status::LIFT_OFF),
        ("SATURATED_U1", status::SATURATED_U1),
        ("SATURATED_U2", status::SATURATED_U2),
        ("LOAD_CLIPPED", status::LOAD_CLIPPED),
        ("REFERENCE_MOVING", status::REFERENCE_MOVING),
    ] {
        ensure(!(bad && bit(b)), || format!("{name} set on a bad frame"))?;
    }
    let clipped = |c: i16| c == wire::LOAD_CODE_MIN || c == wire::LOAD_CODE_MAX;
    ensure(!bit(status::LOAD_CLIPPED) || clipped(frame.f_t_code) || clipped(frame.f_n_code), || {
        "LOAD_CLIPPED without a load code at an end".into()
    })?;
    let mut must_latch = None;
    if bad {
        m.bad_run = m.bad_run.saturating_add(1);
        if m.bad_run >= cfg.bad_frame_limit {
            must_latch = Some(SafeReason::BadFrames);
        }
    } else {
        m.bad_run = 0;
        m.last_seq = Some(frame.seq);
    }
    // Deadline: the step's time from the clock, in us.
    let elapsed_us = u64::from(clock.elapsed) * 1_000_000 / u64::from(clock.tps.max(1));
    let miss = now_us.saturating_sub(frame.t_us).saturating_add(elapsed_us) >= cfg.period.as_us();
    ensure(bit(status::DEADLINE_MISS) == miss, || {
        format!("DEADLINE_MISS = {}, expected {miss} (now {now_us}, t_us {}, step {elapsed_us} us)", bit(status::DEADLINE_MISS), frame.t_us)
    })?;
    ensure(cmd.step_ticks == clock.elapsed, || format!("step_ticks = {}, the clock measured {}", cmd.step_ticks, clock.elapsed))?;
    ensure(cmd.t_sent_us == now_us.saturating_add(elapsed_us), || {
        format!("t_sent_us = {}, expected now + step = {}", cmd.t_sent_us, now_us.saturating_add(elapsed_us))
    })?;
    let before = m.overruns;
    if miss {
        m.overruns = m.overruns.saturating_add(1);
        m.miss_run = m.miss_run.saturating_add(1);
        if m.miss_run >= cfg.deadline_miss_limit && must_latch.is_none() {
            must_latch = Some(SafeReason::DeadlineMisses);
        }
    } else {
        m.miss_run = 0;
    }
    ensure(cmd.overruns >= before, || format!("overruns decreased from {before} to {}", cmd.overruns))?;
    ensure(cmd.overruns == m.overruns && fw_overruns == m.overruns, || {
        format!("overruns = {} (firmware {fw_overruns}), expected {} (a miss counts one)", cmd.overruns, m.overruns)
    })?;
    // The safe state.
    let reason_bits = cmd.status >> status::REASON_SHIFT;
    let reported = SafeReason::from_status(cmd.status);
    ensure(bit(status::SAFE_STATE) || reason_bits == 0, || format!("reason bits {reason_bits} without SAFE_STATE"))?;
    ensure(!bit(status::SAFE_STATE) || reported.is_some(), || format!("SAFE_STATE with undefined reason code {reason_bits}"))?;
    ensure(reported == fw_safe, || format!("status reports {reported:?}, the firmware says {fw_safe:?}"))?;
    match (m.safe, reported) {
        (Some(was), now) => {
            ensure(now.map(|r| r as u32) == Some(was), || format!("safe state left or changed: latched {was}, now {now:?}"))?
        }
        (None, Some(r)) => {
            let allowed = match must_latch {
                // The first reason wins: a bad frame or a law fault before the deadline check.
                Some(SafeReason::BadFrames) => r == SafeReason::BadFrames,
                Some(_) => r == SafeReason::DeadlineMisses || (!bad && LAW_REASONS.contains(&r)),
                None => !bad && LAW_REASONS.contains(&r),
            };
            ensure(allowed, || {
                format!(
                    "safe state {r:?} latched; expected {must_latch:?} (bad frame {bad}, bad run {}, miss run {})",
                    m.bad_run, m.miss_run
                )
            })?;
            m.safe = Some(r as u32);
        }
        (None, None) => {
            ensure(must_latch.is_none(), || format!("{must_latch:?} not latched (bad run {}, miss run {})", m.bad_run, m.miss_run))?
        }
    }
    if m.safe.is_some() {
        ensure((cmd.u1_code, cmd.u2_code) == (0, 0), || format!("safe state with torque codes ({}, {})", cmd.u1_code, cmd.u2_code))?;
    } else if bad {
        ensure([cmd.u1_code, cmd.u2_code] == m.last_codes, || {
            format!("bad frame: codes ({}, {}) do not hold the previous {:?}", cmd.u1_code, cmd.u2_code, m.last_codes)
        })?;
    }
    m.last_codes = [cmd.u1_code, cmd.u2_code];
    Ok(())
}

/// One step as the harness saw it: the inputs and what the firmware answered.
#[derive(Debug, Clone, Copy)]
pub struct Observed<'a> {
    /// The frame.
    pub frame: &'a SensorFrame,
    /// When the step started.
    pub now_us: u64,
    /// The step's clock.
    pub clock: &'a Clock,
    /// The command.
    pub cmd: &'a ActuatorCommand,
    /// `Firmware::safe_state` after the step.
    pub fw_safe: Option<SafeReason>,
    /// `Firmware::overruns` after the step.
    pub fw_overruns: u32,
}

/// The model's state, opaque outside this module.
#[derive(Debug, Clone, Default)]
pub struct ModelState(Model);

/// What the cases reached: how often each status bit and each safe-state reason
/// was seen in a command (the tests assert the generator reaches them all).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Coverage {
    /// Steps run.
    pub steps: u64,
    /// Commands with status bit `i` set, bits 0 to 9.
    pub bits: [u64; 10],
    /// Latches of each reason code (index = code, 1 to 7).
    pub reasons: [u64; 8],
    /// Commands with non-zero torque.
    pub torque: u64,
}

/// The property of this target (module docs).
///
/// # Errors
/// What is wrong, with the operation's index.
pub fn check(case: &Case) -> Result<(), String> {
    check_covering(case, &mut Coverage::default())
}

/// [`check`], counting what the case reached into `cov`.
///
/// # Errors
/// As [`check`].
pub fn check_covering(case: &Case, cov: &mut Coverage) -> Result<(), String> {
    let cfg = case.knobs.config();
    let mut fw = Firmware::new(cfg).map_err(|e| format!("generator defect: invalid configuration: {e}"))?;
    let mut model = ModelState::default();
    let mut maker = FrameMaker { seq: case.seq0, t_us: case.t0, z_t: f64::from(case.z_t0) * 0.3, first: true };
    for (i, op) in case.ops.iter().enumerate() {
        let at = |e: String| format!("op {i}: {e}");
        match op {
            Op::Step { counts, flags, seq, t, start, clock } => {
                let frame = maker.frame(&cfg, case.elbow_up, counts, *flags, seq, t);
                let now_us = match *start {
                    Start::Delay(d) => frame.t_us.saturating_add(u64::from(d)),
                    Start::Early(e) => frame.t_us.saturating_sub(e),
                    Start::At(n) => n,
                    Start::NearMax(n) => u64::MAX - u64::from(n),
                };
                let c = ScriptedClock { next: Cell::new(clock.start), elapsed: clock.elapsed, tps: clock.tps };
                let cmd = fw.step(shared::time::Instant(now_us), &frame, &c);
                let seen = Observed { frame: &frame, now_us, clock, cmd: &cmd, fw_safe: fw.safe_state(), fw_overruns: fw.overruns() };
                let was_safe = model.0.safe.is_some();
                check_step(&cfg, &mut model, &seen)
                    .map_err(|e| at(format!("{e}\n  frame {frame:?}\n  now_us {now_us}\n  command {cmd:?}")))?;
                cov.steps += 1;
                for (b, n) in cov.bits.iter_mut().enumerate() {
                    *n += u64::from(cmd.status & (1 << b) != 0);
                }
                if !was_safe && let Some(r) = model.0.safe {
                    cov.reasons[r as usize % 8] += 1;
                }
                cov.torque += u64::from(cmd.u1_code != 0 || cmd.u2_code != 0);
            }
            Op::Reset => {
                fw.reset();
                model = ModelState::default();
                ensure(fw.safe_state().is_none() && fw.overruns() == 0, || at("reset left the safe state or the overruns".into()))?;
            }
            Op::PeerLost { seq, now_us } => {
                fw.enter_safe_state(SafeReason::PeerLost);
                let m = &mut model.0;
                if m.safe.is_none() {
                    cov.reasons[SafeReason::PeerLost as usize] += 1;
                }
                let reason = *m.safe.get_or_insert(SafeReason::PeerLost as u32);
                let cmd = fw.safe_command(*seq, shared::time::Instant(*now_us));
                let expected = ActuatorCommand {
                    t_sent_us: *now_us,
                    seq: *seq,
                    u1_code: 0,
                    u2_code: 0,
                    status: status::SAFE_STATE | (reason << status::REASON_SHIFT),
                    step_ticks: 0,
                    overruns: m.overruns,
                    reserved: 0,
                };
                ensure(cmd == expected, || at(format!("safe command {cmd:?}, expected {expected:?}")))?;
                m.last_codes = [0, 0];
            }
        }
    }
    Ok(())
}
