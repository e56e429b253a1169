//! The `pil-decode` target's generators: messages of both directions with any bit
//! pattern in every float and any value in every integer, the mutations of a
//! frame, and the four kinds of case ([`super::Case`]).

use firmware::{
    Config, ControllerKind,
    config::{FrictionCompensation, HybridGains, PidGains},
    pil::{Downlink, StepClock, Uplink},
};
use proptest::{collection::vec, prelude::*};
use shared::{
    ElbowBranch, Params, Period,
    wire::{ActuatorCommand, FirmwareTelemetry, SensorFrame},
};

use super::{Case, Msg, Mutation};

fn any_f32() -> impl Strategy<Value = f32> {
    let special = [0.0, -0.0, f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, f32::MIN_POSITIVE, 1e-45];
    prop_oneof![
        3 => -1e3f32..1e3,
        2 => any::<u32>().prop_map(f32::from_bits),
        1 => proptest::sample::select(special.to_vec()),
    ]
}

fn any_u32() -> impl Strategy<Value = u32> {
    prop_oneof![2 => 0u32..200, 1 => any::<u32>(), 1 => Just(u32::MAX)]
}

fn any_u64() -> impl Strategy<Value = u64> {
    prop_oneof![2 => 0u64..200_000, 1 => any::<u64>(), 1 => Just(u64::MAX)]
}

fn sensor_frame() -> impl Strategy<Value = SensorFrame> {
    (any_u64(), any_u32(), any::<[u16; 2]>(), any::<[i16; 3]>(), any::<u16>()).prop_map(|(t_us, seq, e, c, flags)| SensorFrame {
        t_us,
        seq,
        theta1_count: e[0],
        elbow_count: e[1],
        f_t_code: c[0],
        f_n_code: c[1],
        belt_count: c[2],
        flags,
    })
}

fn config() -> impl Strategy<Value = Config> {
    let kind = prop_oneof![Just(ControllerKind::Pid), Just(ControllerKind::Hybrid)];
    let friction = prop_oneof![
        Just(FrictionCompensation::Measured),
        Just(FrictionCompensation::ModelMeasuredNormal),
        Just(FrictionCompensation::ModelCommandedNormal),
        Just(FrictionCompensation::None),
        Just(FrictionCompensation::Estimated),
    ];
    let branch = proptest::option::of(prop_oneof![Just(ElbowBranch::Up), Just(ElbowBranch::Down)]);
    // A law's own name (or none: the paper's laws) and any eight values.
    let law = ("[a-zA-Z0-9_-]{0,16}", vec(any_f32(), 8)).prop_map(|(name, v)| firmware::LawParams {
        name: firmware::LawName::new(&name).unwrap_or(firmware::LawName::PAPER),
        values: [v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]],
    });
    (vec(any_f32(), 30), kind, friction, branch, any_u32(), any::<[u8; 4]>(), any::<[u16; 4]>(), law).prop_map(
        |(f, controller, friction, branch, period_us, b, w, law)| Config {
            params: Params { m: f[0], l: f[1], sigma: f[2], k: f[3], h: f[4], alpha0: f[5], g: f[6], mu: f[7], v_belt: f[8] },
            controller,
            period: Period::from_us(period_us.max(1)).unwrap_or(Period::MILLISECOND),
            target_z_t: f[9],
            move_time_s: f[10],
            f_n_ref: f[11],
            force_ramp_s: f[12],
            pid: PidGains { kp: [f[13], f[14]], ki: [f[15], f[16]], kd: [f[17], f[18]] },
            hybrid: HybridGains { kp: f[19], kd: f[20], ki: f[21] },
            friction,
            torque_limit: f[22],
            observer_bandwidth: f[23],
            lift_off_force: f[24],
            lift_off_height: f[25],
            lift_off_confirm: b[0],
            touchdown_force: f[26],
            sensor_contact_force: f[27],
            sensor_height_tolerance: f[28],
            sensor_fault_confirm: b[1],
            innovation_threshold: f[29],
            innovation_confirm: w[0],
            innovation_settle: w[1],
            runaway_limits: b[3] & 1 == 0,
            deadline_miss_limit: w[2],
            bad_frame_limit: w[3],
            branch,
            encoder_bits: b[2],
            law,
        },
    )
}

fn downlink() -> impl Strategy<Value = Downlink> {
    prop_oneof![
        2 => config().prop_map(Downlink::Configure),
        4 => (sensor_frame(), any_u32()).prop_map(|(frame, start_delay_us)| Downlink::Frame { frame, start_delay_us }),
        1 => Just(Downlink::End),
        1 => Just(Downlink::Hello),
    ]
}

fn uplink() -> impl Strategy<Value = Uplink> {
    let clock = prop_oneof![Just(StepClock::EmulatedSysTick), Just(StepClock::DwtCycles), Just(StepClock::Simulated)];
    let command = (any_u64(), any_u32(), any::<[i16; 2]>(), vec(any_u32(), 4)).prop_map(|(t_sent_us, seq, u, w)| ActuatorCommand {
        t_sent_us,
        seq,
        u1_code: u[0],
        u2_code: u[1],
        status: w[0],
        step_ticks: w[1],
        overruns: w[2],
        reserved: w[3],
    });
    let telemetry = (any_u32(), any_u32(), vec(any_f32(), 10)).prop_map(|(seq, status, f)| FirmwareTelemetry {
        seq,
        status,
        z_t_ref: f[0],
        f_n_ref: f[1],
        q: [f[2], f[3]],
        qd: [f[4], f[5]],
        f: [f[6], f[7]],
        u_raw: [f[8], f[9]],
    });
    prop_oneof![
        1 => (any::<u16>(), any_u32(), clock, any_u32())
            .prop_map(|(protocol, ticks_per_second, clock, law_digest)| Uplink::Hello { protocol, ticks_per_second, clock, law_digest }),
        1 => Just(Uplink::Configured),
        1 => Just(Uplink::Rejected),
        4 => (command, telemetry, any_u32()).prop_map(|(command, telemetry, frame_ticks)| Uplink::Answer { command, telemetry, frame_ticks }),
        1 => Just(Uplink::Garbled),
    ]
}

fn msg() -> impl Strategy<Value = Msg> {
    prop_oneof![downlink().prop_map(Msg::Down), uplink().prop_map(Msg::Up)]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), any::<u8>()).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Set { at, byte }),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Insert { at, byte }),
        2 => (any::<usize>(), 1u8..=8).prop_map(|(at, len)| Mutation::Delete { at, len }),
        1 => vec(any::<u8>(), 1..8).prop_map(Mutation::Append),
        1 => any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        1 => (any::<usize>(), 1u8..=16).prop_map(|(at, len)| Mutation::Duplicate { at, len }),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::Swap { a, b }),
    ]
}

/// The cases of this target.
pub fn strategy() -> impl Strategy<Value = Case> {
    prop_oneof![
        5 => (msg(), vec(mutation(), 1..=6)).prop_map(|(msg, mutations)| Case::Mutated { msg, mutations }),
        2 => (msg(), vec(any::<u8>(), 1..=16)).prop_map(|(msg, junk)| Case::Trailing { msg, junk }),
        2 => prop_oneof![vec(any::<u8>(), 0..=300), vec(prop_oneof![Just(0u8), Just(1u8), Just(0xffu8), any::<u8>()], 0..=64)]
            .prop_map(|bytes| Case::Raw { bytes }),
        1 => (vec(downlink(), 1..=6), vec(mutation(), 0..=4)).prop_map(|(msgs, mutations)| Case::StreamDown { msgs, mutations }),
        1 => (vec(uplink(), 1..=6), vec(mutation(), 0..=4)).prop_map(|(msgs, mutations)| Case::StreamUp { msgs, mutations }),
    ]
}
