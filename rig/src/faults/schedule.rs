//! Seeded random fault schedules (the soak test's, `scripts/soak.sh`): windows of
//! faults that each stay short of the firmware's safe state.

use super::{Fault, FaultKind, LinkKind, Signal};

/// What [`random_schedule`] draws: how many fault windows, over which span of
/// sample time, and the bounds that keep every fault short of the firmware's safe
/// state, so that a long run (the soak test, `tests/soak.rs`) goes on after
/// each one and every fault's effect can be checked on its own.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomSchedule {
    /// Seed of the generator (ChaCha8): the same settings give the same schedule.
    pub seed: u64,
    /// The kinds drawn from, uniformly. [`FaultKind::KillFirmware`] ends the run
    /// and is refused: add it after the schedule's end if wanted.
    pub kinds: Vec<FaultKind>,
    /// Number of windows (at most 1000, a scenario's limit).
    pub count: usize,
    /// Windows start at or after this sample time, s.
    pub from_s: f64,
    /// Every window, and the periods a fault reaches past it (a stall's late
    /// answers, the recovery period after bad frames), ends before this sample time, s.
    pub to_s: f64,
    /// Control period `Ts`, s (the scenario's `timing.period()`).
    pub ts: f64,
    /// Most consecutive periods the firmware may count as missed or bad: one
    /// less than the smaller of its `deadline_miss_limit` and `bad_frame_limit`
    /// (3 by default, so 2). Bounds `late_command` past the deadline,
    /// `nan_sensor`, `out_of_range` (periods) and the misses a stall causes.
    pub max_in_a_row: u32,
    /// Longest window of the faults without a limit (`drop_command`,
    /// `stuck_sensor`, `late_command` within the deadline), periods, >= 1.
    pub max_window: u32,
    /// The plant's lockstep command timeout (`rig.command_timeout_s`), s: a stall
    /// lasts `(n + 1/2)` timeouts of wall time, `n` drawn in
    /// `0..=max_stall_timeouts`, so that the plant times out `n` periods, half a
    /// timeout from either boundary (the stall is in (0, 60] s:
    /// `(max_stall_timeouts + 1/2)` timeouts must fit).
    pub command_timeout_s: f64,
    /// Most periods a stall is drawn to time out (`n` above), at most
    /// `max_in_a_row`. A stall is wall time against the plant's wall-clock
    /// timeouts: a firmware that wakes more than half a timeout late (a machine
    /// under load) makes the plant time out `n + 1` periods, and both sides count
    /// them (docs/rig.md "Soak test"). `max_in_a_row - 1` keeps that extra one
    /// short of the safe state; `max_in_a_row` draws the longest stall the
    /// firmware survives on an idle machine.
    pub max_stall_timeouts: u32,
}

impl RandomSchedule {
    /// The kinds the iceoryx2 lockstep link injects that leave the run going:
    /// all of [`LinkKind::Ipc`]'s but [`FaultKind::KillFirmware`].
    pub fn survivable_ipc_kinds() -> Vec<FaultKind> {
        LinkKind::Ipc.injectable().iter().copied().filter(|k| *k != FaultKind::KillFirmware).collect()
    }

    /// Periods a window of `kind` may reach, from its first period to the last it
    /// affects (the window, plus a stall's misses and the answer after them, plus
    /// the recovery period after bad frames).
    fn span_periods(&self, kind: FaultKind) -> u64 {
        let n = u64::from(self.max_in_a_row);
        match kind {
            FaultKind::Stall => u64::from(self.max_stall_timeouts.min(self.max_in_a_row)) + 1,
            FaultKind::NanSensor | FaultKind::OutOfRange => n + 1,
            FaultKind::LateCommand => n.max(u64::from(self.max_window)),
            _ => u64::from(self.max_window),
        }
    }
}

/// A seeded random schedule of non-overlapping fault windows (the soak test's,
/// `scripts/soak.sh`): the span `[from_s, to_s)` is cut into `count` equal
/// slots of whole periods, and each slot holds one window of a kind drawn
/// uniformly from `kinds`, at a random start (a whole period) with at least
/// two clean periods after everything it affects. Within a kind:
///
/// - `drop_command`, `stuck_sensor`: 1 to `max_window` periods (a sensor fault's
///   `signal` drawn from the five);
/// - `late_command`: half of them on time (`delay_s` from 1 us to `Ts - 1 us`, 1
///   to `max_window` periods), half past the deadline (`delay_s` from `Ts` to
///   `3 Ts`, 1 to `max_in_a_row` periods); delays are whole microseconds, as the
///   firmware's clock counts them;
/// - `nan_sensor`, `out_of_range`: 1 to `max_in_a_row` periods;
/// - `stall`: `(n + 1/2) command_timeout_s` of wall time, `n` in `0..=max_stall_timeouts`.
///
/// Windows start at `k Ts` and last `n Ts` exactly (`duration_s`), so each hits
/// periods `k..k+n`.
///
/// # Errors
/// A message when the settings cannot give such a schedule: no kinds or
/// `kill_firmware` among them, `count` outside 1 to 1000, a non-finite or empty
/// span, a period outside (0, 1] s, `max_in_a_row` or `max_window` of 0,
/// `max_stall_timeouts` above `max_in_a_row`, slots too short for the longest
/// window plus two clean periods, or a stall longer than 60 s.
pub fn random_schedule(spec: &RandomSchedule) -> Result<Vec<Fault>, String> {
    use rand::{RngExt, SeedableRng};

    let ts = spec.ts;
    if spec.kinds.is_empty() {
        return Err("no fault kinds to draw from".into());
    }
    if spec.kinds.contains(&FaultKind::KillFirmware) {
        return Err("kill_firmware ends the run: add it after the schedule's end, not among its kinds".into());
    }
    if !(1..=1000).contains(&spec.count) {
        return Err(format!("count = {}: 1 to 1000 windows (a scenario's limit)", spec.count));
    }
    if !(ts.is_finite() && ts > 0.0 && ts <= 1.0) {
        return Err(format!("ts = {ts}: a period in (0, 1] s"));
    }
    if !(spec.from_s.is_finite() && spec.to_s.is_finite() && spec.from_s >= 0.0 && spec.to_s > spec.from_s) {
        return Err(format!("span [{}, {}) s: finite, from >= 0, to > from", spec.from_s, spec.to_s));
    }
    if spec.max_in_a_row == 0 || spec.max_window == 0 {
        return Err("max_in_a_row and max_window: at least 1 period".into());
    }
    if spec.max_stall_timeouts > spec.max_in_a_row {
        return Err(format!(
            "max_stall_timeouts = {}: at most max_in_a_row = {} (more periods timed out in a row latch the safe state)",
            spec.max_stall_timeouts, spec.max_in_a_row
        ));
    }
    let longest_stall = (f64::from(spec.max_stall_timeouts) + 0.5) * spec.command_timeout_s;
    if spec.kinds.contains(&FaultKind::Stall) && !(spec.command_timeout_s > 0.0 && longest_stall <= 60.0) {
        return Err(format!("a stall of up to {longest_stall} s: command_timeout_s > 0 and (max_stall_timeouts + 1/2) timeouts <= 60 s"));
    }
    let first = (spec.from_s / ts).ceil() as u64;
    let last = (spec.to_s / ts).floor() as u64;
    let slot = last.saturating_sub(first) / spec.count as u64;
    let longest = spec.kinds.iter().map(|k| spec.span_periods(*k)).max().unwrap_or(1);
    if slot < longest + 2 {
        return Err(format!(
            "{} windows in [{}, {}) s leave {slot} periods each: at least {} needed (the longest window and two clean periods)",
            spec.count,
            spec.from_s,
            spec.to_s,
            longest + 2
        ));
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(spec.seed);
    const SIGNALS: [Signal; 5] = [Signal::Theta1, Signal::Elbow, Signal::FT, Signal::FN, Signal::Belt];
    let period_us = (ts * 1e6).round() as u64;
    let mut faults = Vec::with_capacity(spec.count);
    for i in 0..spec.count as u64 {
        let kind = spec.kinds[rng.random_range(0..spec.kinds.len())];
        let (periods, delay_s, duration_s) = match kind {
            FaultKind::LateCommand if rng.random::<bool>() => {
                let us = rng.random_range(period_us..=3 * period_us);
                (rng.random_range(1..=spec.max_in_a_row), us as f64 * 1e-6, None)
            }
            FaultKind::LateCommand => {
                let us = rng.random_range(1..period_us.max(2));
                (rng.random_range(1..=spec.max_window), us as f64 * 1e-6, None)
            }
            FaultKind::NanSensor | FaultKind::OutOfRange => (rng.random_range(1..=spec.max_in_a_row), 0.0, None),
            FaultKind::Stall => {
                let n = rng.random_range(0..=spec.max_stall_timeouts);
                (1, 0.0, Some((f64::from(n) + 0.5) * spec.command_timeout_s))
            }
            _ => (rng.random_range(1..=spec.max_window), 0.0, None),
        };
        let start = first + i * slot + rng.random_range(0..=slot - spec.span_periods(kind) - 2);
        let signal = matches!(kind, FaultKind::StuckSensor | FaultKind::NanSensor | FaultKind::OutOfRange)
            .then(|| SIGNALS[rng.random_range(0..SIGNALS.len())]);
        faults.push(Fault { delay_s, signal, ..Fault::new(kind, start as f64 * ts, duration_s.unwrap_or(f64::from(periods) * ts)) });
    }
    Ok(faults)
}
