//! The run's log (`foxglove.Log`): what happened and when, in words, for
//! Foxglove's Log panel: a closed-loop run's lift-offs and touchdowns (true and
//! as the firmware detects them), contact mode changes, deadline misses and
//! the firmware's safe state with its reason; an open-loop run's events
//! (`events.csv`: touchdown, lift-off, `p = 0`, jam, impacts).

use foxglove::messages::{Log, log::Level};

use crate::geometry::timestamp;

/// The `name` of every log line (Foxglove's Log panel filters by it): `rig`
/// for what the plant saw, `firmware` for what the firmware reported.
pub const PLANT: &str = "plant";
/// The name of the firmware's lines.
pub const FIRMWARE: &str = "firmware";

/// A log line at time `t` (s).
pub fn line(t: f64, level: Level, name: &str, message: String) -> Log {
    Log { timestamp: Some(timestamp(t)), level: level as i32, message, name: name.into(), file: String::new(), line: 0 }
}

/// What changed between two periods of a closed-loop run, as log lines.
#[derive(Debug, Clone, Default)]
pub struct RunLog {
    last: Option<Flags>,
    /// The control law in words (`rig::scenario::Scenario::law_in_words`), logged at the first period.
    law: Option<String>,
}

/// The flags of one period that the log follows.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Flags {
    mode: &'static str,
    lift_off_true: bool,
    lift_off_detected: bool,
    safe: bool,
}

impl RunLog {
    /// The log of a run of the control law `law` (in words, `rig::scenario::Scenario::law_in_words`:
    /// `hybrid`, ``law `impedance` (k_t = 2500, the rest at their defaults)``),
    /// which its first line names (issue 84: a trace must say which law ran).
    #[must_use]
    pub fn of_law(law: String) -> Self {
        Self { last: None, law: Some(law) }
    }

    /// The control law in words, when the log was made for one ([`RunLog::of_law`]).
    #[must_use]
    pub fn law(&self) -> Option<&str> {
        self.law.as_deref()
    }

    /// The lines of period `r` against the one before: the first period's
    /// law (when known) and mode; a mode change (`sliding -> flight` is a true lift-off, `flight ->
    /// ...` a touchdown); the firmware's lift-off detection rising or falling;
    /// every deadline miss (the plant's: the previous command held; the
    /// firmware's own: `DEADLINE_MISS`); the firmware's safe state when it
    /// latches, with its reason (`rig::status_words::describe_status`).
    pub fn lines(&mut self, r: &rig::record::PeriodRecord) -> Vec<Log> {
        let now = Flags {
            mode: r.mode,
            lift_off_true: r.lift_off_true,
            lift_off_detected: r.lift_off_detected,
            safe: r.status & shared::wire::status::SAFE_STATE != 0,
        };
        let mut out = Vec::new();
        let t = r.t;
        match self.last {
            None => {
                if let Some(law) = &self.law {
                    out.push(line(t, Level::Info, FIRMWARE, format!("control law: {law}")));
                }
                out.push(line(t, Level::Info, PLANT, format!("start: contact mode {}, z_t = {:.4} m, z_n = {:.4} m", r.mode, r.z_t, r.z_n)))
            }
            Some(last) => {
                if now.mode != last.mode {
                    let (level, what) = match (last.mode, now.mode) {
                        (_, "flight") => (Level::Warning, "lift-off (true)"),
                        ("flight", _) => (Level::Info, "touchdown (true)"),
                        _ => (Level::Info, "contact mode change"),
                    };
                    out.push(line(
                        t,
                        level,
                        PLANT,
                        format!("{what}: {} -> {}, z_n = {:.5} m, f_n = {:.3} N", last.mode, now.mode, r.z_n, r.f_n),
                    ));
                }
                if now.lift_off_detected != last.lift_off_detected {
                    let what = if now.lift_off_detected { "lift-off detected" } else { "lift-off no longer detected" };
                    let truth = if r.lift_off_true { "the tip is in flight" } else { "the tip is on the belt" };
                    out.push(line(t, Level::Warning, FIRMWARE, format!("{what} ({truth})")));
                }
            }
        }
        if r.deadline_miss {
            out.push(line(t, Level::Warning, PLANT, "deadline miss: no command in time, the previous torques held".into()));
        }
        if r.firmware_deadline_miss {
            out.push(line(t, Level::Warning, FIRMWARE, format!("deadline miss counted by the firmware (overruns {})", r.overruns)));
        }
        if now.safe && !self.last.is_some_and(|l| l.safe) {
            out.push(line(t, Level::Error, FIRMWARE, rig::status_words::describe_status(r.status)));
        }
        self.last = Some(now);
        out
    }
}

/// The line of an open-loop event (a row of `events.csv`): its kind, the mode
/// after it and its velocities; `p = 0`, a jam and an impact without
/// collision are warnings.
pub fn event_line(e: &experiments::simulate::summary::EventRow) -> Log {
    let level = match e.kind {
        "lift_off" | "p_zero" | "jam" | "impact_without_collision" => Level::Warning,
        _ => Level::Info,
    };
    let mut message = format!(
        "{}: mode after {}, v_n {:.4} -> {:.4} m/s, v_r {:.4} -> {:.4} m/s",
        e.kind, e.mode_after, e.v_n_before, e.v_n_after, e.v_r_before, e.v_r_after
    );
    if !e.resolution.is_empty() {
        message.push_str(&format!(
            ", impulses ({:.4}, {:.4}) N s, energy change {:.4e} J ({})",
            e.impulse_t, e.impulse_n, e.energy_change, e.resolution
        ));
    }
    line(e.t, level, PLANT, message)
}
