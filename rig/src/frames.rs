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

use serde::Serialize;
use shared::wire::{ActuatorCommand, FirmwareTelemetry, GroundTruth, SensorFrame};

use crate::link::Exchange;

/// How the firmware's answer to a frame came back ([`Exchange`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
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

/// One period's frame and the firmware's answer to it.
///
/// Units: the frame's as on the wire ([`SensorFrame`]: encoder counts of
/// `2 pi / 2^14`, load-cell codes of `25/2048 N`, belt mm/s); the command's
/// torque codes of `5/2048 N m`; the telemetry in SI units and radians, as the
/// firmware's 32-bit floats. Without an answer the command and telemetry
/// columns are 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrameRow {
    /// Sample time `t_k`, s (the ground truth's: `k Ts`, the belt's travel is
    /// `v_belt t` on the board links).
    pub t: f64,
    /// Period index `k` (the frame's `seq`).
    pub seq: u32,
    /// The frame's stamp, µs since the start of the run (a `u64` on the wire;
    /// held as the table's integer, which any run's length fits).
    pub t_us: i64,
    /// Base-joint encoder, counts.
    pub theta1_count: u16,
    /// Elbow encoder, counts.
    pub elbow_count: u16,
    /// Load cell, tangential code.
    pub f_t_code: i16,
    /// Load cell, normal code.
    pub f_n_code: i16,
    /// Belt speed, mm/s.
    pub belt_count: i16,
    /// The frame's flags (`shared::wire::frame_flags`).
    pub flags: u16,
    /// True `theta1` at `t_k`, rad (what the board links' encoders sense).
    pub theta1: f64,
    /// True `theta1_dot`, rad/s.
    pub theta1_dot: f64,
    /// True `theta2`, rad.
    pub theta2: f64,
    /// True `theta2_dot`, rad/s.
    pub theta2_dot: f64,
    /// True tangential contact force, N (what the board links' load cell senses).
    pub f_t: f64,
    /// True normal contact force, N.
    pub f_n: f64,
    /// How the answer came back: `answered`, `dropped` or `none` ([`Answer`]).
    pub answer: &'static str,
    /// The command's `u1`, torque code.
    pub u1_code: i16,
    /// The command's `u2`, torque code.
    pub u2_code: i16,
    /// The command's status word (`shared::wire::status`).
    pub status: u32,
    /// The command's overrun counter.
    pub overruns: u32,
    /// Telemetry: `z_t*`, m.
    pub z_t_ref: f64,
    /// Telemetry: `f_n*` after the ramp, N.
    pub f_n_ref: f64,
    /// Telemetry: estimated `theta1`, rad.
    pub q1: f64,
    /// Telemetry: estimated `theta2`, rad.
    pub q2: f64,
    /// Telemetry: estimated `theta1_dot`, rad/s.
    pub qd1: f64,
    /// Telemetry: estimated `theta2_dot`, rad/s.
    pub qd2: f64,
    /// Telemetry: measured `f_t`, N.
    pub f_t_meas: f64,
    /// Telemetry: measured `f_n`, N.
    pub f_n_meas: f64,
    /// Telemetry: `u1` before saturation and quantisation, N m.
    pub u1_raw: f64,
    /// Telemetry: `u2` before saturation and quantisation, N m.
    pub u2_raw: f64,
}

// `frames.csv`: [`FrameRow`]'s fields in order.
tables::csv_row!(FrameRow {
    t: f64,
    seq: int,
    t_us: int,
    theta1_count: int,
    elbow_count: int,
    f_t_code: int,
    f_n_code: int,
    belt_count: int,
    flags: int,
    theta1: f64,
    theta1_dot: f64,
    theta2: f64,
    theta2_dot: f64,
    f_t: f64,
    f_n: f64,
    answer: str,
    u1_code: int,
    u2_code: int,
    status: int,
    overruns: int,
    z_t_ref: f64,
    f_n_ref: f64,
    q1: f64,
    q2: f64,
    qd1: f64,
    qd2: f64,
    f_t_meas: f64,
    f_n_meas: f64,
    u1_raw: f64,
    u2_raw: f64,
});

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
            answer: answer.name(),
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
        let answer = Answer::of_name(self.answer).map_or(u32::MAX, |a| a as u32);
        [
            ("answer", Signal::Int(i64::from(answer))),
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
mod tests {
    use super::*;

    fn answered() -> (SensorFrame, Exchange) {
        let frame = SensorFrame {
            t_us: 1_234_000,
            seq: 1234,
            theta1_count: 16383,
            elbow_count: 7,
            f_t_code: -2048,
            f_n_code: 2047,
            belt_count: -400,
            flags: 0x20,
        };
        let command = ActuatorCommand {
            t_sent_us: 1_234_050,
            seq: 1234,
            u1_code: -3,
            u2_code: 2047,
            status: 0x11,
            step_ticks: 99,
            overruns: 2,
            reserved: 0,
        };
        let telemetry = FirmwareTelemetry {
            seq: 1234,
            status: 0x11,
            z_t_ref: 0.1,
            f_n_ref: -3.5e-8,
            q: [1.0e-30, -2.0],
            qd: [f32::MAX, f32::MIN_POSITIVE],
            f: [0.3, 7.0],
            u_raw: [f32::from_bits(1), -0.0],
        };
        (frame, Exchange::Answered { command, telemetry, at_stamp: false })
    }

    fn truth() -> GroundTruth {
        GroundTruth { t: 1.234, seq: 1234, x: [0.1, -2.5, 1e-300, f64::MIN_POSITIVE], f: [-0.0, 9.75], ..GroundTruth::default() }
    }

    #[test]
    fn the_frame_comes_back_bit_for_bit() {
        let (frame, exchange) = answered();
        let row = FrameRow::of(&frame, &truth(), &exchange);
        assert_eq!(row.frame(), frame);
        let t = row.truth();
        assert_eq!(
            (t.t.to_bits(), t.seq, t.x.map(f64::to_bits), t.f.map(f64::to_bits)),
            (truth().t.to_bits(), 1234, truth().x.map(f64::to_bits), truth().f.map(f64::to_bits))
        );
        assert_eq!(row.first_difference(&row), None);
        // Every f32 of the telemetry survives f64 exactly, -0.0 and a subnormal included.
        assert_eq!((row.u1_raw as f32).to_bits(), 1);
        assert_eq!((row.u2_raw as f32).to_bits(), (-0.0f32).to_bits());
    }

    #[test]
    fn a_difference_in_the_last_bit_of_any_signal_is_found() {
        let (frame, exchange) = answered();
        let row = FrameRow::of(&frame, &truth(), &exchange);
        let names: Vec<_> = row.signals().iter().map(|(n, _)| *n).collect();
        for (i, name) in names.iter().enumerate() {
            let mut other = row;
            match *name {
                "answer" => other.answer = Answer::Dropped.name(),
                "u1_code" => other.u1_code ^= 1,
                "u2_code" => other.u2_code ^= 1,
                "status" => other.status ^= 1,
                "overruns" => other.overruns ^= 1,
                _ => {
                    let field = match *name {
                        "z_t_ref" => &mut other.z_t_ref,
                        "f_n_ref" => &mut other.f_n_ref,
                        "q1" => &mut other.q1,
                        "q2" => &mut other.q2,
                        "qd1" => &mut other.qd1,
                        "qd2" => &mut other.qd2,
                        "f_t_meas" => &mut other.f_t_meas,
                        "f_n_meas" => &mut other.f_n_meas,
                        "u1_raw" => &mut other.u1_raw,
                        _ => &mut other.u2_raw,
                    };
                    *field = f64::from(f32::from_bits((*field as f32).to_bits() ^ 1));
                }
            }
            let (found, _, _) = row.first_difference(&other).unwrap_or_else(|| panic!("{name}: not found"));
            assert_eq!(found, names[i]);
        }
    }

    #[test]
    fn no_answer_and_a_lost_one_are_told_apart() {
        let (frame, exchange) = answered();
        let Exchange::Answered { command, telemetry, .. } = exchange else { unreachable!() };
        let dropped = FrameRow::of(&frame, &truth(), &Exchange::Dropped { command, telemetry });
        let none = FrameRow::of(&frame, &truth(), &Exchange::NoAnswer);
        assert_eq!(dropped.answer, "dropped");
        assert_eq!((none.answer, none.u1_code, none.u1_raw), ("none", 0, 0.0));
        assert_eq!(FrameRow::of(&frame, &truth(), &exchange).first_difference(&dropped).map(|d| d.0), Some("answer"));
    }
}
