//! `sil-host board` (bring-up over the board's serial port) and `sil-host
//! board-twin` (the board twin serving the same protocol on a pseudo-terminal):
//! thin commands over `board_link::bringup_procedure` and `board_link::bringup_line`.

use std::{io::Write, sync::Arc, time::Duration};

use arm_app::{
    bringup::{CalibrationRecord, EnableOutcome, MAX_JOG_CODES, RawReadings, Reply, Request, SpanStep, Status},
    telemetry::ArmTelemetry,
};
use board_link::{
    board_backup,
    bringup_line::{self, Client, Pty},
    bringup_procedure::{self as bp, CalibrateOptions, StepError},
    free_arm::{ArmBoard, FreeArm},
};
use board_twin::{BusFaults, FlashModel};
use firmware::pil::StepClock;
use rig::{setup::firmware_config, status_words::describe_status};
use serde::Serialize;

use crate::{
    cli::{AxisArg, BoardArgs, BoardCommand, BoardTwinArgs, FlashArg, JointArg},
    error::CliError,
};
use experiments::scenario::load_scenario;

/// A bring-up step's failure as the command's error: a line that does not
/// answer as the protocol says is bad input (exit 2), a refusal of the board
/// [`CliError::Board`] (exit 1).
fn step(e: StepError) -> CliError {
    match e {
        StepError::Line(m) => CliError::bad_input(m),
        StepError::Refused(m) => CliError::Board(m),
    }
}

/// Everything `status` reads.
#[derive(Debug, Serialize)]
struct Snapshot {
    status: Status,
    raw: RawReadings,
    calibration: CalibrationRecord,
    telemetry: Option<ArmTelemetry>,
}

fn snapshot<S: std::io::Read + Write>(c: &mut Client<S>) -> Result<Snapshot, StepError> {
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

/// The widest `watch` line, characters: a reading fits a 100-column terminal.
pub const WATCH_COLUMNS: usize = 100;

/// One reading of `watch` on one line of at most [`WATCH_COLUMNS`] characters:
/// `#` and the period, the drivers, the joints (theta1 and the elbow's angle in
/// degrees once the zeros are set, else raw counts), the load cell (newtons
/// once tared and spanned or skipped, else ADC counts), the belt's counter, the
/// fault line when asserted, and the status word in short (`ok`, the safe
/// state's reason, the flags: `status` says them in words); cut with `...`
/// beyond the width.
fn watch_line(s: &Snapshot) -> String {
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
        "#{} | drv {} | {joints} | {load} | belt {}{} | {}",
        st.periods,
        if st.drivers_enabled { "on" } else { "off" },
        r.belt_count,
        if r.driver_fault { " | nFAULT ASSERTED" } else { "" },
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
fn describe_calibration(c: &CalibrationRecord) -> Vec<String> {
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

/// The fields of `new` that differ from `old` (two JSON documents of one
/// structure), as `(dotted key, old, new)`: what `configure` changed.
fn changes(prefix: &str, old: &serde_json::Value, new: &serde_json::Value) -> Vec<(String, serde_json::Value, serde_json::Value)> {
    match (old, new) {
        (serde_json::Value::Object(a), serde_json::Value::Object(b)) => b
            .iter()
            .flat_map(|(k, v)| {
                let key = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                changes(&key, a.get(k).unwrap_or(&serde_json::Value::Null), v)
            })
            .collect(),
        _ if old == new => Vec::new(),
        _ => vec![(prefix.to_string(), old.clone(), new.clone())],
    }
}

fn print_snapshot(s: &Snapshot) {
    let st = &s.status;
    outln!(
        "state: {:?}, period {}, drivers {}, overruns {}",
        st.activity,
        st.periods,
        if st.drivers_enabled { "enabled" } else { "disabled" },
        st.overruns
    );
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

fn emit<T: Serialize>(json: bool, value: &T, human: impl FnOnce()) {
    if json {
        outln!("{}", serde_json::to_string_pretty(value).unwrap_or_default());
    } else {
        human();
    }
}

/// The operator at a terminal: the steps printed (not with `--json`), and the
/// jig's removal waited for with Enter when standard input is a terminal (a
/// script's or the twin's calibration goes on at once).
struct Terminal {
    json: bool,
}

impl bp::Operator for Terminal {
    fn say(&mut self, line: &str) {
        if !self.json {
            outln!("{line}");
        }
    }

    fn remove_jig(&mut self) {
        use std::io::IsTerminal;
        if std::io::stdin().is_terminal() {
            eprint!("remove the calibration jig (the arm must hang free), then press Enter: ");
            let _ = std::io::stdin().read_line(&mut String::new());
        }
    }
}

/// `sil-host board`.
///
/// # Errors
/// [`CliError::Analysis`] (exit 2) for bad input, a port that does not open or a
/// board that does not answer; [`CliError::Board`] (exit 1) for a refusal or a
/// failed check.
pub fn run(args: &BoardArgs) -> Result<(), CliError> {
    // A reader that goes away (`board status | head -1`) or a full disk ends
    // the command as every command (crate::stdout): quietly, exit 141, or with a
    // message, exit 1; `watch` stops at the first failed line.
    let mut c = Client::open(&args.port, args.baud).map_err(CliError::bad_input)?;
    bp::hello(&mut c).map_err(step)?;
    let json = args.json;
    let done = |what: &str| emit(json, &serde_json::json!({ "done": what }), || outln!("{what}: done"));
    match &args.command {
        BoardCommand::Status => {
            let s = snapshot(&mut c).map_err(step)?;
            emit(json, &s, || print_snapshot(&s));
        }
        BoardCommand::Watch { interval_ms, count } => {
            let stop = crate::cancel::stop_flag();
            // On a terminal one line, rewritten in place; into a pipe or a file,
            // one line per reading (JSON: one document per reading).
            let tty = std::io::IsTerminal::is_terminal(&std::io::stdout());
            let mut n = 0;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) && !crate::stdout::failed() && count.is_none_or(|k| n < k) {
                let s = snapshot(&mut c).map_err(step)?;
                if json {
                    outln!("{}", serde_json::to_string(&s).unwrap_or_default());
                } else if tty {
                    // Carriage return, erase the line, then the new reading.
                    out!("\r\x1b[2K{}", watch_line(&s));
                } else {
                    outln!("{}", watch_line(&s));
                }
                n += 1;
                std::thread::sleep(Duration::from_millis(*interval_ms));
            }
            if tty && !json {
                outln!();
            }
            if crate::cancel::exit_code().is_some() {
                // Ctrl-C or SIGTERM: the shell's 130 or 143, as every command.
                return Err(CliError::interrupted(format!("watch stopped after {n} readings")));
            }
        }
        BoardCommand::Calibrate { pose_deg, reversed, jog_nm, no_tare } => {
            let [t1, el] = pose_deg[..] else {
                return Err(CliError::bad_input("--pose-deg needs THETA1,ELBOW in degrees (the jig's drawing)"));
            };
            if ![t1, el].iter().all(|d| d.is_finite() && *d > -180.0 && *d <= 180.0) {
                return Err(CliError::bad_input(format!(
                    "--pose-deg {t1},{el}: each angle in (-180, 180] degrees (theta1 from straight down, the elbow's theta2 - theta1)"
                )));
            }
            let max_nm = f64::from(MAX_JOG_CODES) * 5.0 / 2048.0;
            if !(jog_nm.is_finite() && *jog_nm > 0.0 && *jog_nm <= max_nm) {
                return Err(CliError::bad_input(format!("--jog-nm {jog_nm}: must be in (0, {max_nm:.2}] N m")));
            }
            let o = CalibrateOptions {
                pose_counts: [t1, el].map(|d| shared::wire::encode_angle(d.to_radians())),
                reversed: [JointArg::Theta1, JointArg::Elbow].map(|j| reversed.contains(&j)),
                jog_code: (jog_nm / 5.0 * 2048.0).round() as i16,
                jog_periods: 100,
                settle_periods: 300,
                tare: !no_tare,
            };
            let report = bp::calibrate(&mut c, &o, &mut Terminal { json }).map_err(step)?;
            emit(json, &report, || {
                outln!("calibrate: done; the calibration in force (not yet saved):");
                for line in describe_calibration(&report.calibration) {
                    outln!("  {line}");
                }
                outln!("next: `sil-host board span` with a known weight (or --skip) on each axis, `configure`, `save`, `enable`");
            });
        }
        BoardCommand::Span { axis, newtons, skip } => {
            let axis = match axis {
                AxisArg::Tangential => 0,
                AxisArg::Normal => 1,
            };
            let request = match newtons {
                _ if *skip => Request::SkipSpan { axis },
                Some(n) if n.is_finite() && *n != 0.0 && n.abs() <= 25.0 => Request::Span { axis, newtons: *n as f32 },
                Some(n) => return Err(CliError::bad_input(format!("--newtons {n}: must be a non-zero force of at most 25 N"))),
                None => return Err(CliError::bad_input("span needs --newtons or --skip")),
            };
            let reply = match c.request(&request, bp::REPLY_TIMEOUT).map_err(CliError::bad_input)? {
                // The force was in range: the gain it gives is not.
                Reply::Refused(arm_app::bringup::Refusal::OutOfRange) => {
                    return Err(CliError::Board(
                        "span: refused: the gain it gives (the force over the counts from the tare) is not the load cell's: \
                         positive and within a factor 4 of the nominal 25/2048 N per count (docs/hardware.md \"The calibration's \
                         ranges\"); is the weight on this axis, the force's sign right, the front end wired as documented?"
                            .into(),
                    ));
                }
                Reply::Refused(r) => return Err(CliError::Board(format!("span: refused: {}", bp::describe_refusal(&r)))),
                reply => reply,
            };
            let Reply::Calibration(cal) = reply else {
                return Err(CliError::bad_input("unexpected reply to span"));
            };
            let i = usize::from(axis);
            let name = ["f_t", "f_n"][i];
            let gain = cal.load_newtons_per_count[i];
            let ratio = f64::from(gain) / (25.0 / 2048.0);
            emit(json, &cal, || {
                if *skip {
                    outln!("span skipped: {name} keeps the nominal gain {gain:.6} N per count");
                } else {
                    outln!(
                        "span set: {name} gain {gain:.6} N per count ({ratio:.3} times the nominal 25/2048); {name} now reads in newtons"
                    );
                }
            });
        }
        BoardCommand::Configure { scenario } => {
            let s = load_scenario(scenario)?;
            let config = firmware_config(&s);
            // A board never runs without its runaway limits: refused here, naming
            // the key, before the firmware refuses it too.
            bp::check_protection(&config, "controller.runaway_limits").map_err(CliError::bad_input)?;
            let Reply::Config(now) = bp::ask(&mut c, Request::GetConfig).map_err(step)? else {
                return Err(CliError::bad_input("unexpected reply to get configuration"));
            };
            // The image's timer runs one rate: say both when they differ.
            if now.period != config.period {
                return Err(CliError::Board(format!(
                    "configure: refused: the scenario's control period is {} us ({:.0} Hz) and the image's timer runs {} us ({:.0} Hz); set timing.rate_hz to the image's",
                    config.period.as_us(),
                    1e6 / config.period.as_us() as f64,
                    now.period.as_us(),
                    1e6 / now.period.as_us() as f64
                )));
            }
            bp::ask(&mut c, Request::Configure(config)).map_err(step)?;
            let json_of = |c: &firmware::Config| serde_json::to_value(c).unwrap_or_default();
            let changed = changes("config", &json_of(&now), &json_of(&config));
            let listed: Vec<_> = changed.iter().map(|(k, a, b)| serde_json::json!({ "key": k, "old": a, "new": b })).collect();
            emit(json, &serde_json::json!({ "done": "configure", "changed": listed }), || {
                if changed.is_empty() {
                    outln!("configure: done: nothing changed (the configuration in force is the scenario's)");
                } else {
                    outln!("configure: done: {} setting(s) changed, not yet saved (`sil-host board save`):", changed.len());
                    for (k, a, b) in &changed {
                        outln!("  {k} = {a} -> {b}");
                    }
                }
            });
        }
        BoardCommand::Enable => {
            let st = bp::enable(&mut c).map_err(step)?;
            emit(json, &serde_json::json!({ "done": "enable", "status": st }), || {
                outln!(
                    "enable: done: {}; still on at period {} ({} periods watched): {}",
                    bp::describe_enable(&st.last_enable),
                    st.periods,
                    bp::ENABLE_WATCH_PERIODS,
                    describe_status(st.status)
                );
            });
        }
        BoardCommand::Backup { file, force } => {
            if file.exists() && !force {
                return Err(CliError::bad_input(format!("backup: {} exists: give --force to overwrite it", file.display())));
            }
            let b = bp::backup(&mut c).map_err(step)?;
            board_backup::write(file, &b).map_err(|e| CliError::bad_input(e.to_string()))?;
            let controller = format!("{:?}", b.config.controller).to_lowercase();
            emit(json, &serde_json::json!({ "done": "backup", "file": file, "backup": b }), || {
                outln!(
                    "backup: done: the calibration (lacks: {}) and the {controller} configuration written to {}",
                    bp::describe_missing(b.calibration.missing()),
                    file.display()
                );
            });
        }
        BoardCommand::Restore { file } => {
            let b = board_backup::read(file).map_err(|e| CliError::bad_input(e.to_string()))?;
            // The firmware's own rules, named by key, before anything is sent.
            board_backup::validate(&b).map_err(|e| CliError::bad_input(format!("{}: {e}", file.display())))?;
            let st = bp::restore(&mut c, &b).map_err(step)?;
            emit(json, &serde_json::json!({ "done": "restore", "file": file, "status": st }), || {
                outln!("restore: done: the calibration and configuration of {} are in force", file.display());
                outln!(
                    "settings: {}; torque limit {} codes of 2048{}",
                    st.settings.describe(),
                    st.torque_limit_codes,
                    if st.settings.allows_enable() { "" } else { "; next: `sil-host board save`" }
                );
            });
        }
        BoardCommand::Save => {
            bp::ask(&mut c, Request::Save).map_err(step)?;
            let b = bp::backup(&mut c).map_err(step)?;
            emit(json, &serde_json::json!({ "done": "save", "saved": b }), || {
                outln!(
                    "save: done: the calibration and the {} configuration in force are the record in flash (loaded at every reset)",
                    b.config.controller
                );
            });
        }
        BoardCommand::LiftTorqueLimit | BoardCommand::Disable => {
            let (request, name) = match args.command {
                BoardCommand::LiftTorqueLimit => (Request::LiftTorqueLimit, "lift the torque limit"),
                _ => (Request::Disable, "disable"),
            };
            bp::ask(&mut c, request).map_err(step)?;
            done(name);
        }
    }
    Ok(())
}

/// `sil-host board-twin --pty`.
///
/// # Errors
/// [`CliError`]: a bad scenario or board description (exit 2), a pseudo-terminal
/// that does not open, a plant failure.
pub fn twin(args: &BoardTwinArgs) -> Result<(), CliError> {
    let s = load_scenario(&args.scenario)?;
    if let Some(t) = args.serve_for
        && !(t.is_finite() && t > 0.0)
    {
        return Err(CliError::bad_input(format!("--serve-for {t}: must be a positive number of seconds")));
    }
    let flash = if args.flash == FlashArg::Erased {
        FlashModel::erased()
    } else {
        FlashModel::brought_up(&s.calibration.arm_calibration(), firmware_config(&s))
            .map_err(|e| CliError::bad_input(format!("the settings record: {}", e.describe())))?
    };
    if args.flash == FlashArg::Corrupt {
        // One bit of the record's frame: its CRC-32C no longer matches.
        flash.bytes().borrow_mut()[12] ^= 0x10;
    }
    // A board's compiled-in configuration has the runaway limits on, always: a
    // scenario that turns them off puts that in the saved record only (`--flash
    // saved`), which the board refuses at reset, the drivers locked out.
    let mut s = s;
    s.controller.runaway_limits = true;
    if args.emulated {
        let elf = args.elf.clone().unwrap_or_else(board_link::emulator_link::default_image);
        let arm = FreeArm::emulated(&s, s.board, &flash, &elf).map_err(|e| CliError::bad_input(e.to_string()))?;
        serve_arm(args, &s, arm, "emulated arm image")
    } else {
        let arm = FreeArm::with_flash(&s, s.board, &s.calibration, flash).map_err(|e| CliError::bad_input(e.to_string()))?;
        serve_arm(args, &s, arm, "board twin")
    }
}

/// What the twin's operator does, from a line of its standard input.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Operator {
    /// Hangs the load `[f_t, f_n]`, N, on the load cell (`weight AXIS NEWTONS`, `weight off`).
    Weight([f64; 2]),
    /// Presses the reset button (`reset`).
    Reset,
    /// Raises the belt to the tip (`belt up`) or lowers it below the hanging
    /// tip (`belt down`).
    Belt(bool),
}

/// A line of the twin's standard input: `weight AXIS NEWTONS`, `weight off`,
/// `reset`, `belt up` or `belt down`.
fn operator_command(line: &str) -> Result<Operator, String> {
    match line.split_whitespace().collect::<Vec<_>>()[..] {
        ["reset"] => Ok(Operator::Reset),
        ["belt", "up"] => Ok(Operator::Belt(true)),
        ["belt", "down"] => Ok(Operator::Belt(false)),
        _ => weight_command(line).map(Operator::Weight),
    }
}

/// `weight AXIS NEWTONS` or `weight off`: the load `[f_t, f_n]` it hangs, N.
fn weight_command(line: &str) -> Result<[f64; 2], String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let usage = || format!("`{line}`: expected `weight normal|tangential NEWTONS`, `weight off`, `reset`, `belt up` or `belt down`");
    match words[..] {
        ["weight", "off"] => Ok([0.0; 2]),
        ["weight", axis, n] => {
            let n: f64 = n.parse().map_err(|_| usage())?;
            if !(n.is_finite() && n.abs() <= 25.0) {
                return Err(format!("`{line}`: the load cell takes at most 25 N"));
            }
            match axis {
                "normal" => Ok([0.0, n]),
                "tangential" => Ok([n, 0.0]),
                _ => Err(usage()),
            }
        }
        _ => Err(usage()),
    }
}

/// Announces the port and the pose, then serves `arm` until stopped.
fn serve_arm<B: ArmBoard>(args: &BoardTwinArgs, s: &rig::scenario::Scenario, mut arm: FreeArm<B>, what: &str) -> Result<(), CliError> {
    if args.fault_line {
        arm.set_faults(BusFaults { driver_fault: true, ..BusFaults::default() });
    }
    let mut pty = Pty::open().map_err(CliError::bad_input)?;
    let pose = arm.pose_counts();
    let pose_deg = pose.map(|c| {
        let d = f64::from(c) * 360.0 / 16384.0;
        if d > 180.0 { d - 360.0 } else { d }
    });
    let flash_name = format!("{:?}", args.flash).to_lowercase();
    if args.json {
        outln!("{}", serde_json::json!({ "port": pty.path, "pose_deg": pose_deg, "pose_counts": pose, "flash": flash_name }));
    } else {
        outln!(
            "{what} on {}: the arm hangs at theta1 {:.6} deg, elbow {:.6} deg (counts {:?}: the jig's pose); flash {flash_name}{}",
            pty.path.display(),
            pose_deg[0],
            pose_deg[1],
            pose,
            if args.fault_line { "; fault line asserted" } else { "" }
        );
    }
    if crate::stdout::failed() {
        // Nobody can read the port's name: nothing to serve (exit 141 or 1, crate::stdout).
        return Ok(());
    }
    // The operator, from standard input (one a line): a weight on the load
    // cell (`weight normal 4.905`, `weight tangential -2`, `weight off`), the
    // reset button (`reset`), or the belt's lift (`belt up`, `belt down`).
    let load = arm.load();
    let reset = arm.reset_button();
    let belt = arm.belt_lift();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines().map_while(Result::ok) {
            match operator_command(&line) {
                Ok(Operator::Weight(w)) => {
                    *load.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = w;
                    eprintln!("load cell: f_t {} N, f_n {} N hung", w[0], w[1]);
                }
                Ok(Operator::Reset) => {
                    reset.store(true, std::sync::atomic::Ordering::Relaxed);
                    eprintln!("reset: the board restarts from its flash");
                }
                Ok(Operator::Belt(up)) => {
                    belt.store(up, std::sync::atomic::Ordering::Relaxed);
                    eprintln!(
                        "{}",
                        if up {
                            "belt up: the tip on the running belt at the scenario's initial pose, held there while the drivers are off"
                        } else {
                            "belt down: below the hanging tip"
                        }
                    );
                }
                Err(e) => eprintln!("{e}"),
            }
        }
    });
    // Until Ctrl-C or SIGTERM, or --serve-for's time (which sets the same flag,
    // without a signal: the exit code stays 0).
    let stop = crate::cancel::stop_flag();
    if let Some(t) = args.serve_for {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(t));
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        });
    }
    let ts = Duration::from_secs_f64(s.timing.period().as_secs_f64());
    bringup_line::serve(&mut arm, &mut pty.master, ts, &stop).map_err(CliError::Board)?;
    if crate::cancel::exit_code().is_some() {
        // Ctrl-C or SIGTERM (not --serve-for's end): 130 or 143.
        return Err(CliError::interrupted(format!("{what} stopped")));
    }
    Ok(())
}
