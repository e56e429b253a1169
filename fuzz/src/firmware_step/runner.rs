//! A case run on the firmware beside the model: each operation applied, each
//! command checked, and what the case reached counted.

use std::cell::Cell;

use firmware::{Firmware, SafeReason, TickClock};
use shared::wire::{ActuatorCommand, status};

use super::{
    case::{Case, Op, Start},
    frames::FrameMaker,
    model::{ModelState, Observed, check_step},
};
use crate::ensure;

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

/// What the cases reached: how often each status bit and each safe-state reason
/// was seen in a command (the tests assert the generator reaches them all).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Coverage {
    /// Steps run.
    pub steps: u64,
    /// Commands with status bit `i` set, bits 0 to 9.
    pub bits: [u64; 10],
    /// Latches of each reason code (index = code, 1 to 15; `SafeReason`'s codes).
    pub reasons: [u64; 16],
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
                let frame = maker.frame(&cfg, (case.elbow_up, case.pressed), counts, *flags, seq, t);
                let now_us = match *start {
                    Start::Delay(d) => frame.t_us.saturating_add(u64::from(d)),
                    Start::Early(e) => frame.t_us.saturating_sub(e),
                    Start::At(n) => n,
                    Start::NearMax(n) => u64::MAX - u64::from(n),
                };
                let c = ScriptedClock { next: Cell::new(clock.start), elapsed: clock.elapsed, tps: clock.tps };
                let cmd = fw.step(shared::time::Instant::from_us(now_us), &frame, &c);
                let seen = Observed { frame: &frame, now_us, clock, cmd: &cmd, fw_safe: fw.safe_state(), fw_overruns: fw.overruns() };
                let was_safe = model.0.safe.is_some();
                check_step(&cfg, &mut model, &seen)
                    .map_err(|e| at(format!("{e}\n  frame {frame:?}\n  now_us {now_us}\n  command {cmd:?}")))?;
                cov.steps += 1;
                for (b, n) in cov.bits.iter_mut().enumerate() {
                    *n += u64::from(cmd.status & (1 << b) != 0);
                }
                if !was_safe && let Some(r) = model.0.safe {
                    cov.reasons[r as usize % 16] += 1;
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
                let cmd = fw.safe_command(*seq, shared::time::Instant::from_us(*now_us));
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
