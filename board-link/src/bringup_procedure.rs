//! The bring-up steps the host runs over the line (docs/board.md "Bring-up";
//! `sil-host board`), as a library: each step one or more requests
//! (`arm_app::bringup`), each refusal and each failed check said in words.

use std::{
    io::{Read, Write},
    time::Duration,
};

use arm_app::{
    Joint,
    bringup::{
        BRINGUP_PROTOCOL, CalibrationRecord, EnableOutcome, JogFault, JogOutcome, MAX_JOG_COUNTS, MIN_JOG_COUNTS, Missing, Refusal, Reply,
        Request, Status,
    },
};
use serde::Serialize;

use rig::status_words::describe_status;

use crate::{
    board_backup::{BACKUP_FORMAT, Backup, explain_invalid},
    bringup_line::Client,
};

/// How long a request may wait for its reply (a save erases a flash sector:
/// about 1 s on the STM32F405).
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(5);

/// A step that did not go through: refused by the board, a failed check, or the line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The line failed or the board did not answer (exit 2: nothing done).
    #[error("{0}")]
    Line(String),
    /// The board refused the request, or a check failed (exit 1).
    #[error("{0}")]
    Refused(String),
}

pub use rig::board_protection::{PROTECTION_OFF, check_protection};

/// A refusal in words, with what to do.
pub fn describe_refusal(r: &Refusal) -> String {
    match r {
        Refusal::DriversEnabled => "the drivers are enabled or the closed loop runs: `sil-host board disable` first".into(),
        Refusal::ZerosNotSet => "the encoders' zeros are not set: run `sil-host board calibrate` first".into(),
        Refusal::OutOfRange => "a value is out of its range".into(),
        Refusal::EncoderFault(e) => format!("an encoder gives no reading ({}): check its wiring and magnet", e.describe()),
        Refusal::NoConversion => "the ADC gave no conversion this period: check the load cell's amplifier".into(),
        Refusal::NoSpan => {
            "the force gives less than 40 counts of difference from the tare: is the weight on the load cell, and heavy enough?".into()
        }
        Refusal::InvalidConfig => "the configuration is invalid".into(),
        Refusal::Rate => format!(
            "the control period is not one the image runs ({}), or the board's tick does not run the configuration's period",
            arm_app::rate::RANGE_WORDS
        ),
        Refusal::NoJog => "no jog has run since power-up".into(),
        Refusal::Busy => "a jog is under way".into(),
        Refusal::DirectionsNotChecked => "both joints' directions must be checked by `sil-host board calibrate` first".into(),
        Refusal::LockedOut(s) => s.describe().into(),
        Refusal::Flash(f) => format!("the save failed: {}", f.describe()),
        Refusal::Incomplete(m) => format!("the calibration lacks {}", describe_missing(*m)),
        Refusal::ProtectionOff => format!("controller.runaway_limits = false: {PROTECTION_OFF}"),
        Refusal::NothingToSave => "nothing to save: the settings in force are already the record in flash (loaded at the last reset, \
                                   or saved since); a change sent before a reset is discarded by it (the reset reloads the record): \
                                   send it again, then save"
            .into(),
    }
}

/// The bring-up steps a calibration lacks, in words ("nothing" when none).
pub fn describe_missing(m: Missing) -> String {
    let names: Vec<&str> = m.names().collect();
    if names.is_empty() { "nothing".into() } else { names.join("; ") }
}

/// Why the drivers are off after an enable, or that they came on, in words.
pub fn describe_enable(e: &EnableOutcome) -> String {
    match e {
        EnableOutcome::NotAsked => "no enable since power-up".into(),
        EnableOutcome::Pending => "the enable is still pending".into(),
        EnableOutcome::Enabled { seq } => format!("drivers enabled at period {seq}"),
        EnableOutcome::DriversRefused { seq } => {
            format!(
                "the drivers refused to enable at period {seq}: their fault line (nFAULT) is asserted; check the motor supply and wiring"
            )
        }
        EnableOutcome::SafeState { seq, status } => format!(
            "the firmware went to its safe state at period {seq} ({}, status {status:#x}): drivers left disabled",
            describe_status(*status)
        ),
        EnableOutcome::Cancelled => "a disable came before the drivers enabled".into(),
    }
}

/// A jog's verdict in words.
pub fn describe_jog(j: &JogOutcome) -> String {
    let i = usize::from(j.joint == Joint::Elbow);
    let moved = j.moved_counts[i];
    let deg = f64::from(moved) * 360.0 / 16384.0;
    let what = match j.verdict {
        Ok(()) => "moved its torque's way".to_string(),
        Err(JogFault::WrongDirection) => {
            "moved AGAINST its torque: its motor is wired the other way or its encoder counts the other way; swap the motor's leads, or \
             flip the encoder's direction (`sil-host board calibrate --reversed JOINT`)"
                .into()
        }
        Err(JogFault::NoMotion) => format!(
            "did not move (less than {MIN_JOG_COUNTS} counts): check the motor, its driver and its encoder, and that the arm is free"
        ),
        Err(JogFault::TooFar) => format!("moved more than {MAX_JOG_COUNTS} counts: the jog was stopped; check the torque full scale"),
        Err(JogFault::EncoderFault) => "an encoder gave no reading during the jog".into(),
        Err(JogFault::DriversRefused) => "the drivers refused to enable: the fault line (nFAULT) is asserted".into(),
    };
    format!("jog of {} at code {:+}: {moved:+} counts ({deg:+.2} deg): {what}", j.joint.name(), j.code)
}

/// Sends `request` and returns the reply, a refusal as [`StepError::Refused`].
///
/// # Errors
/// [`StepError`].
pub fn ask<S: Read + Write>(c: &mut Client<S>, request: Request) -> Result<Reply, StepError> {
    match c.request(&request, REPLY_TIMEOUT).map_err(StepError::Line)? {
        Reply::Refused(r) => Err(StepError::Refused(format!("{}: refused: {}", request_name(&request), describe_refusal(&r)))),
        reply => Ok(reply),
    }
}

fn request_name(r: &Request) -> &'static str {
    match r {
        Request::Hello => "hello",
        Request::Status => "status",
        Request::Raw => "raw readings",
        Request::GetCalibration => "get calibration",
        Request::GetConfig => "get configuration",
        Request::SetZeros { .. } => "set zeros",
        Request::Jog { .. } => "jog",
        Request::JogResult => "jog result",
        Request::Tare => "tare",
        Request::Span { .. } => "span",
        Request::SkipSpan { .. } => "skip span",
        Request::SetCalibration(_) => "set calibration",
        Request::Configure(_) => "configure",
        Request::LiftTorqueLimit => "lift the torque limit",
        Request::Enable => "enable",
        Request::Disable => "disable",
        Request::Telemetry => "telemetry",
        Request::Save => "save",
        Request::Restore(_) => "restore",
    }
}

/// Checks that the board speaks this protocol.
///
/// # Errors
/// [`StepError::Line`] when it does not answer or speaks another version.
pub fn hello<S: Read + Write>(c: &mut Client<S>) -> Result<(), StepError> {
    // Replies a killed client left on the line come first: skipped.
    let reply = c.request_until(&Request::Hello, REPLY_TIMEOUT, |r| matches!(r, Reply::Hello { .. })).map_err(StepError::Line)?;
    match reply {
        Reply::Hello { protocol } if protocol == BRINGUP_PROTOCOL => Ok(()),
        Reply::Hello { protocol } => Err(StepError::Line(format!(
            "the board speaks bring-up protocol {protocol}, this sil-host {BRINGUP_PROTOCOL}: flash the matching image"
        ))),
        other => Err(StepError::Line(format!("unexpected reply to hello: {other:?}"))),
    }
}

/// The control law a board's image runs, to bind a scenario's `[law]` table
/// to (`sil-host board configure`): the declaration in `elf`, the image that
/// was flashed (`PAINLEVE_LAW_SPEC`; an ELF that declares none is refused), or
/// without `elf` the paper's laws', held
/// to the digest the board reports (`Status::law_digest`, its law's
/// `firmware::LawSpec::digest`).
///
/// # Errors
/// A message naming what to do when the ELF cannot be read, or when the
/// declaration is not the one the board runs (another law, another build of
/// it, or a law of one's own without `elf`).
pub fn board_law(status: &Status, elf: Option<&std::path::Path>) -> Result<rig::law::LawDescription, String> {
    let law = match elf {
        Some(path) => rig::law::LawDescription::declared_by(path).map_err(|e| e.to_string())?,
        None => rig::law::LawDescription::paper(),
    };
    if law.digest() == status.law_digest {
        return Ok(law);
    }
    Err(match elf {
        None => format!(
            "the board runs a law of one's own (its declaration's digest {:08x}), not the paper's laws: give the image that \
             was flashed, --elf PATH, whose declaration binds the scenario's [law] table",
            status.law_digest
        ),
        Some(path) => format!(
            "{}: its law ({}, digest {:08x}) is not the one the board runs (digest {:08x}): give the ELF that was flashed, \
             or flash this one",
            path.display(),
            if law.is_paper() { "the paper's laws".to_string() } else { format!("`{}`", law.name) },
            law.digest(),
            status.law_digest
        ),
    })
}

/// The board's calibration and configuration in force, as a backup
/// (`GetCalibration`, `GetConfig`; `sil-host board backup`).
///
/// # Errors
/// [`StepError`].
pub fn backup<S: Read + Write>(c: &mut Client<S>) -> Result<Backup, StepError> {
    let Reply::Calibration(calibration) = ask(c, Request::GetCalibration)? else {
        return Err(StepError::Line("unexpected reply to get calibration".into()));
    };
    let Reply::Config(config) = ask(c, Request::GetConfig)? else {
        return Err(StepError::Line("unexpected reply to get configuration".into()));
    };
    Ok(Backup { format: BACKUP_FORMAT, protocol: BRINGUP_PROTOCOL, calibration, config })
}

/// Restores backup `b` with one `Restore` request: the firmware checks it as it
/// checks its flash record at reset and takes it whole or not at all; then reads
/// the settings back (they must equal the file's) and returns the board's status
/// (the settings now unsaved unless the file was what the board held).
///
/// # Errors
/// [`StepError::Refused`] when the firmware refuses it (the message names the
/// value out of range, from [`explain_invalid`]; the board is unchanged) or reads
/// back other settings; [`StepError::Line`].
pub fn restore<S: Read + Write>(c: &mut Client<S>, b: &Backup) -> Result<Status, StepError> {
    match c.request(&Request::Restore(b.stored()), REPLY_TIMEOUT).map_err(StepError::Line)? {
        Reply::Done => {}
        Reply::Refused(r) => {
            let why = match (r, explain_invalid(b)) {
                (Refusal::InvalidConfig | Refusal::OutOfRange, Some(value)) => value,
                _ => describe_refusal(&r),
            };
            return Err(StepError::Refused(format!("restore: refused by the firmware, the board unchanged: {why}")));
        }
        other => return Err(StepError::Line(format!("unexpected reply to restore: {other:?}"))),
    }
    let back = backup(c)?;
    if (back.calibration, back.config) != (b.calibration, b.config) {
        return Err(StepError::Refused("restore: the settings read back differ from the file's".into()));
    }
    status(c)
}

/// The board's status.
///
/// # Errors
/// [`StepError`].
pub fn status<S: Read + Write>(c: &mut Client<S>) -> Result<Status, StepError> {
    match ask(c, Request::Status)? {
        Reply::Status(s) => Ok(s),
        other => Err(StepError::Line(format!("unexpected reply to status: {other:?}"))),
    }
}

/// What `calibrate` asks for.
#[derive(Debug, Clone, Copy)]
pub struct CalibrateOptions {
    /// The calibration pose's joint counts `[theta1, theta2 - theta1]` (2^14 per
    /// turn): the jig's drawing (docs/board.md "Bring-up").
    pub pose_counts: [u16; 2],
    /// Encoders to count the other way from now on `[theta1, elbow]`.
    pub reversed: [bool; 2],
    /// The jog's torque code (at most `MAX_JOG_CODES`).
    pub jog_code: i16,
    /// The jog's length, s (at most `arm_app::bringup::MAX_JOG_US`): sent in
    /// the board's control periods ([`periods_of`] with its
    /// `Status::period_us`), so a jog moves the arm as far at every rate.
    pub jog_s: f64,
    /// Rest between jogs, so that the arm hangs still again, s: counted in the
    /// board's control periods (its raw readings' period, not the host's clock:
    /// a board or an emulated image slower than real time rests as long).
    pub settle_s: f64,
    /// Tare the load cell at the end (nothing on it).
    pub tare: bool,
}

/// How many control periods of `period_us` last `seconds` (rounded, at least
/// one): the bring-up's times in the board's own periods.
pub fn periods_of(seconds: f64, period_us: u32) -> u32 {
    ((seconds * 1e6 / f64::from(period_us.max(1))).round() as u32).max(1)
}

/// Waits until the board has run `periods` control periods more (its raw
/// readings' period counter), polling every 10 ms.
///
/// # Errors
/// [`StepError`] for the line; [`StepError::Refused`] when the board's period
/// does not advance for 5 s (its control tick stopped).
fn settle<S: Read + Write>(c: &mut Client<S>, periods: u32) -> Result<(), StepError> {
    let seq = |c: &mut Client<S>| match ask(c, Request::Raw)? {
        Reply::Raw(r) => Ok(r.seq),
        other => Err(StepError::Line(format!("unexpected reply to raw readings: {other:?}"))),
    };
    let start = seq(c)?;
    let (mut last, mut since) = (start, std::time::Instant::now());
    loop {
        let now = seq(c)?;
        if now.wrapping_sub(start) >= periods {
            return Ok(());
        }
        if now != last {
            (last, since) = (now, std::time::Instant::now());
        } else if since.elapsed() > Duration::from_secs(5) {
            return Err(StepError::Refused(format!("the board's control tick stopped at period {now}")));
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// What `calibrate` tells its operator, and the one thing it asks.
pub trait Operator {
    /// A step done.
    fn say(&mut self, line: &str);
    /// The zeros are set: the jig must come off before the jogs. Returns when
    /// it is off.
    fn remove_jig(&mut self);
}

/// What `calibrate` did.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrateReport {
    /// Every jog, in order.
    pub jogs: Vec<JogOutcome>,
    /// The calibration in force at the end.
    pub calibration: CalibrationRecord,
}

/// The guided calibration: the drivers must be disabled; the encoders'
/// directions as asked, their zeros set at the pose (held by the jig, which the
/// operator then removes); each joint jogged both ways
/// at low torque, which must move it its torque's way by a bounded angle;
/// then the tare. Stops at the first failed step.
///
/// # Errors
/// [`StepError::Refused`] naming the joint and why, or the refused request.
pub fn calibrate<S: Read + Write>(c: &mut Client<S>, o: &CalibrateOptions, op: &mut impl Operator) -> Result<CalibrateReport, StepError> {
    hello(c)?;
    let st = status(c)?;
    if st.drivers_enabled {
        return Err(StepError::Refused("the drivers are enabled: `sil-host board disable` first".into()));
    }
    let jog_periods = periods_of(o.jog_s, st.period_us);
    if !(o.jog_s.is_finite() && o.jog_s > 0.0 && u64::from(jog_periods) * u64::from(st.period_us) <= arm_app::bringup::MAX_JOG_US) {
        return Err(StepError::Refused(format!(
            "a jog of {} s: at most {} s (the board runs {} us periods)",
            o.jog_s,
            arm_app::bringup::MAX_JOG_US as f64 * 1e-6,
            st.period_us
        )));
    }
    if o.reversed != [false; 2] {
        let Reply::Calibration(mut cal) = ask(c, Request::GetCalibration)? else {
            return Err(StepError::Line("unexpected reply to get calibration".into()));
        };
        cal.reversed = o.reversed;
        ask(c, Request::SetCalibration(cal))?;
    }
    ask(c, Request::SetZeros { pose_counts: o.pose_counts })?;
    op.say(&format!("zeros set at the pose {:?} counts", o.pose_counts));
    // From here the board has changed: a line that fails is no longer "nothing
    // done" (exit 2) but a calibration left half done (exit 1).
    let periods = (jog_periods as u16, periods_of(o.settle_s, st.period_us));
    calibrate_after_zeros(c, o, periods, op).map_err(|e| match e {
        StepError::Line(m) => StepError::Refused(format!(
            "the line failed after the encoders' zeros were set ({m}): the calibration is half done and not saved; run calibrate again"
        )),
        refused => refused,
    })
}

/// `calibrate`'s steps after the zeros: the jogs and the tare, the jogs'
/// length and the rests `(jog, settle)` in the board's periods.
fn calibrate_after_zeros<S: Read + Write>(
    c: &mut Client<S>,
    o: &CalibrateOptions,
    (jog_periods, settle_periods): (u16, u32),
    op: &mut impl Operator,
) -> Result<CalibrateReport, StepError> {
    op.remove_jig();
    let mut jogs = Vec::new();
    for joint in [Joint::Theta1, Joint::Elbow] {
        for code in [o.jog_code, -o.jog_code] {
            ask(c, Request::Jog { joint, code, periods: jog_periods })?;
            let outcome = loop {
                std::thread::sleep(Duration::from_millis(20));
                match c.request(&Request::JogResult, REPLY_TIMEOUT).map_err(StepError::Line)? {
                    Reply::Refused(Refusal::Busy) => {}
                    Reply::Jogged(j) => break j,
                    Reply::Refused(r) => return Err(StepError::Refused(format!("jog result: refused: {}", describe_refusal(&r)))),
                    other => return Err(StepError::Line(format!("unexpected reply to jog result: {other:?}"))),
                }
            };
            op.say(&describe_jog(&outcome));
            jogs.push(outcome);
            if outcome.verdict.is_err() {
                return Err(StepError::Refused(format!("calibration stopped: {}", describe_jog(&outcome))));
            }
            settle(c, settle_periods)?;
        }
    }
    if o.tare {
        ask(c, Request::Tare)?;
        op.say("load cell tared (nothing on it)");
    }
    let Reply::Calibration(calibration) = ask(c, Request::GetCalibration)? else {
        return Err(StepError::Line("unexpected reply to get calibration".into()));
    };
    Ok(CalibrateReport { jogs, calibration })
}

/// How long `enable` waits for the drivers to come on: the firmware resets at
/// the next tick and the drivers enable at its first command, two periods
/// (8 ms at 250 Hz, the slowest rate); the rest is the line's and a loaded
/// host's slack.
pub const ENABLE_TIMEOUT: Duration = Duration::from_secs(2);

/// How long `enable` watches the drivers once they came on, in the board's
/// control periods, at least (50 ms at 1 kHz), before it says done: the
/// firmware's checks that need a few periods to confirm a fault (the sensor
/// consistency check latches within 3 to 24 periods on an arm that cannot be
/// where its sensors say, the runaway limits within 3 or 10 ms) have all had
/// their time. At a faster rate the watch is [`ENABLE_WATCH_S`] long instead
/// ([`enable_watch_periods`]). A board whose period counter stops for 5 s is
/// reported (its control tick stopped).
pub const ENABLE_WATCH_PERIODS: u32 = 50;

/// The shortest watch of `enable`, s (the runaway limits' 10 ms with a margin).
pub const ENABLE_WATCH_S: f64 = 0.05;

/// The periods `enable` watches the drivers for on a board whose tick runs
/// `period_us`: [`ENABLE_WATCH_PERIODS`], or [`ENABLE_WATCH_S`] when longer
/// (500 periods at 10 kHz).
pub fn enable_watch_periods(period_us: u32) -> u32 {
    ENABLE_WATCH_PERIODS.max(periods_of(ENABLE_WATCH_S, period_us))
}

/// Enables the drivers, reads the state back until the enable has an outcome,
/// then watches the drivers for [`enable_watch_periods`] of the board's
/// periods (its `Status::period_us`): `Ok` only when they came on and are still on at the end.
///
/// # Errors
/// [`StepError::Refused`] when the board refuses (locked out, incomplete
/// calibration: saying why), when the drivers did not come on (their fault
/// line, the firmware's safe state with its reason in words), when no outcome
/// came within [`ENABLE_TIMEOUT`], or when the drivers went off within the
/// watch (the period and the firmware's status word in words: the safe state
/// and its reason); [`StepError::Line`] for the line.
pub fn enable<S: Read + Write>(c: &mut Client<S>) -> Result<Status, StepError> {
    ask(c, Request::Enable)?;
    let start = std::time::Instant::now();
    let on_at = loop {
        let st = status(c)?;
        match st.last_enable {
            EnableOutcome::Pending if start.elapsed() < ENABLE_TIMEOUT => std::thread::sleep(Duration::from_millis(5)),
            EnableOutcome::Pending => {
                return Err(StepError::Refused(format!(
                    "enable: no outcome within {} s: the control loop is not ticking (period {})",
                    ENABLE_TIMEOUT.as_secs(),
                    st.periods
                )));
            }
            EnableOutcome::Enabled { seq } => break (seq, enable_watch_periods(st.period_us)),
            other => return Err(StepError::Refused(format!("enable: the drivers are off: {}", describe_enable(&other)))),
        }
    };
    watch_drivers(c, on_at)
}

/// Watches the drivers that came on at period `on_at` until the board has run
/// `watch` periods since, polling its status.
fn watch_drivers<S: Read + Write>(c: &mut Client<S>, (on_at, watch): (u32, u32)) -> Result<Status, StepError> {
    let (mut last, mut since) = (None, std::time::Instant::now());
    loop {
        let st = status(c)?;
        if !st.drivers_enabled {
            return Err(StepError::Refused(format!(
                "enable: the drivers came on at period {on_at} and went off again by period {} (watched for {watch} \
                 periods): {}",
                st.periods,
                describe_status(st.status)
            )));
        }
        if st.periods.wrapping_sub(on_at) >= watch {
            return Ok(st);
        }
        if last != Some(st.periods) {
            (last, since) = (Some(st.periods), std::time::Instant::now());
        } else if since.elapsed() > Duration::from_secs(5) {
            return Err(StepError::Refused(format!("enable: the board's control tick stopped at period {}", st.periods)));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}
