//! A recorded run's frames through a firmware build, every answer compared
//! with the recorded one bit for bit (docs/rig.md "Replay"): the library under
//! `sil-host replay` and `painleve.replay`. copper-rs re-simulates a task graph
//! from its log and PX4 replays a flight log through a new estimator; here the
//! log is the run's frames table ([`rig::frames::FrameRow`]: the frame the
//! firmware read, the arm's state the board links' sensors read, the answer),
//! the firmware is any link of `run` and `pil`, configured from the run's own
//! scenario ([`Recording`]).
//!
//! The replay is open loop: each recorded frame goes out whatever the firmware
//! answered to the one before, so after a divergence the frames are no longer
//! what this firmware would have made its plant do; the first divergence is
//! the finding, the count after it (`all`) a measure of its reach.

mod recording;

pub use recording::Recording;

use rig::{
    FaultPlan, FirmwareLink,
    frames::{FrameRow, Signal},
    link::DropCommands,
};
use serde::Serialize;

use crate::error::Error;

/// The signals compared in every period: the answer's kind, the command's
/// codes, status and overrun counter, and the telemetry's ten 32-bit floats
/// ([`FrameRow::signals`]).
pub const SIGNALS: &str = "the answer, the command's u1_code, u2_code, status and overruns, and the telemetry's z_t_ref, f_n_ref, q1, q2, qd1, qd2, f_t_meas, f_n_meas, u1_raw, u2_raw";

/// Where the replayed firmware first answered differently.
#[derive(Debug, Clone, Serialize)]
pub struct Divergence {
    /// The period `k` (the frame's `seq`).
    pub period: u32,
    /// Its sample time, s.
    pub t: f64,
    /// The first signal that differs ([`FrameRow::signals`]' names).
    pub signal: &'static str,
    /// The recorded value (a float as its 32-bit text and bits).
    pub recorded: String,
    /// The replayed value.
    pub replayed: String,
}

/// How much one signal diverged over the periods compared (`replay --json`'s
/// `per_signal`: issue 84, a replay says how much, not only where).
#[derive(Debug, Clone, Serialize)]
pub struct SignalDivergence {
    /// The signal ([`FrameRow::signals`]' names).
    pub signal: &'static str,
    /// Its unit: `code` (the torque codes, their N m in
    /// [`SignalDivergence::largest_difference_nm`]), `m`, `N`, `rad`, `rad/s`,
    /// `N m`, `count` (the overrun counter), `bits` (the status word: the
    /// difference is the bits that differed), `kind` (the answer: 0 answered,
    /// 1 dropped, 2 none).
    pub unit: &'static str,
    /// The first period in which it differs.
    pub first_period: u32,
    /// Its sample time, s.
    pub first_t: f64,
    /// Periods in which it differs.
    pub divergent_periods: usize,
    /// The largest `|replayed - recorded|`, in [`SignalDivergence::unit`] (for
    /// `bits`, every bit that differed in some period; a NaN on one side is
    /// infinite).
    pub largest_difference: f64,
    /// The period of the largest difference.
    pub largest_at_period: u32,
    /// The torque codes' largest difference in N m (`shared::wire::decode_torque`:
    /// 5 N m full scale, 2048 codes); `None` for the other signals.
    pub largest_difference_nm: Option<f64>,
}

/// The unit of each of [`FrameRow::signals`], by name ([`SignalDivergence::unit`]).
fn unit_of(signal: &str) -> &'static str {
    match signal {
        "answer" => "kind",
        "u1_code" | "u2_code" => "code",
        "status" => "bits",
        "overruns" => "count",
        "z_t_ref" => "m",
        "f_n_ref" | "f_t_meas" | "f_n_meas" => "N",
        "q1" | "q2" => "rad",
        "qd1" | "qd2" => "rad/s",
        "u1_raw" | "u2_raw" => "N m",
        _ => "",
    }
}

/// The size of a difference between two values of one signal, in its unit.
fn difference(unit: &str, recorded: Signal, replayed: Signal) -> f64 {
    match (recorded, replayed) {
        (Signal::Int(a), Signal::Int(b)) if unit == "bits" => (a ^ b) as f64,
        (Signal::Int(a), Signal::Int(b)) => (a - b).unsigned_abs() as f64,
        (Signal::Real(a), Signal::Real(b)) => {
            let d = (a - b).abs();
            if d.is_nan() { f64::INFINITY } else { d }
        }
        _ => f64::INFINITY,
    }
}

impl SignalDivergence {
    /// Adds period `row`'s difference of this signal.
    fn add(&mut self, row: &FrameRow, d: f64) {
        self.divergent_periods += 1;
        if self.unit == "bits" {
            self.largest_difference = ((self.largest_difference as i64) | (d as i64)) as f64;
        } else if d > self.largest_difference {
            self.largest_difference = d;
            self.largest_at_period = row.seq;
        }
        if self.unit == "code" {
            self.largest_difference_nm = Some(self.largest_difference * f64::from(shared::wire::decode_torque(1)));
        }
    }
}

/// What the comparison found ([`replay`]).
#[derive(Debug)]
pub struct Comparison {
    /// Periods replayed (all of them, unless the link failed, the replay was
    /// stopped, or it stopped at a divergence without `all`).
    pub replayed: usize,
    /// Periods whose answer differs (all of them counted only with `all`).
    pub divergent: usize,
    /// The first divergence, if any.
    pub first: Option<Divergence>,
    /// Each signal that differed in some period compared: where first, in how
    /// many periods, by how much at most (in the order they first differed, a
    /// period's in [`FrameRow::signals`]' order).
    pub per_signal: Vec<SignalDivergence>,
    /// Why the link stopped part way (or the replay was interrupted), if it did.
    pub link_error: Option<Error>,
}

/// Sends every recorded frame of `rec` to the firmware behind `link`, as the
/// period loop drives a link (the faults of `plan` that act on the firmware
/// first, then the exchange through the `drop_command` wrapper), and compares
/// each answer with the recorded one bit for bit ([`FrameRow::first_difference`]).
/// Stops at the first divergence unless `all`; hands each replayed period's row
/// (the recorded frame with the replayed answer) to `answers`, in order (`sil-host
/// replay --out`: a run folder of them); calls `progress` with the count of periods
/// replayed after each, and stops (an interruption, in [`Comparison::link_error`])
/// when it returns `false`. Ends the link's run (`FirmwareLink::finish`) either way.
pub fn replay(
    rec: &Recording,
    link: &mut dyn FirmwareLink,
    plan: &FaultPlan,
    all: bool,
    answers: &mut dyn FnMut(&FrameRow),
    progress: &mut dyn FnMut(usize) -> bool,
) -> Comparison {
    let mut c = Comparison { replayed: 0, divergent: 0, first: None, per_signal: Vec::new(), link_error: None };
    for row in &rec.rows {
        if !progress(c.replayed) {
            c.link_error = Some(Error::interrupted(format!("interrupted after {} periods", c.replayed)));
            break;
        }
        let (frame, truth) = (row.frame(), row.truth());
        link.before_period(u64::from(row.seq));
        let mut wire = DropCommands { inner: &mut *link, plan };
        match wire.exchange(&frame, &truth) {
            Ok(exchange) => {
                c.replayed += 1;
                let got = FrameRow::of(&frame, &truth, &exchange);
                answers(&got);
                if let Some((signal, recorded, replayed)) = row.first_difference(&got) {
                    c.divergent += 1;
                    for ((name, a), (_, b)) in row.signals().into_iter().zip(got.signals()) {
                        if a.same_bits(&b) {
                            continue;
                        }
                        let unit = unit_of(name);
                        let at = match c.per_signal.iter().position(|d| d.signal == name) {
                            Some(i) => i,
                            None => {
                                c.per_signal.push(SignalDivergence {
                                    signal: name,
                                    unit,
                                    first_period: row.seq,
                                    first_t: row.t,
                                    divergent_periods: 0,
                                    largest_difference: 0.0,
                                    largest_at_period: row.seq,
                                    largest_difference_nm: None,
                                });
                                c.per_signal.len() - 1
                            }
                        };
                        c.per_signal[at].add(row, difference(unit, a, b));
                    }
                    c.first.get_or_insert(Divergence {
                        period: row.seq,
                        t: row.t,
                        signal,
                        recorded: recorded.to_string(),
                        replayed: replayed.to_string(),
                    });
                    if !all {
                        break;
                    }
                }
            }
            Err(e) => {
                c.link_error = Some(Error::from(e));
                break;
            }
        }
    }
    link.finish(c.replayed as u32);
    c
}

/// A replay's result (`sil-host replay --json`, `painleve.replay`'s dict).
#[derive(Debug, Clone, Serialize)]
pub struct ReplaySummary {
    /// The run's folder.
    pub folder: String,
    /// The file the frames came from.
    pub frames: String,
    /// The recorded scenario's name.
    pub scenario: String,
    /// The `--set`s applied to it, as given.
    pub overrides: Vec<String>,
    /// The link the frames went over (`in-process`, `iceoryx2`, `twin`, `emulator`, `pil`).
    pub link: String,
    /// Periods recorded.
    pub periods_recorded: usize,
    /// Periods replayed (all of them, unless the link failed or the replay stopped at a divergence).
    pub periods_replayed: usize,
    /// Whether every replayed answer equals the recorded one, bit for bit, and every period was replayed.
    pub identical: bool,
    /// Periods whose answer differs (all of them counted only with `--all`).
    pub divergent_periods: usize,
    /// The first divergence, if any.
    pub first_divergence: Option<Divergence>,
    /// How much each signal diverged ([`SignalDivergence`]; over the first
    /// divergent period only, unless `--all`).
    pub per_signal: Vec<SignalDivergence>,
    /// Why the link stopped part way, if it did.
    pub link_error: Option<String>,
    /// What is compared in each period.
    pub signals: &'static str,
    /// Wall-clock time of the replay (the link's start included), s.
    pub wall_s: f64,
}

impl ReplaySummary {
    /// The summary of comparison `c` of recording `rec` with `overrides`
    /// (`KEY=VALUE` as given) over the link named `link`, in `wall_s` seconds;
    /// and the failure it ends with: the link's error if it stopped part way,
    /// else [`Error::Diverged`] with [`ReplaySummary::verdict`] at a divergence.
    pub fn of(rec: &Recording, c: Comparison, overrides: Vec<String>, link: String, wall_s: f64) -> (Self, Option<Error>) {
        let summary = Self {
            folder: rec.folder.display().to_string(),
            frames: rec.source.display().to_string(),
            scenario: rec.scenario.name.clone(),
            overrides,
            link,
            periods_recorded: rec.rows.len(),
            periods_replayed: c.replayed,
            identical: c.first.is_none() && c.link_error.is_none() && c.replayed == rec.rows.len(),
            divergent_periods: c.divergent,
            first_divergence: c.first,
            per_signal: c.per_signal,
            link_error: c.link_error.as_ref().map(ToString::to_string),
            signals: SIGNALS,
            wall_s,
        };
        let failure = c.link_error.or_else(|| summary.verdict().map(Error::Diverged));
        (summary, failure)
    }

    /// The one-line verdict of a divergence (`None` without one).
    pub fn verdict(&self) -> Option<String> {
        let d = self.first_divergence.as_ref()?;
        let reach = if self.periods_replayed == self.periods_recorded {
            format!("{} of {} periods differ", self.divergent_periods, self.periods_recorded)
        } else {
            "stopped there (--all counts every period that differs)".to_string()
        };
        Some(format!(
            "the replay diverged from the recording at period {} (t = {} s): {} recorded {}, replayed {}; {reach}",
            d.period, d.t, d.signal, d.recorded, d.replayed
        ))
    }
}

/// The human report (`sil-host replay`'s output): the replay's line, then
/// "identical" or the first divergence and its reach, and the link's error.
impl std::fmt::Display for ReplaySummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = self;
        let set = if s.overrides.is_empty() { String::new() } else { format!(", with --set {}", s.overrides.join(" --set ")) };
        write!(f, "replay of {} ({}; scenario {}{set}) over the {} link, {:.3} s:", s.folder, s.frames, s.scenario, s.link, s.wall_s)?;
        if s.identical {
            return write!(f, "\n  identical over {} periods: every answer bit for bit ({})", s.periods_replayed, s.signals);
        }
        if let Some(d) = &s.first_divergence {
            write!(
                f,
                "\n  DIVERGED at period {} (t = {} s): {} recorded {}, replayed {}",
                d.period, d.t, d.signal, d.recorded, d.replayed
            )?;
            let stopped = s.periods_replayed < s.periods_recorded && s.link_error.is_none();
            write!(
                f,
                "\n  {} of {} periods replayed, {} differ{}",
                s.periods_replayed,
                s.periods_recorded,
                s.divergent_periods,
                if stopped { " (stopped at the first: --all compares every period)" } else { "" }
            )?;
            for d in &s.per_signal {
                let nm = d.largest_difference_nm.map(|v| format!(" ({v} N m)")).unwrap_or_default();
                let largest = if d.unit == "bits" {
                    format!("bits 0x{:x} differed", d.largest_difference as i64)
                } else {
                    format!("at most {} {}{nm} (period {})", d.largest_difference, d.unit, d.largest_at_period)
                };
                write!(f, "\n    {}: from period {}, in {} periods, {largest}", d.signal, d.first_period, d.divergent_periods)?;
            }
        }
        if let Some(e) = &s.link_error {
            write!(f, "\n  the link stopped after {} of {} periods: {e}", s.periods_replayed, s.periods_recorded)?;
        }
        Ok(())
    }
}
