//! What `board status` and `board watch` read from the board, and the words
//! they print it in: the status, the raw readings, the calibration and the
//! telemetry window.

use std::io::Write;

use arm_app::{
    bringup::{CalibrationRecord, EnableOutcome, RawReadings, Reply, Request, SpanStep, Status},
    telemetry::ArmTelemetry,
};
use board_link::{
    bringup_line::Client,
    bringup_procedure::{self as bp, StepError},
};
use firmware::pil::StepClock;
use rig::status_words::describe_status;
use serde::Serialize;

/// Everything `status` reads.
#[derive(Debug, Serialize)]
pub(super) struct Snapshot {
    status: Status,
    raw: RawReadings,
    calibration: CalibrationRecord,
    telemetry: Option<ArmTelemetry>,
}

pub(super) fn snapshot<S: std::io::Read + Write>(c: &mut Client<S>) -> Result<Snapshot, StepError> {
    let status = bp::status(c)?;
    let Reply::Raw(raw) = bp::ask(c, Request::Raw)? else { return Err(StepError::Line("unexpected reply to raw".into())) };
    let Reply::Calibration(calibration) = bp::ask(c, Request::GetCalibration)? else {
        return Err(StepError::Line("unexpected reply to get calibration".into()));
    };
    let Reply::Telemetry(telemetry) = bp::ask(c, Request::Telemetry)? else {
        return Err(StepError::Line("unexpected reply to telemetry".into()));
    };
    Ok(Snapshot { status, raw, calibration, telemetry })
}

/// The widest `watch` line, characters: a reading fits an 80-column terminal
/// (issue 69; a 6-digit period, three-digit angles and two-digit forces take 80).
pub const WATCH_COLUMNS: usize = 80;

/// One reading of `watch` on one line of at most [`WATCH_COLUMNS`] characters:
/// `#` and the period, the drivers, the joints (theta1 and the elbow's angle in
/// degrees once the zeros are set, else raw counts), the load cell (newtons
/// once tared and spanned or skipped, else ADC counts), the belt's counter, the
/// fault line when asserted, and the status word in short (`ok`, the safe
/// state's reason, the flags: `status` says them in words); cut with `...`
/// beyond the width.
pub(super) fn watch_line(s: &Snapshot) -> String {
    let st = &s.status;
    let r = &s.raw;
    let joints = match (r.encoder_counts, [0, 1].map(|i| r.encoder_counts[i].ok().and_then(|n| joint_degrees(n, &s.calibration, i)))) {
        (_, [Some(a), Some(b)]) => format!("θ1 {a:+.2}° el {b:+.2}°"),
        ([Ok(a), Ok(b)], _) => format!("θ1 {a} el {b} counts"),
        ([a, b], _) => {
            let one = |x: Result<u16, arm_app::EncoderFault>| x.map_or_else(|e| format!("{e:?}"), |n| n.to_string());
            format!("θ1 {} el {}", one(a), one(b))
        }
    };
    let load = match r.adc_counts {
        None => "load cell: no conversion".to_string(),
        Some(counts) => match load_newtons(counts, &s.calibration) {
            [Some(t), Some(n)] => format!("f_t {t:+.2} f_n {n:+.2} N"),
            _ => format!("f_t {} f_n {} counts", counts[0], counts[1]),
        },
    };
    let line = format!(
        "#{} drv {}  {joints}  {load}  belt {}{}  {}",
        st.periods,
        if st.drivers_enabled { "on" } else { "off" },
        r.belt_count,
        if r.driver_fault { "  nFAULT ASSERTED" } else { "" },
        short_status(st.status)
    );
    fit(&line, WATCH_COLUMNS)
}

/// A status word in a few characters (`watch`): `ok`, `safe: REASON`, or its
/// flags' short names (docs/wire.md; `describe_status` says them in words).
fn short_status(word: u32) -> String {
    use shared::wire::status;
    let mut parts = Vec::new();
    if word & status::SAFE_STATE != 0 {
        parts.push(firmware::SafeReason::from_status(word).map_or_else(|| "safe: unknown".to_string(), |r| format!("safe: {r:?}")));
    }
    for (bit, name) in [
        (status::BAD_FRAME, "bad frame"),
        (status::STALE_FRAME, "stale"),
        (status::SEQUENCE_GAP, "seq gap"),
        (status::LIFT_OFF, "lift-off"),
        (status::SATURATED_U1, "u1 sat"),
        (status::SATURATED_U2, "u2 sat"),
        (status::DEADLINE_MISS, "deadline"),
        (status::LOAD_CLIPPED, "clipped"),
        (status::REFERENCE_MOVING, "moving"),
    ] {
        if word & bit != 0 {
            parts.push(name.to_string());
        }
    }
    if parts.is_empty() { "ok".into() } else { parts.join(", ") }
}

/// `line` cut to `width` characters, `...` at its end when cut.
fn fit(line: &str, width: usize) -> String {
    if line.chars().count() <= width {
        line.to_string()
    } else {
        let mut cut: String = line.chars().take(width - 3).collect();
        cut.push_str("...");
        cut
    }
}

/// The load cell's forces `[f_t, f_n]`, N, from its ADC counts, for each axis
/// whose calibration is known: tared, and spanned (or its span skipped: the
/// nominal gain kept on purpose); `None` for an axis still in ADC counts.
fn load_newtons(counts: [u16; 2], cal: &CalibrationRecord) -> [Option<f64>; 2] {
    [0, 1].map(|i| {
        (cal.tared && cal.span[i] != SpanStep::NotDone)
            .then(|| (f64::from(counts[i]) - f64::from(cal.load_zero_counts[i])) * f64::from(cal.load_newtons_per_count[i]))
    })
}

/// The calibration in force, in words (`calibrate`'s end, `status`).
pub(super) fn describe_calibration(c: &CalibrationRecord) -> Vec<String> {
    let reversed = match c.reversed {
        [false, false] => "neither encoder reversed",
        [true, false] => "theta1's encoder reversed",
        [false, true] => "the elbow's encoder reversed",
        [true, true] => "both encoders reversed",
    };
    let span = |i: usize| match c.span[i] {
        SpanStep::NotDone => "span not done",
        SpanStep::Measured => "spanned with a known weight",
        SpanStep::Skipped => "span skipped: the nominal gain",
    };
    vec![
        format!(
            "encoders: zeros at count {} (theta1) and {} (elbow) of 16384, {reversed}; {}; directions {}",
            c.zero_counts[0],
            c.zero_counts[1],
            if c.zeros_set { "set at the jig's pose" } else { "not set (the compiled-in defaults)" },
            if c.directions_checked { "checked by the jogs" } else { "not checked" }
        ),
        format!(
            "load cell: {} at f_t {} and f_n {} counts; gains f_t {:.6} N per count ({}), f_n {:.6} N per count ({})",
            if c.tared { "tared" } else { "not tared, zero" },
            c.load_zero_counts[0],
            c.load_zero_counts[1],
            c.load_newtons_per_count[0],
            span(0),
            c.load_newtons_per_count[1],
            span(1)
        ),
        format!("belt: {:e} m per count", c.belt_metres_per_count),
    ]
}

pub(super) fn print_snapshot(s: &Snapshot) {
    let st = &s.status;
    outln!(
        "state: {:?}, period {}, drivers {}, overruns {}",
        st.activity,
        st.periods,
        if st.drivers_enabled { "enabled" } else { "disabled" },
        st.overruns
    );
    outln!("control tick: {} us ({:.0} Hz)", st.period_us, 1e6 / f64::from(st.period_us.max(1)));
    outln!("firmware status {:#x}: {}", st.status, describe_status(st.status));
    let off_again = matches!(st.last_enable, EnableOutcome::Enabled { .. }) && !st.drivers_enabled;
    outln!(
        "last enable: {}{}",
        bp::describe_enable(&st.last_enable),
        if off_again { "; off again since (the firmware status above says why)" } else { "" }
    );
    outln!(
        "settings: {:?} ({}); zeros set {}, directions checked {}, torque limit {} codes of 2048",
        st.settings,
        st.settings.describe(),
        st.zeros_set,
        st.directions_checked,
        st.torque_limit_codes
    );
    if !st.missing.is_empty() {
        outln!("calibration lacks: {}", bp::describe_missing(st.missing));
    }
    let r = &s.raw;
    for (i, name) in ["theta1", "elbow"].iter().enumerate() {
        match r.encoder_counts[i] {
            Ok(n) => outln!(
                "encoder {name}: raw count {n} of 16384{}, AGC {}",
                joint_degrees(n, &s.calibration, i).map_or_else(String::new, |d| format!(" ({d:+.3} deg)")),
                r.encoder_agc[i].map_or_else(|| "unreadable".into(), |a| a.to_string())
            ),
            Err(e) => outln!("encoder {name}: no reading ({})", e.describe()),
        }
    }
    match r.adc_counts {
        Some(counts @ [t, n]) => {
            let newtons = load_newtons(counts, &s.calibration);
            let axis = |f: Option<f64>| f.map_or_else(|| "not yet spanned".to_string(), |f| format!("{f:+.3} N"));
            outln!("load cell: f_t {} ({t} counts), f_n {} ({n} counts of 4095)", axis(newtons[0]), axis(newtons[1]));
        }
        None => outln!("load cell ADC: no conversion this period"),
    }
    outln!("belt counter: {}; driver fault line: {}", r.belt_count, if r.driver_fault { "ASSERTED" } else { "clear" });
    for line in describe_calibration(&s.calibration) {
        outln!("calibration: {line}");
    }
    match &s.telemetry {
        Some(t) => outln!("last window (period {}): {}", t.seq, describe_window(t)),
        None => outln!("telemetry: no window closed yet"),
    }
}

/// A telemetry window in words: the step's ticks and the stack's high-water
/// mark where the board measures them, else that they are not measured (the
/// board twin's step takes no time and it has no stack: every figure is 0).
fn describe_window(t: &ArmTelemetry) -> String {
    let step = match t.clock {
        StepClock::Simulated => "step time not measured (the board twin's step takes no time)".to_string(),
        _ => format!("step median {} worst {} ticks", t.step.median, t.step.worst),
    };
    let stack = match (t.clock, t.stack_high_water_bytes) {
        (StepClock::Simulated, _) => "stack not measured (the twin runs on the PC's stack)".to_string(),
        (_, 0) => "stack high-water not measured".to_string(),
        (_, b) => format!("stack high-water {b} B"),
    };
    format!("{step}, overruns {}, {stack}", t.overruns)
}

/// Joint `i`'s calibrated angle from its raw count, degrees in (-180, 180]
/// (`[theta1, theta2 - theta1]`), once the zeros are set.
fn joint_degrees(raw: u16, cal: &CalibrationRecord, i: usize) -> Option<f64> {
    if !cal.zeros_set {
        return None;
    }
    let (raw, zero) = (i32::from(raw), i32::from(cal.zero_counts[i]));
    let counts = if cal.reversed[i] { zero - raw } else { raw - zero }.rem_euclid(1 << 14);
    let deg = f64::from(counts) * 360.0 / 16384.0;
    Some(if deg > 180.0 { deg - 360.0 } else { deg })
}
