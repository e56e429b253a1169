//! What crossed the wire in each period of a closed-loop run, recorded bit for
//! bit so the run can be replayed through another firmware build (`sil-host
//! replay`, docs/rig.md "Replay"): the sensor frame the firmware read (every
//! field of [`SensorFrame`]), the arm's true state the board links' device
//! models read instead (the board twin's and the emulated board's encoders and
//! load cell sense `theta1`, ..., `f_n` themselves: [`GroundTruth`]'s `x` and
//! `f`), and what the firmware answered (the command's signals and its
//! telemetry, [`ActuatorCommand`], [`FirmwareTelemetry`]). A row of `frames.csv`
//! (`frames.arrow`; the `/wire/...` channels of `trace.mcap`).
//!
//! The answer's timing (`t_sent_us`, `step_ticks`) is left out: it is the link's
//! (the in-process step takes no time, the emulated board's and QEMU's count
//! cycles), so the table is the same bytes over every link, as the trace is.
//! The 32-bit floats of the telemetry are held as `f64` (exactly) and written
//! in the shortest text that reads back to the same bits.
//!
//! The table is declared once ([`FrameRow`], `tables::table_row!`): the CSV,
//! Arrow and MCAP writers and the Python columns are derived from it, and so is
//! the reader ([`read_frames`]: serde's `Deserialize`, through the `csv` crate or
//! `tables::Table::rows_as`).

use serde::{Deserialize, Deserializer, Serialize};
use shared::wire::{ActuatorCommand, FirmwareTelemetry, GroundTruth, SensorFrame};

use crate::link::Exchange;

mod read;

pub use read::{FramesError, read_frames, read_table};

/// How the firmware's answer to a frame came back ([`Exchange`]); in the table
/// by its name ([`Answer::name`]), read back from it (an unknown name refused).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Answer {
    /// It answered and the command was applied (or held back as late).
    Answered,
    /// It answered but the wire lost the command (the `drop_command` fault).
    Dropped,
    /// No answer came before the link stopped waiting.
    None,
}

impl Answer {
    /// The name in the table: `answered`, `dropped`, `none`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Answered => "answered",
            Self::Dropped => "dropped",
            Self::None => "none",
        }
    }

    /// The answer named `name` ([`Answer::name`]); `None` for another name.
    pub fn of_name(name: &str) -> Option<Self> {
        [Self::Answered, Self::Dropped, Self::None].into_iter().find(|a| a.name() == name)
    }
}

/// The `str` column's cell ([`tables::csv_row!`]).
impl AsRef<str> for Answer {
    fn as_ref(&self) -> &str {
        self.name()
    }
}

/// A stamp read back from a table: the table's integer, never negative.
fn stamp<'de, D: Deserializer<'de>>(d: D) -> Result<i64, D::Error> {
    let v = i64::deserialize(d)?;
    if v < 0 {
        return Err(serde::de::Error::custom(format_args!("`t_us` = {v} is outside its wire type's range (a u64 stamp)")));
    }
    Ok(v)
}

tables::table_row! {
    /// One period's frame and the firmware's answer to it.
    ///
    /// Units: the frame's as on the wire ([`SensorFrame`]: encoder counts of
    /// `2 pi / 2^14`, load-cell codes of `25/2048 N`, belt mm/s); the command's
    /// torque codes of `5/2048 N m`; the telemetry in SI units and radians, as the
    /// firmware's 32-bit floats. Without an answer the command and telemetry
    /// columns are 0.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    pub struct FrameRow {
        /// Sample time `t_k`, s (the ground truth's: `k Ts`, the belt's travel is
        /// `v_belt t` on the board links).
        pub t: f64 => f64,
        /// Period index `k` (the frame's `seq`).
        pub seq: u32 => int,
        /// The frame's stamp, µs since the start of the run (a `u64` on the wire;
        /// held as the table's integer, which any run's length fits; a negative
        /// one is refused on reading).
        #[serde(deserialize_with = "stamp")]
        pub t_us: i64 => int,
        /// Base-joint encoder, counts.
        pub theta1_count: u16 => int,
        /// Elbow encoder, counts.
        pub elbow_count: u16 => int,
        /// Load cell, tangential code.
        pub f_t_code: i16 => int,
        /// Load cell, normal code.
        pub f_n_code: i16 => int,
        /// Belt speed, mm/s.
        pub belt_count: i16 => int,
        /// The frame's flags (`shared::wire::frame_flags`).
        pub flags: u16 => int,
        /// True `theta1` at `t_k`, rad (what the board links' encoders sense).
        pub theta1: f64 => f64,
        /// True `theta1_dot`, rad/s.
        pub theta1_dot: f64 => f64,
        /// True `theta2`, rad.
        pub theta2: f64 => f64,
        /// True `theta2_dot`, rad/s.
        pub theta2_dot: f64 => f64,
        /// True tangential contact force, N (what the board links' load cell senses).
        pub f_t: f64 => f64,
        /// True normal contact force, N.
        pub f_n: f64 => f64,
        /// How the answer came back: `answered`, `dropped` or `none` ([`Answer`]).
        pub answer: Answer => str,
        /// The command's `u1`, torque code.
        pub u1_code: i16 => int,
        /// The command's `u2`, torque code.
        pub u2_code: i16 => int,
        /// The command's status word (`shared::wire::status`).
        pub status: u32 => int,
        /// The command's overrun counter.
        pub overruns: u32 => int,
        /// Telemetry: `z_t*`, m.
        pub z_t_ref: f64 => f64,
        /// Telemetry: `f_n*` after the ramp, N.
        pub f_n_ref: f64 => f64,
        /// Telemetry: estimated `theta1`, rad.
        pub q1: f64 => f64,
        /// Telemetry: estimated `theta2`, rad.
        pub q2: f64 => f64,
        /// Telemetry: estimated `theta1_dot`, rad/s.
        pub qd1: f64 => f64,
        /// Telemetry: estimated `theta2_dot`, rad/s.
        pub qd2: f64 => f64,
        /// Telemetry: measured `f_t`, N.
        pub f_t_meas: f64 => f64,
        /// Telemetry: measured `f_n`, N.
        pub f_n_meas: f64 => f64,
        /// Telemetry: `u1` before saturation and quantisation, N m.
        pub u1_raw: f64 => f64,
        /// Telemetry: `u2` before saturation and quantisation, N m.
        pub u2_raw: f64 => f64,
    }
}

// `--format mcap` (trace.mcap): the frame, the command and the telemetry, one
// channel each; docs/rig.md "Outputs" lists them.
impl tables::mcap::McapRows for FrameRow {
    const TABLE: &'static str = "frames";
    const GROUPS: &'static [tables::mcap::McapGroup] = &[
        tables::mcap::McapGroup {
            topic: "/wire/frame",
            schema: "painleve.WireFrame",
            columns: &["seq", "t_us", "theta1_count", "elbow_count", "f_t_code", "f_n_code", "belt_count", "flags"],
        },
        tables::mcap::McapGroup {
            topic: "/wire/arm",
            schema: "painleve.WireArm",
            columns: &["theta1", "theta1_dot", "theta2", "theta2_dot", "f_t", "f_n"],
        },
        tables::mcap::McapGroup {
            topic: "/wire/command",
            schema: "painleve.WireCommand",
            columns: &["answer", "u1_code", "u2_code", "status", "overruns"],
        },
        tables::mcap::McapGroup {
            topic: "/wire/telemetry",
            schema: "painleve.WireTelemetry",
            columns: &["z_t_ref", "f_n_ref", "q1", "q2", "qd1", "qd2", "f_t_meas", "f_n_meas", "u1_raw", "u2_raw"],
        },
    ];
}

impl FrameRow {
    /// The row of `frame`, the ground truth `truth` of the same instant and
    /// the answer `exchange` to it.
    pub fn of(frame: &SensorFrame, truth: &GroundTruth, exchange: &Exchange) -> Self {
        let (answer, command, telemetry) = match exchange {
            Exchange::Answered { command, telemetry, .. } => (Answer::Answered, *command, *telemetry),
            Exchange::Dropped { command, telemetry } => (Answer::Dropped, *command, *telemetry),
            Exchange::NoAnswer => (Answer::None, ActuatorCommand::default(), FirmwareTelemetry::default()),
        };
        Self::from_parts(frame, truth, answer, &command, &telemetry)
    }

    /// The row of `frame`, `truth`, `answer` and its command and telemetry.
    pub fn from_parts(
        frame: &SensorFrame,
        truth: &GroundTruth,
        answer: Answer,
        command: &ActuatorCommand,
        telemetry: &FirmwareTelemetry,
    ) -> Self {
        let t = &telemetry;
        Self {
            t: truth.t,
            seq: frame.seq,
            t_us: i64::try_from(frame.t_us).unwrap_or(i64::MAX),
            theta1_count: frame.theta1_count,
            elbow_count: frame.elbow_count,
            f_t_code: frame.f_t_code,
            f_n_code: frame.f_n_code,
            belt_count: frame.belt_count,
            flags: frame.flags,
            theta1: truth.x[0],
            theta1_dot: truth.x[1],
            theta2: truth.x[2],
            theta2_dot: truth.x[3],
            f_t: truth.f[0],
            f_n: truth.f[1],
            answer,
            u1_code: command.u1_code,
            u2_code: command.u2_code,
            status: command.status,
            overruns: command.overruns,
            z_t_ref: f64::from(t.z_t_ref),
            f_n_ref: f64::from(t.f_n_ref),
            q1: f64::from(t.q[0]),
            q2: f64::from(t.q[1]),
            qd1: f64::from(t.qd[0]),
            qd2: f64::from(t.qd[1]),
            f_t_meas: f64::from(t.f[0]),
            f_n_meas: f64::from(t.f[1]),
            u1_raw: f64::from(t.u_raw[0]),
            u2_raw: f64::from(t.u_raw[1]),
        }
    }

    /// The frame as the firmware read it, bit for bit.
    pub fn frame(&self) -> SensorFrame {
        SensorFrame {
            t_us: u64::try_from(self.t_us).unwrap_or(0),
            seq: self.seq,
            theta1_count: self.theta1_count,
            elbow_count: self.elbow_count,
            f_t_code: self.f_t_code,
            f_n_code: self.f_n_code,
            belt_count: self.belt_count,
            flags: self.flags,
        }
    }

    /// The ground truth the board links read (`t`, `seq`, the state `x` and
    /// the contact force `f`, bit for bit); its other fields, which only
    /// monitors read, are left at 0.
    pub fn truth(&self) -> GroundTruth {
        GroundTruth {
            t: self.t,
            seq: self.seq,
            x: [self.theta1, self.theta1_dot, self.theta2, self.theta2_dot],
            f: [self.f_t, self.f_n],
            ..GroundTruth::default()
        }
    }

    /// The answer's signals, by name, as compared by a replay: `answer` (0
    /// answered, 1 dropped, 2 none), the command's codes, status and overruns,
    /// then the telemetry's floats (as `f64`, compared by their bits).
    pub fn signals(&self) -> [(&'static str, Signal); 15] {
        [
            ("answer", Signal::Int(self.answer as i64)),
            ("u1_code", Signal::Int(i64::from(self.u1_code))),
            ("u2_code", Signal::Int(i64::from(self.u2_code))),
            ("status", Signal::Int(i64::from(self.status))),
            ("overruns", Signal::Int(i64::from(self.overruns))),
            ("z_t_ref", Signal::Real(self.z_t_ref)),
            ("f_n_ref", Signal::Real(self.f_n_ref)),
            ("q1", Signal::Real(self.q1)),
            ("q2", Signal::Real(self.q2)),
            ("qd1", Signal::Real(self.qd1)),
            ("qd2", Signal::Real(self.qd2)),
            ("f_t_meas", Signal::Real(self.f_t_meas)),
            ("f_n_meas", Signal::Real(self.f_n_meas)),
            ("u1_raw", Signal::Real(self.u1_raw)),
            ("u2_raw", Signal::Real(self.u2_raw)),
        ]
    }

    /// The first of [`FrameRow::signals`] in which `self` (recorded) and `other`
    /// (replayed) differ, with both values; `None` when they agree bit for bit.
    pub fn first_difference(&self, other: &Self) -> Option<(&'static str, Signal, Signal)> {
        self.signals().into_iter().zip(other.signals()).find(|((_, a), (_, b))| !a.same_bits(b)).map(|((name, a), (_, b))| (name, a, b))
    }
}

/// One signal of an answer: an integer field, or a float compared by its bits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Signal {
    /// A code, a status word, a counter.
    Int(i64),
    /// A telemetry value (a 32-bit float, held exactly as `f64`).
    Real(f64),
}

impl Signal {
    /// Whether the two are the same bits (a NaN equals the same NaN).
    pub fn same_bits(&self, other: &Self) -> bool {
        match (self, other) {
            (Self::Int(a), Self::Int(b)) => a == b,
            (Self::Real(a), Self::Real(b)) => a.to_bits() == b.to_bits(),
            _ => false,
        }
    }
}

impl core::fmt::Display for Signal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Int(v) => write!(f, "{v}"),
            // The 32-bit value's shortest text, and its bits.
            Self::Real(v) => write!(f, "{} (0x{:08x})", *v as f32, (*v as f32).to_bits()),
        }
    }
}

#[cfg(test)]
mod tests;
