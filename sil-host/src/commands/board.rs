//! `sil-host board` (bring-up over the board's serial port) and `sil-host
//! board-twin` (the board twin serving the same protocol on a pseudo-terminal):
//! thin commands over `rig::bringup_procedure` and `rig::bringup_line`.

use std::{io::Write, sync::Arc, time::Duration};

use arm_app::{
    bringup::{CalibrationRecord, EnableOutcome, MAX_JOG_CODES, RawReadings, Reply, Request, Status},
    telemetry::ArmTelemetry,
};
use board_twin::{BusFaults, FlashModel};
use rig::{
    board_backup,
    bringup_line::{self, Client, Pty},
    bringup_procedure::{self as bp, CalibrateOptions, StepError},
    free_arm::{ArmBoard, FreeArm},
    setup::firmware_config,
    status_words::describe_status,
};
use serde::Serialize;

use crate::{
    cli::{AxisArg, BoardArgs, BoardCommand, BoardTwinArgs, FlashArg, JointArg},
    error::CliError,
};
use experiments::scenario::load_scenario;

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

/// One reading of `watch` on one line: the period, the drivers, the joints
/// (degrees once the zeros are set, else raw counts), the load cell's counts,
/// the belt's counter, the fault line and the status word in words.
fn watch_line(s: &Snapshot) -> String {
    let st = &s.status;
    let r = &s.raw;
    let joints: Vec<String> = ["theta1", "elbow"]
        .iter()
        .enumerate()
        .map(|(i, name)| match r.encoder_counts[i] {
            Ok(n) => match joint_degrees(n, &s.calibration, i) {
                Some(d) => format!("{name} {d:+8.3} deg"),
                None => format!("{name} {n:5} counts"),
            },
            Err(e) => format!("{name} no reading ({})", e.describe()),
        })
        .collect();
    let adc = r.adc_counts.map_or_else(|| "ADC none".to_string(), |[t, n]| format!("ADC f_t {t:4} f_n {n:4}"));
    format!(
        "period {} | drivers {} | {} | {adc} | belt {} | fault line {} | {}",
        st.periods,
        if st.drivers_enabled { "on " } else { "off" },
        joints.join(", "),
        r.belt_count,
        if r.driver_fault { "ASSERTED" } else { "clear" },
        describe_status(st.status)
    )
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
        Some([t, n]) => outln!("load cell ADC: f_t {t}, f_n {n} of 4095"),
        None => outln!("load cell ADC: no conversion this period"),
    }
    outln!("belt counter: {}; driver fault line: {}", r.belt_count, if r.driver_fault { "ASSERTED" } else { "clear" });
    let c = &s.calibration;
    outln!(
        "calibration: zeros {:?} reversed {:?}; load cell zeros {:?} N/count {:?}; belt {} m/count",
        c.zero_counts,
        c.reversed,
        c.load_zero_counts,
        c.load_newtons_per_count,
        c.belt_metres_per_count
    );
    match &s.telemetry {
        Some(t) => outln!(
            "last window (period {}): step median {} worst {} ticks, overruns {}, stack high-water {} B",
            t.seq,
            t.step.median,
            t.step.worst,
            t.overruns,
            t.stack_high_water_bytes
        ),
        None => outln!("telemetry: no window closed yet"),
    }
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
    bp::hello(&mut c)?;
    let json = args.json;
    let done = |what: &str| emit(json, &serde_json::json!({ "done": what }), || outln!("{what}: done"));
    match &args.command {
        BoardCommand::Status => {
            let s = snapshot(&mut c)?;
            emit(json, &s, || print_snapshot(&s));
        }
        BoardCommand::Watch { interval_ms, count } => {
            let stop = crate::cancel::stop_flag();
            // On a terminal one line, rewritten in place; into a pipe or a file,
            // one line per reading (JSON: one document per reading).
            let tty = std::io::IsTerminal::is_terminal(&std::io::stdout());
            let mut n = 0;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) && !crate::stdout::failed() && count.is_none_or(|k| n < k) {
                let s = snapshot(&mut c)?;
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
            let report = bp::calibrate(&mut c, &o, &mut Terminal { json })?;
            emit(json, &report, || {
                outln!("calibration in force (not yet saved): {:?}", report.calibration);
                outln!("next: `sil-host board span` with a known weight, `configure`, `save`, `enable`");
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
            let Reply::Calibration(cal) = bp::ask(&mut c, request)? else {
                return Err(CliError::bad_input("unexpected reply to span"));
            };
            emit(json, &cal, || {
                if *skip {
                    outln!("span skipped: the nominal gain {} N per count is kept", cal.load_newtons_per_count[usize::from(axis)]);
                } else {
                    outln!("span set: N per count {:?}", cal.load_newtons_per_count);
                }
            });
        }
        BoardCommand::Configure { scenario } => {
            let s = load_scenario(scenario)?;
            let config = firmware_config(&s);
            // The image's timer runs one rate: say both when they differ.
            if let Ok(Reply::Config(now)) = bp::ask(&mut c, Request::GetConfig)
                && now.period != config.period
            {
                return Err(CliError::Board(format!(
                    "configure: refused: the scenario's control period is {} us ({:.0} Hz) and the image's timer runs {} us ({:.0} Hz); set timing.rate_hz to the image's",
                    config.period.as_us(),
                    1e6 / config.period.as_us() as f64,
                    now.period.as_us(),
                    1e6 / now.period.as_us() as f64
                )));
            }
            bp::ask(&mut c, Request::Configure(config))?;
            done("configure");
        }
        BoardCommand::Enable => {
            let st = bp::enable(&mut c)?;
            emit(json, &serde_json::json!({ "done": "enable", "status": st }), || {
                outln!("enable: done: {}", bp::describe_enable(&st.last_enable));
            });
            if !st.drivers_enabled {
                eprintln!("warning: the drivers are off again since: {}", describe_status(st.status));
            }
        }
        BoardCommand::Backup { file, force } => {
            if file.exists() && !force {
                return Err(CliError::bad_input(format!("backup: {} exists: give --force to overwrite it", file.display())));
            }
            let b = bp::backup(&mut c)?;
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
            let st = bp::restore(&mut c, &b)?;
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
        BoardCommand::Save | BoardCommand::LiftTorqueLimit | BoardCommand::Disable => {
            let (request, name) = match args.command {
                BoardCommand::Save => (Request::Save, "save"),
                BoardCommand::LiftTorqueLimit => (Request::LiftTorqueLimit, "lift the torque limit"),
                _ => (Request::Disable, "disable"),
            };
            bp::ask(&mut c, request)?;
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
    if args.emulated {
        let elf = args.elf.clone().unwrap_or_else(rig::emulator_link::default_image);
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
}

/// A line of the twin's standard input: `weight AXIS NEWTONS`, `weight off` or `reset`.
fn operator_command(line: &str) -> Result<Operator, String> {
    if line.split_whitespace().collect::<Vec<_>>() == ["reset"] {
        return Ok(Operator::Reset);
    }
    weight_command(line).map(Operator::Weight)
}

/// `weight AXIS NEWTONS` or `weight off`: the load `[f_t, f_n]` it hangs, N.
fn weight_command(line: &str) -> Result<[f64; 2], String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let usage = || format!("`{line}`: expected `weight normal|tangential NEWTONS`, `weight off` or `reset`");
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
    // cell (`weight normal 4.905`, `weight tangential -2`, `weight off`), or
    // the reset button (`reset`).
    let load = arm.load();
    let reset = arm.reset_button();
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
