//! The model of the firmware's frame checks, deadline monitor and safe state
//! (`firmware/src/controller/step.rs`), and the check of one command against it.

use firmware::{Config, SafeReason};
use shared::wire::{self, ActuatorCommand, SensorFrame, status};

use super::{case::Clock, frames::out_of_range};
use crate::ensure;

/// Every status bit the firmware defines: bits 0 to 9 and the reason in 24..31.
pub const DEFINED_STATUS_BITS: u32 = 0x3ff | (0xff << status::REASON_SHIFT);

/// What the model expects of the firmware across steps (the parts of its state the
/// properties need), reset with it.
#[derive(Debug, Clone, Default)]
pub(super) struct Model {
    last_seq: Option<u32>,
    bad_run: u16,
    miss_run: u16,
    pub(super) overruns: u32,
    pub(super) safe: Option<u32>,
    pub(super) last_codes: [i16; 2],
}

/// Reason codes of the safe state a trusted frame may latch in the step itself
/// (the law and the sensor checks).
const LAW_REASONS: [SafeReason; 11] = [
    SafeReason::NonFinite,
    SafeReason::Singular,
    SafeReason::Unreachable,
    SafeReason::SensorFault,
    SafeReason::Runaway,
    SafeReason::Overload,
    SafeReason::Miswired,
    SafeReason::Tracking,
    SafeReason::LiftOff,
    SafeReason::Saturated,
    SafeReason::Unstable,
];

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
pub struct ModelState(pub(super) Model);
