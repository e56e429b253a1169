//! `sil-host board` (bring-up over the board's serial port) and `sil-host
//! board-twin` (the board twin serving the same protocol on a pseudo-terminal):
//! thin commands over `board_link::bringup_procedure` and `board_link::bringup_line`.
//! `snapshot` reads and words what the board reports (`status`, `watch`);
//! `twin` serves the board twin or the emulated image on a pseudo-terminal.

mod snapshot;
mod twin;

pub use twin::twin;

use std::time::Duration;

use arm_app::bringup::{MAX_JOG_CODES, Reply, Request};
use board_link::{
    board_backup,
    bringup_line::Client,
    bringup_procedure::{self as bp, CalibrateOptions, StepError},
};
use rig::{setup::firmware_config, status_words::describe_status};
use serde::Serialize;

use crate::{
    cli::{AxisArg, BoardArgs, BoardCommand, JointArg},
    error::CliError,
};
use experiments::scenario::load_scenario;

use snapshot::{describe_calibration, print_snapshot, snapshot, watch_line};

/// A bring-up step's failure as the command's error: a line that does not
/// answer as the protocol says is bad input (exit 2), a refusal of the board
/// [`CliError::Board`] (exit 1).
fn step(e: StepError) -> CliError {
    match e {
        StepError::Line(m) => CliError::bad_input(m),
        StepError::Refused(m) => CliError::Board(m),
    }
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
/// [`CliError::BadInput`] (exit 2) for bad input, a port that does not open or a
/// board that does not answer; [`CliError::Board`] (exit 1) for a refusal or a
/// failed check.
pub fn run(args: &BoardArgs) -> Result<(), CliError> {
    // The input files first (issue 80): a scenario, an ELF or a backup that is
    // not a regular file within its bound, or an ELF that declares no law, is
    // refused (exit 2) before the port opens.
    let mut scenario_read = None;
    let mut backup_read = None;
    match &args.command {
        BoardCommand::Configure { scenario, elf } => {
            if let Some(elf) = elf {
                rig::law::LawDescription::declared_by(elf).map_err(|e| CliError::bad_input(format!("configure: {e}")))?;
            }
            scenario_read = Some(load_scenario(scenario)?);
        }
        BoardCommand::Restore { file } => backup_read = Some(board_backup::read(file).map_err(|e| CliError::bad_input(e.to_string()))?),
        _ => {}
    }
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
                // In the board's periods at its rate (bp::periods_of).
                jog_s: 0.1,
                settle_s: 0.3,
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
        BoardCommand::Configure { scenario, elf } => {
            let s = match scenario_read {
                Some(s) => s,
                None => load_scenario(scenario)?,
            };
            // The law the board's image runs: the flashed ELF's declaration (the
            // paper's laws without --elf; an ELF without one refused) held to the digest the board reports; the
            // scenario's `[law]` table bound to it, or refused with the
            // declaration in the message, before anything is sent.
            let board_status = bp::status(&mut c).map_err(step)?;
            let law = bp::board_law(&board_status, elf.as_deref()).map_err(|e| CliError::bad_input(format!("configure: {e}")))?;
            let bound = rig::law::bind(s.law.as_ref(), &law).map_err(|e| CliError::bad_input(format!("configure: {e}")))?;
            let config = firmware::Config { law: bound, ..firmware_config(&s) };
            // A board never runs without its runaway limits: refused here, naming
            // the key, before the firmware refuses it too.
            bp::check_protection(&config, "controller.runaway_limits").map_err(CliError::bad_input)?;
            // The rates the image runs (arm_app::rate, the one statement the
            // image shares): refused here, naming the range, before the
            // firmware refuses it too (`Refusal::Rate`).
            let us = config.period.as_us();
            if !arm_app::rate::supported(config.period) {
                return Err(CliError::bad_input(format!(
                    "configure: timing.rate_hz = {} gives a control period of {us} us: the image runs {}",
                    s.timing.rate_hz,
                    arm_app::rate::RANGE_WORDS
                )));
            }
            let Reply::Config(now) = bp::ask(&mut c, Request::GetConfig).map_err(step)? else {
                return Err(CliError::bad_input("unexpected reply to get configuration"));
            };
            bp::ask(&mut c, Request::Configure(config)).map_err(step)?;
            // The board's tick follows the configuration's rate (TIM2's reload):
            // what it runs now, read back.
            let tick_us = u64::from(bp::status(&mut c).map_err(step)?.period_us);
            if tick_us != us {
                return Err(CliError::Board(format!(
                    "configure: the board took the configuration but its tick runs {tick_us} us, not the configuration's {us} us: \
                     the board could not reprogram its timer, and its drivers stay locked out until it does (reset it)"
                )));
            }
            let json_of = |c: &firmware::Config| serde_json::to_value(c).unwrap_or_default();
            let changed = changes("config", &json_of(&now), &json_of(&config));
            let listed: Vec<_> = changed.iter().map(|(k, a, b)| serde_json::json!({ "key": k, "old": a, "new": b })).collect();
            emit(json, &serde_json::json!({ "done": "configure", "changed": listed, "period_us": tick_us }), || {
                if changed.is_empty() {
                    outln!("configure: done: nothing changed (the configuration in force is the scenario's)");
                } else {
                    outln!("configure: done: {} setting(s) changed, not yet saved (`sil-host board save`):", changed.len());
                    for (k, a, b) in &changed {
                        let unit = board_link::setting_units::unit_of(k).map_or(String::new(), |u| format!(" {u}"));
                        outln!("  {k} = {a} -> {b}{unit}");
                    }
                }
                outln!("the board's control tick runs {tick_us} us ({:.0} Hz)", 1e6 / tick_us as f64);
            });
        }
        BoardCommand::Enable => {
            let st = bp::enable(&mut c).map_err(step)?;
            emit(json, &serde_json::json!({ "done": "enable", "status": st }), || {
                outln!(
                    "enable: done: {}; still on at period {} ({} periods watched): {}",
                    bp::describe_enable(&st.last_enable),
                    st.periods,
                    bp::enable_watch_periods(st.period_us),
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
            let b = match backup_read {
                Some(b) => b,
                None => board_backup::read(file).map_err(|e| CliError::bad_input(e.to_string()))?,
            };
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
