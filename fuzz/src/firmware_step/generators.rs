//! The proptest strategies of the cases (module docs of `firmware_step`).

use firmware::{ControllerKind, config::FrictionCompensation};
use proptest::{option, prelude::*};
use shared::{ElbowBranch, wire::frame_flags};

use super::{
    case::{Case, Clock, Counts, MAX_OPS, Op, SeqMove, Start, TimeMove},
    knobs::Knobs,
};

fn knobs() -> impl Strategy<Value = Knobs> {
    let kind = prop_oneof![Just(ControllerKind::Pid), Just(ControllerKind::Hybrid)];
    let friction = prop_oneof![
        Just(FrictionCompensation::Measured),
        Just(FrictionCompensation::ModelMeasuredNormal),
        Just(FrictionCompensation::ModelCommandedNormal),
        Just(FrictionCompensation::None),
        Just(FrictionCompensation::Estimated),
    ];
    let branch = option::of(prop_oneof![Just(ElbowBranch::Up), Just(ElbowBranch::Down)]);
    let limit = prop_oneof![4 => 1u16..6, 1 => Just(u16::MAX)];
    (
        (0usize..6, option::of(kind), option::of(100u32..=4000), option::of(0.01f32..=5.0), option::of(limit.clone())),
        (option::of(limit), option::of(10u8..=16), option::of(branch), option::of(friction), option::of(-0.99f32..0.99)),
        (
            option::of(0.001f32..20.0),
            option::of(0.0f32..=firmware::runaway::MAX_F_N_REF),
            option::of(0.0f32..2.0),
            option::of(0.0f32..50.0),
            option::of(0.01f32..0.99),
        ),
        proptest::bool::weighted(0.25),
    )
        .prop_map(|(a, b, c, protection_off)| Knobs {
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
            protection_off,
        })
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
    (knobs(), -1.0f32..1.0, any::<bool>(), proptest::bool::weighted(0.1), seq0, t0, proptest::collection::vec(op(), 1..=MAX_OPS)).prop_map(
        |(knobs, z_t0, elbow_up, pressed, seq0, t0, mut ops)| {
            if pressed {
                // A tip driven into the belt: every frame plausible, the load cell
                // at full scale (the overload limit needs 10 ms of it in a row).
                for op in &mut ops {
                    if let Op::Step { counts, .. } = op
                        && !matches!(counts, Counts::Plausible { .. })
                    {
                        *counts = Counts::Plausible { dz_t: 0, dz_n: 0, f_t: 0, f_n: 0, belt: 0 };
                    }
                }
            }
            Case { knobs, z_t0, elbow_up, pressed, seq0, t0, ops }
        },
    )
}
