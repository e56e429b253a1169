//! What a SIL run records: one row per control period (`trace.csv`), why a run
//! stopped early, and the lift-off detection statistics (docs/hardware.md "Lift-off
//! detection").

use serde::Serialize;

use plant::{Sample, SimError};

tables::table_row! {
    /// One control period of a run (a row of `trace.csv` of `run` and `pil`: the
    /// fields in order, the header the `csv` crate derived from them;
    /// experiments/src/run.rs's test checks the bytes against it).
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
    pub struct PeriodRecord {
        /// Sample time `t_k`, s.
        pub t: f64 => f64,
        /// True state at `t_k` (rad, rad/s).
        pub theta1: f64 => f64,
        /// `theta1_dot`, rad/s.
        pub theta1_dot: f64 => f64,
        /// `theta2`, rad.
        pub theta2: f64 => f64,
        /// `theta2_dot`, rad/s.
        pub theta2_dot: f64 => f64,
        /// Tip `z_t`, m.
        pub z_t: f64 => f64,
        /// Tip `z_n`, m.
        pub z_n: f64 => f64,
        /// Reference `z_t*` (the firmware's), m.
        pub z_t_ref: f64 => f64,
        /// True tangential contact force at `t_k`, N.
        pub f_t: f64 => f64,
        /// True normal contact force at `t_k`, N.
        pub f_n: f64 => f64,
        /// True contact mode at `t_k` (read back by its name, [`mode_named`]).
        #[serde(deserialize_with = "mode_named")]
        pub mode: ModeName => str,
        /// Motor torques that take effect in period `k`, N m (after quantisation; the
        /// previous command again when this period's was missed).
        pub u1_cmd: f64 => f64,
        /// Commanded `u2`, N m.
        pub u2_cmd: f64 => f64,
        /// Torques applied at `t_k` (the previous command), N m.
        pub u1_applied: f64 => f64,
        /// Applied `u2`, N m.
        pub u2_applied: f64 => f64,
        /// True lift-off (the tip in flight at `t_k`).
        pub lift_off_true: bool => bool,
        /// Lift-off as the firmware reports it.
        pub lift_off_detected: bool => bool,
        /// Deadline miss seen by the plant: no command, a lost one, or one that left
        /// after `t_k + Ts`; the previous command was held.
        pub deadline_miss: bool => bool,
        /// Deadline miss counted by the firmware itself (`DEADLINE_MISS` in its status).
        pub firmware_deadline_miss: bool => bool,
        /// The firmware's overrun counter, as its command reported it (0 without a command).
        pub overruns: u32 => int,
        /// The firmware's status word (0 without a command).
        pub status: u32 => int,
    }
}

// `--format mcap` (trace.mcap): the signal groups of the closed-loop trace, one
// channel each; docs/rig.md "Outputs" lists them.
impl tables::mcap::McapRows for PeriodRecord {
    const TABLE: &'static str = "trace";
    const GROUPS: &'static [tables::mcap::McapGroup] = &[
        tables::mcap::McapGroup { topic: "/state", schema: "painleve.State", columns: &["theta1", "theta1_dot", "theta2", "theta2_dot"] },
        tables::mcap::McapGroup {
            topic: "/contact",
            schema: "painleve.Contact",
            columns: &["mode", "f_t", "f_n", "z_t", "z_n", "z_t_ref", "lift_off_true"],
        },
        tables::mcap::McapGroup {
            topic: "/torques",
            schema: "painleve.Torques",
            columns: &["u1_cmd", "u2_cmd", "u1_applied", "u2_applied"],
        },
        tables::mcap::McapGroup {
            topic: "/firmware",
            schema: "painleve.Firmware",
            columns: &["lift_off_detected", "deadline_miss", "firmware_deadline_miss", "overruns", "status"],
        },
    ];
}

/// A contact mode's name, `shared::ContactMode::name` (an alias, so that serde's
/// derive reads it through [`mode_named`] rather than borrowing it from the input).
pub type ModeName = &'static str;

/// A contact mode's name read back as the name [`shared::ContactMode::name`] gives
/// (`trace.csv`'s `mode`): an unknown name is an error naming it.
fn mode_named<'de, D: serde::Deserializer<'de>>(d: D) -> Result<ModeName, D::Error> {
    use shared::ContactMode::*;
    let name = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(d)?;
    [Sliding, Sticking, Flight, Indeterminate, Inconsistent]
        .iter()
        .map(|m| m.name())
        .find(|n| *n == name)
        .ok_or_else(|| serde::de::Error::custom(format!("`{name}` is not a contact mode")))
}

impl PeriodRecord {
    /// The record of the plant sampled at `t_k` (`s`: the state, tip, contact mode and
    /// force the sensors read; `s.t` is `t_k`, s) with the firmware's reference `z_t_ref`
    /// (m): the plant's columns, the ones `simulate`'s `trace.csv` has too, mapped here
    /// once (`experiments::simulate::summary::TraceRow::of_sample` is the open loop's
    /// view of the same [`Sample`]). The command's columns are zero, as for a period
    /// without a command; the period loop sets them with struct update syntax.
    pub fn of_sample(s: &Sample, z_t_ref: f64) -> Self {
        Self {
            t: s.t,
            theta1: s.x[0],
            theta1_dot: s.x[1],
            theta2: s.x[2],
            theta2_dot: s.x[3],
            z_t: s.tip[0],
            z_n: s.tip[1],
            z_t_ref,
            f_t: s.f[0],
            f_n: s.f[1],
            mode: s.mode.name(),
            u1_cmd: 0.0,
            u2_cmd: 0.0,
            u1_applied: 0.0,
            u2_applied: 0.0,
            lift_off_true: s.mode == shared::ContactMode::Flight,
            lift_off_detected: false,
            deadline_miss: false,
            firmware_deadline_miss: false,
            overruns: 0,
            status: 0,
        }
    }
}

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The plant failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The scenario is out of its ranges (`Scenario::validate`), e.g. a command
    /// delay `timing.delta_s` not within one control period, which would drop every
    /// command as late.
    #[error("invalid scenario: {0}")]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// The firmware configuration is invalid.
    #[error("firmware configuration: {0}")]
    Firmware(#[from] firmware::config::ConfigError),
    /// The firmware latched its safe state (zero torque).
    #[error("the firmware entered its safe state at period {k} (t = {t:.3} s): {reason:?}")]
    SafeState {
        /// Period.
        k: usize,
        /// Sample time, s.
        t: f64,
        /// The reason it reported.
        reason: firmware::SafeReason,
    },
    /// The firmware process is gone or no longer answers.
    #[error("firmware lost at period {k} (t = {t:.3} s): {what}")]
    FirmwareLost {
        /// Period.
        k: usize,
        /// Sample time, s.
        t: f64,
        /// What the rig saw.
        what: String,
    },
    /// The transport failed (iceoryx2).
    #[error("transport: {0}")]
    Transport(String),
    /// Another live process already holds this rig in this role (one plant and one
    /// firmware per rig name).
    #[error("rig `{rig}` is in use by process {pid} (its {role}); pick another --rig name, or stop that process")]
    RigInUse {
        /// The rig name.
        rig: String,
        /// `plant` or `firmware`.
        role: &'static str,
        /// The owner's process id (-1 if unknown).
        pid: i64,
    },
    /// The handshake before period 0 refused the firmware: another wire version,
    /// an undecodable announcement, or another configuration (docs/rig.md).
    #[error(transparent)]
    Handshake(#[from] crate::handshake::HandshakeError),
    /// The scenario's `[law]` table does not fit the law the firmware runs
    /// (another law, an undeclared parameter, a value out of its range).
    #[error("law: {0}")]
    Law(#[from] crate::law::LawError),
    /// The scenario needs something this transport cannot do.
    #[error("{0}")]
    Unsupported(String),
    /// The board (the twin or the emulated board) refused its description,
    /// calibration or image, its application did not start, or its image
    /// stopped ticking.
    #[error("board: {0}")]
    Board(String),
    /// The scenario asks a board (`--link twin`, `--link emulator`) for what a
    /// board never runs: the message names the key (`controller.runaway_limits =
    /// false`: the runaway limits off) and where such a study runs instead. Bad
    /// input (exit 2): nothing ran.
    #[error("{0}")]
    NotOnABoard(String),
    /// An iceoryx2 service of the rig, created by another process (a monitor
    /// started first), lacks what this run needs: the message names the service,
    /// the attribute, its value and the value to use (docs/rig.md, "Monitors").
    #[error("{0}")]
    IncompatibleService(String),
    /// The user's private folder of locks and sockets
    /// ([`crate::private_files::runtime_dir`]) is refused: a symbolic link, not a
    /// folder, another user's, open to others, or not ours to make. The message
    /// names the folder and why. Bad input (exit 2, as a rig in use): nothing ran
    /// ([`RunError::private_folder`]).
    #[error("{0}")]
    PrivateFolder(String),
    /// The firmware process's plant took its handshake answer and left before
    /// its first frame: the plant refused this firmware (another configuration,
    /// law or wire version; the plant's own message names the difference), and the
    /// firmware process exits at once rather than waiting for another plant. Bad
    /// input (exit 2), as the plant's refusal is.
    #[error(
        "the plant on rig `{rig}` read this firmware's announcement and left before its first frame: it refused this firmware (the plant's message names what differs); start the firmware with the plant's scenario and flags"
    )]
    RefusedByPlant {
        /// The rig name.
        rig: String,
    },
    /// The run was interrupted (SIGINT or SIGTERM).
    #[error("interrupted at period {k}")]
    Interrupted {
        /// Period.
        k: usize,
    },
}

impl RunError {
    /// The error of the private folder `what` (`the rig's lock folder`) that
    /// [`crate::private_files::runtime_dir`] gave: a refusal of the folder
    /// ([`std::io::ErrorKind::PermissionDenied`]: a link, another user's, open to
    /// others, not ours to make) is [`RunError::PrivateFolder`] (exit 2); any
    /// other failure [`RunError::Transport`] (exit 1).
    pub fn private_folder(what: &str, e: &std::io::Error) -> Self {
        let message = format!("{what}: {e}");
        if e.kind() == std::io::ErrorKind::PermissionDenied { Self::PrivateFolder(message) } else { Self::Transport(message) }
    }
}

/// Lift-off detection statistics of a run (docs/hardware.md "Lift-off detection").
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LiftOffStats {
    /// True lift-offs (contact to flight transitions at the samples).
    pub lift_offs: u32,
    /// True lift-offs the firmware detected before the tip was back in contact.
    pub lift_offs_detected: u32,
    /// True lift-offs it did not detect.
    pub missed_lift_offs: u32,
    /// Detections with the tip in contact throughout.
    pub false_alarms: u32,
    /// Largest detection latency, periods.
    pub max_detection_latency_periods: u32,
}

/// Periods after a true flight ends during which a detection still counts for
/// it, and before a detection starts during which a flight excuses it
/// (docs/hardware.md "Lift-off detection").
pub const DETECTION_GRACE_PERIODS: usize = 5;

/// The lift-off detection statistics ([`LiftOffStats`]) of a run fed one period
/// at a time: a true flight episode is detected if the firmware declares
/// lift-off during it or within [`DETECTION_GRACE_PERIODS`] periods after it
/// ends; a detection episode that overlaps no true flight (nor starts within
/// that many periods after one) is a false alarm. Memory: a handful of open
/// episodes (those whose window is still open), whatever the run's length.
#[derive(Debug, Clone, Default)]
pub struct LiftOffTracker {
    /// Periods seen.
    k: usize,
    prev_true: bool,
    prev_detected: bool,
    /// Flight episodes not matched yet: their first period and, once the flight
    /// has ended, the first period past their window.
    pending: Vec<(usize, Option<usize>)>,
    /// The last period in true flight.
    last_true: Option<usize>,
    /// The first period of the detection episode under way.
    alarm_start: Option<usize>,
    stats: LiftOffStats,
}

impl LiftOffTracker {
    /// Feeds the next period: whether the tip was truly in flight and whether
    /// the firmware declared lift-off.
    pub fn push(&mut self, lift_off_true: bool, lift_off_detected: bool) {
        const GRACE: usize = DETECTION_GRACE_PERIODS;
        let k = self.k;
        if !lift_off_true && self.prev_true {
            // The flight ended at k - 1: its window closes GRACE periods later.
            for p in self.pending.iter_mut().filter(|p| p.1.is_none()) {
                p.1 = Some(k + GRACE);
            }
        }
        if !self.pending.is_empty() {
            let before = self.pending.len();
            self.pending.retain(|p| p.1.is_none_or(|end| end > k));
            self.stats.missed_lift_offs += (before - self.pending.len()) as u32;
        }
        if lift_off_true && !self.prev_true {
            self.stats.lift_offs += 1;
            self.pending.push((k, None));
        }
        if lift_off_detected {
            for (start, _) in self.pending.drain(..) {
                self.stats.lift_offs_detected += 1;
                self.stats.max_detection_latency_periods = self.stats.max_detection_latency_periods.max((k - start) as u32);
            }
        }
        if !lift_off_detected && self.prev_detected {
            // The detection ended at k - 1: judged on the flights up to then.
            self.close_alarm();
        }
        if lift_off_true {
            self.last_true = Some(k);
        }
        if lift_off_detected && !self.prev_detected {
            self.alarm_start = Some(k);
        }
        self.prev_true = lift_off_true;
        self.prev_detected = lift_off_detected;
        self.k += 1;
    }

    /// Ends the detection episode under way: a false alarm unless a true flight
    /// was seen from [`DETECTION_GRACE_PERIODS`] before its start to its end.
    fn close_alarm(&mut self) {
        if let Some(start) = self.alarm_start.take()
            && self.last_true.is_none_or(|t| t + DETECTION_GRACE_PERIODS < start)
        {
            self.stats.false_alarms += 1;
        }
    }

    /// The statistics of the periods fed so far, as if the run ended here
    /// (flights still unmatched are missed, a detection under way is judged).
    pub fn stats(&self) -> LiftOffStats {
        let mut end = self.clone();
        end.stats.missed_lift_offs += end.pending.len() as u32;
        end.close_alarm();
        end.stats
    }
}

/// Matches true and detected lift-offs period by period: a true flight episode is
/// detected if the firmware declares lift-off during it or within 5 periods after
/// it ends (a short hop may end before the confirmation); a detection episode that
/// overlaps no true flight (nor starts within 5 periods after one) is a false alarm.
/// The same numbers as [`LiftOffTracker`] fed the records one by one.
pub fn lift_off_stats(records: &[PeriodRecord]) -> LiftOffStats {
    let mut t = LiftOffTracker::default();
    records.iter().for_each(|r| t.push(r.lift_off_true, r.lift_off_detected));
    t.stats()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The lift-off statistics over a whole list (the definition, kept as the
    /// reference the streaming tracker must reproduce).
    fn reference(truth: &[bool], det: &[bool]) -> LiftOffStats {
        const GRACE: usize = DETECTION_GRACE_PERIODS;
        let mut st = LiftOffStats::default();
        let n = truth.len();
        let mut k = 0;
        while k < n {
            if truth[k] && (k == 0 || !truth[k - 1]) {
                st.lift_offs += 1;
                let start = k;
                let mut end = k;
                while end + 1 < n && truth[end + 1] {
                    end += 1;
                }
                match (start..n.min(end + 1 + GRACE)).find(|&j| det[j]) {
                    Some(j) => {
                        st.lift_offs_detected += 1;
                        st.max_detection_latency_periods = st.max_detection_latency_periods.max((j - start) as u32);
                    }
                    None => st.missed_lift_offs += 1,
                }
                k = end + 1;
            } else {
                k += 1;
            }
        }
        let mut k = 0;
        while k < n {
            if det[k] && (k == 0 || !det[k - 1]) {
                let start = k;
                let mut end = k;
                while end + 1 < n && det[end + 1] {
                    end += 1;
                }
                if !(start.saturating_sub(GRACE)..=end).any(|j| truth[j]) {
                    st.false_alarms += 1;
                }
                k = end + 1;
            } else {
                k += 1;
            }
        }
        st
    }

    /// Runs of random lengths (hops and detections of a few periods, like a run's).
    fn runs() -> impl Strategy<Value = Vec<bool>> {
        proptest::collection::vec((any::<bool>(), 1usize..12), 0..40)
            .prop_map(|runs| runs.into_iter().flat_map(|(b, len)| std::iter::repeat_n(b, len)).collect())
    }

    proptest! {
        #[test]
        fn streaming_lift_off_stats_equal_the_reference(truth in runs(), det in runs()) {
            let n = truth.len().min(det.len());
            let (truth, det) = (&truth[..n], &det[..n]);
            let mut t = LiftOffTracker::default();
            for k in 0..n {
                t.push(truth[k], det[k]);
                // Also as if the run stopped at every period.
                prop_assert_eq!(t.stats(), reference(&truth[..=k], &det[..=k]));
            }
            prop_assert!(t.pending.len() <= 4, "pending {:?}", t.pending);
        }

    }

    #[test]
    fn stats_match_hand_made_sequences() {
        let base = PeriodRecord {
            t: 0.0,
            theta1: 0.0,
            theta1_dot: 0.0,
            theta2: 0.0,
            theta2_dot: 0.0,
            z_t: 0.0,
            z_n: 0.0,
            z_t_ref: 0.0,
            f_t: 0.0,
            f_n: 0.0,
            mode: "sliding",
            u1_cmd: 0.0,
            u2_cmd: 0.0,
            u1_applied: 0.0,
            u2_applied: 0.0,
            lift_off_true: false,
            lift_off_detected: false,
            deadline_miss: false,
            firmware_deadline_miss: false,
            overruns: 0,
            status: 0,
        };
        let seq = |truth: &str, det: &str| -> Vec<PeriodRecord> {
            truth
                .chars()
                .zip(det.chars())
                .map(|(t, d)| PeriodRecord { lift_off_true: t == '1', lift_off_detected: d == '1', ..base })
                .collect()
        };
        // One hop detected 2 periods late, one missed, one false alarm.
        let r = seq("0011110000000000011000000000000000", "0000111100000000000000000000011000");
        let st = lift_off_stats(&r);
        assert_eq!((st.lift_offs, st.lift_offs_detected, st.missed_lift_offs, st.false_alarms), (2, 1, 1, 1));
        assert_eq!(st.max_detection_latency_periods, 2);
    }
}
