//! `sil-host board` end to end against `sil-host board-twin --pty` (issue 23;
//! docs/board.md "Bring-up"): every bring-up step of the procedure over a
//! pseudo-terminal, in the PIL framing, against the `arm` image's application
//! on the simulated board, the arm hanging free; and the refusals: a reversed
//! encoder, a corrupt stored record, an asserted fault line. Every test runs
//! twice: on the board twin (the application compiled for the PC) and on the
//! emulated image (`board-twin --emulated`: the unmodified `arm` ELF, its own
//! USART1, flash and timers; issue 38), with the same commands and results.

use std::{
    io::{BufRead, BufReader},
    process::{Command, Stdio},
};

/// A board twin serving on a pseudo-terminal; killed when dropped.
type Twin = crate::common::BoardTwin;

/// Which board serves: the twin's application, or the emulated `arm` ELF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Board {
    Twin,
    Emulated,
}

/// Two tests of one body: on the twin and on the emulated image.
macro_rules! on_both {
    ($($name:ident),* $(,)?) => {
        mod twin {
            $(#[test] fn $name() { super::$name(super::Board::Twin) })*
        }
        mod emulated {
            $(#[test] fn $name() { super::$name(super::Board::Emulated) })*
        }
    };
}

on_both!(
    the_bring_up_procedure_runs_end_to_end_from_a_new_board_to_an_enabled_one,
    a_never_calibrated_board_cannot_be_saved_into_an_enabled_one,
    enable_says_why_the_drivers_stayed_off_and_status_words_are_in_words,
    a_reversed_encoder_stops_the_calibration_naming_the_joint_until_it_is_declared,
    a_corrupt_record_locks_the_drivers_out_and_a_sound_one_is_loaded,
    an_asserted_fault_line_stops_the_calibration_and_shows_in_the_raw_readings,
    a_record_saved_over_the_line_is_reloaded_after_the_reset_button,
    a_client_killed_mid_command_leaves_a_board_the_next_client_can_use,
    every_friction_term_is_accepted_by_configure,
    a_backup_restores_to_the_same_settings_and_a_bad_file_leaves_the_board_unchanged,
    the_runaway_limits_cannot_be_turned_off_on_a_board,
    a_save_after_a_reset_that_discarded_a_configure_says_nothing_was_saved,
    configure_sets_the_control_rate_and_a_saved_one_comes_back_after_the_reset,
);

/// Issue 56: `configure` sends the scenario's control rate and the board's tick
/// follows it (TIM2's reload on the emulated image), which `configure` reads
/// back and `status` reports; a rate the image does not run is refused naming
/// the range, nothing sent; a saved rate comes back at the reset, a backup
/// carries it, and a backup with a period outside the range is refused naming
/// the key and the range, the board unchanged.
fn configure_sets_the_control_rate_and_a_saved_one_comes_back_after_the_reset(on: Board) {
    use std::io::Write;
    let mut t = twin(on, &["--flash", "saved"]);
    assert_eq!(status(&t)["status"]["period_us"], 1000);
    for rate in ["200", "12000"] {
        let (code, _, err) = board(&t, &["configure", "--set", &format!("timing.rate_hz={rate}")]);
        assert!(code == 2 && err.contains("timing.rate_hz") && err.contains("250 to 10000 Hz"), "{rate} Hz: {err}");
        assert_eq!(status(&t)["status"]["period_us"], 1000, "{rate} Hz: nothing sent");
    }
    // 10 kHz needs a sampling delay within its 100 us period.
    for (rate, us, delta) in [("250", 4000, "0.0002"), ("4000", 250, "0.0002"), ("10000", 100, "0.00005"), ("1000", 1000, "0.0002")] {
        let (code, out, err) =
            board(&t, &["configure", "--set", &format!("timing.rate_hz={rate}"), "--set", &format!("timing.delta_s={delta}")]);
        assert_eq!(code, 0, "{rate} Hz: {out}{err}");
        assert!(out.contains(&format!("the board's control tick runs {us} us")), "{rate} Hz: {out}");
        let s = status(&t);
        assert_eq!(s["status"]["period_us"], us, "{rate} Hz: {s}");
    }
    let (code, out, err) = board(&t, &["configure", "--set", "timing.rate_hz=4000"]);
    assert!(code == 0 && out.contains("config.period = 1000 -> 250 us"), "{out}{err}");
    assert_eq!(board(&t, &["save"]).0, 0);
    let periods = status(&t)["status"]["periods"].as_u64().unwrap();
    writeln!(t.stdin, "reset").unwrap();
    t.stdin.flush().unwrap();
    let mut after = status_while_booting(&t);
    for _ in 0..400 {
        if after["status"]["periods"].as_u64().unwrap() < periods {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
        after = status_while_booting(&t);
    }
    assert!(after["status"]["periods"].as_u64().unwrap() < periods, "no reset: {after}");
    assert_eq!((after["status"]["period_us"].as_u64(), after["status"]["settings"].as_str()), (Some(250), Some("Saved")), "{after}");
    let (code, out, _) = board(&t, &["status"]);
    assert!(code == 0 && out.contains("control tick: 250 us (4000 Hz)"), "{out}");
    // The backup carries the rate; one with a period the image does not run is refused.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("b.toml");
    assert_eq!(board(&t, &["backup", file.to_str().unwrap()]).0, 0);
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("period = 250"), "{text}");
    for bad in ["5000", "99", "0"] {
        std::fs::write(&file, text.replace("period = 250", &format!("period = {bad}"))).unwrap();
        let (code, _, err) = board(&t, &["restore", file.to_str().unwrap()]);
        assert!(code == 2 && err.contains(&format!("`config.period` = {bad}")) && err.contains("100 to 4000 us"), "{bad}: {err}");
    }
    assert_eq!(status(&t)["status"]["period_us"], 250, "the board unchanged");
}

/// Issue 44: `backup FILE` writes the calibration and configuration in force as
/// TOML; `restore FILE` puts them back whole (the firmware checks them as it
/// checks its flash record), so that backup, change, restore, backup gives the
/// first file again. A file that is not a backup (not TOML, a key unknown or
/// missing, another protocol) or holds a value out of range by the firmware's
/// own rules is refused before it is sent (exit 2, naming the key); the board is
/// unchanged.
fn a_backup_restores_to_the_same_settings_and_a_bad_file_leaves_the_board_unchanged(on: Board) {
    let t = twin(on, &["--flash", "saved"]);
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let read = |name: &str| std::fs::read_to_string(path(name)).unwrap();
    let (code, out, err) = board(&t, &["backup", &path("a.toml")]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("backup: done"), "{out}");
    let a: toml::Table = read("a.toml").parse().unwrap();
    assert_eq!(a["format"].as_integer(), Some(1), "{a}");
    // Each setting's unit at the end of its line (issue 69).
    let text = read("a.toml");
    for line in ["f_n_ref = 10.0  # N", "period = 1000  # us", "belt_metres_per_count = ", "kp = [200.0, 0.0]  # N m/rad"] {
        assert!(text.lines().any(|l| l.starts_with(line) && l.contains("  # ")), "{line:?} with its unit in:\n{text}");
    }
    assert_eq!(a["calibration"]["zeros_set"].as_bool(), Some(true), "{a}");
    // The file is the board's own record: what `status` shows.
    let s = status(&t);
    assert_eq!(s["status"]["settings"], "Saved", "{s}");
    let zeros: Vec<i64> = a["calibration"]["zero_counts"].as_array().unwrap().iter().map(|v| v.as_integer().unwrap()).collect();
    assert_eq!(serde_json::json!(zeros), s["calibration"]["zero_counts"], "{s}");
    // No overwrite without --force.
    let (code, _, err) = board(&t, &["backup", &path("a.toml")]);
    assert!(code == 2 && err.contains("--force"), "{err}");

    // Change both: a configuration over the line, a calibration from an edited file.
    assert_eq!(board(&t, &["configure", "--set", "controller.friction=none"]).0, 0);
    let mut b = a.clone();
    b["calibration"]["belt_metres_per_count"] = toml::Value::Float(1.9073486328125e-6); // 2^-19: an f32 exactly
    b["calibration"]["zero_counts"] = toml::Value::Array(vec![toml::Value::Integer(1234), toml::Value::Integer(4321)]);
    std::fs::write(path("b.toml"), toml::to_string(&b).unwrap()).unwrap();
    let (code, out, err) = board(&t, &["--json", "restore", &path("b.toml")]);
    assert_eq!(code, 0, "{out}{err}");
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["status"]["settings"], "Unsaved", "a change is unsaved: {r}");
    assert_eq!(r["status"]["torque_limit_codes"], 410, "a new calibration runs at the reduced limit: {r}");
    assert_eq!(board(&t, &["backup", "--force", &path("b2.toml")]).0, 0);
    // The edited file is what the board holds, to the f32 (the board writes each
    // float's shortest form: 1.9073486e-6 for the edit's 2^-19).
    let parse = |text: &str| board_link::board_backup::parse(text).unwrap();
    assert_eq!(parse(&read("b2.toml")), parse(&toml::to_string(&b).unwrap()), "the edited file is what the board holds");

    // Restore the first: the board holds it again, bit for bit.
    let (code, out, err) = board(&t, &["restore", &path("a.toml")]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("restore: done") && out.contains("sil-host board save"), "{out}");
    assert_eq!(board(&t, &["backup", &path("a2.toml")]).0, 0);
    assert_eq!(read("a2.toml"), read("a.toml"), "backup, change, restore, backup: the first file");
    assert_eq!(board(&t, &["save"]).0, 0);
    assert_eq!(status(&t)["status"]["settings"], "Saved");

    // Bad files: refused, the board unchanged (its backup and its settings).
    let before = status(&t);
    let edit = |f: &dyn Fn(&mut toml::Table)| {
        let mut x = a.clone();
        f(&mut x);
        toml::to_string(&x).unwrap()
    };
    let cases: Vec<(&str, String, i32, &str)> = vec![
        ("not TOML", "calibration = [\n".into(), 2, "not a TOML backup"),
        ("truncated", read("a.toml").lines().take(6).collect::<Vec<_>>().join("\n"), 2, "missing"),
        ("another format", edit(&|x| x["format"] = toml::Value::Integer(9)), 2, "backup format 9"),
        (
            "an unknown key",
            edit(&|x| {
                x["config"].as_table_mut().unwrap().insert("torque_limt".into(), 1.0.into());
            }),
            2,
            "config.torque_limt",
        ),
        ("a wrong type", edit(&|x| x["calibration"]["reversed"] = toml::Value::String("no".into())), 2, "calibration.reversed"),
        ("a torque limit of 50 N m", edit(&|x| x["config"]["torque_limit"] = toml::Value::Float(50.0)), 2, "`config.torque_limit` = 50"),
        (
            "a 15-bit encoder zero",
            edit(&|x| x["calibration"]["zero_counts"][1] = toml::Value::Integer(20000)),
            2,
            "zero_counts[1]` = 20000",
        ),
        ("a zero load-cell gain", edit(&|x| x["calibration"]["load_newtons_per_count"][0] = toml::Value::Float(0.0)), 2, "gain"),
        ("a zero belt scale", edit(&|x| x["calibration"]["belt_metres_per_count"] = toml::Value::Float(0.0)), 2, "belt_metres_per_count"),
        // Issue 52: what the scenario path refuses, a restore took.
        ("f_n* of 100 N", edit(&|x| x["config"]["f_n_ref"] = toml::Value::Float(100.0)), 2, "`config.f_n_ref` = 100"),
        (
            "a load-cell gain of 1e-45",
            edit(&|x| x["calibration"]["load_newtons_per_count"][1] = toml::Value::Float(1e-45)),
            2,
            "`calibration.load_newtons_per_count[1]` = 1e-45",
        ),
        (
            "a negative load-cell gain",
            edit(&|x| x["calibration"]["load_newtons_per_count"][0] = toml::Value::Float(-0.012)),
            2,
            "`calibration.load_newtons_per_count[0]` = -1.2e-2",
        ),
        (
            "the runaway limits off",
            edit(&|x| x["config"]["runaway_limits"] = toml::Value::Boolean(false)),
            2,
            "cannot be turned off on a board",
        ),
        (
            "another protocol",
            edit(&|x| x["protocol"] = toml::Value::Integer(5)),
            2,
            "made with bring-up protocol 5, this sil-host speaks protocol 9",
        ),
    ];
    for (what, text, want, says) in cases {
        std::fs::write(path("bad.toml"), &text).unwrap();
        let (code, out, err) = board(&t, &["restore", &path("bad.toml")]);
        assert_eq!(code, want, "{what}: {out}{err}");
        assert!(err.contains(says), "{what}: the error names it: {err}");
        assert_eq!(board(&t, &["backup", "--force", &path("after.toml")]).0, 0);
        assert_eq!(read("after.toml"), read("a.toml"), "{what}: the board is unchanged");
        let after = status(&t);
        assert_eq!(after["status"]["settings"], before["status"]["settings"], "{what}: {after}");
        assert_eq!(after["status"]["torque_limit_codes"], before["status"]["torque_limit_codes"], "{what}: {after}");
    }
}

/// Issue 52 (1): the runaway limits cannot be turned off on a board. `configure`
/// and `restore` refuse them off before sending (exit 2, naming the key and
/// why); the firmware refuses the same requests sent over the line as they are
/// (`Refusal::ProtectionOff`), its settings unchanged; and a flash record
/// holding them off is refused at reset, the drivers locked out saying why.
fn the_runaway_limits_cannot_be_turned_off_on_a_board(on: Board) {
    use arm_app::bringup::{Refusal, Reply, Request};
    let t = twin(on, &["--flash", "saved"]);
    let (code, _, err) = board(&t, &["configure", "--set", "controller.runaway_limits=false"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("controller.runaway_limits = false") && err.contains("cannot be turned off on a board"), "{err}");
    assert!(err.contains("--in-process"), "where such a study runs: {err}");
    let Reply::Config(config) = ask_raw(&t, Request::GetConfig) else { panic!() };
    let Reply::Calibration(calibration) = ask_raw(&t, Request::GetCalibration) else { panic!() };
    assert!(config.runaway_limits);
    let off = firmware::Config { runaway_limits: false, ..config };
    assert_eq!(ask_raw(&t, Request::Configure(off)), Reply::Refused(Refusal::ProtectionOff));
    let stored = arm_app::record::Stored { calibration, config: off };
    assert_eq!(ask_raw(&t, Request::Restore(stored)), Reply::Refused(Refusal::ProtectionOff));
    let s = status(&t);
    assert_eq!(s["status"]["settings"], "Saved", "{s}");
    assert_eq!(ask_raw(&t, Request::GetConfig), Reply::Config(config), "the configuration in force unchanged");
    drop(t);
    // A record that holds them off (saved by another image, or written by hand).
    let t = twin(on, &["--flash", "saved", "--set", "controller.runaway_limits=false"]);
    let s = status(&t);
    assert_eq!(s["status"]["settings"]["Corrupt"], "ProtectionOff", "{s}");
    let (code, _, err) = board(&t, &["enable"]);
    assert!(code == 1 && err.contains("turns the runaway limits off"), "{err}");
}

/// Issue 52 (3): `save` said "done" after the reset button had discarded the
/// `configure` before it (a reset reloads the flash record); it now says that
/// nothing was saved, and why (exit 1).
fn a_save_after_a_reset_that_discarded_a_configure_says_nothing_was_saved(on: Board) {
    use std::io::Write;
    let mut t = twin(on, &["--flash", "saved"]);
    let (code, out, err) = board(&t, &["configure", "--set", "controller.f_n_ref=7"]);
    assert!(code == 0 && out.contains("config.f_n_ref = 10.0 -> 7.0 N"), "{out}{err}");
    let periods = status(&t)["status"]["periods"].as_u64().unwrap();
    writeln!(t.stdin, "reset").unwrap();
    t.stdin.flush().unwrap();
    let mut after = status_while_booting(&t);
    for _ in 0..400 {
        if after["status"]["periods"].as_u64().unwrap() < periods {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
        after = status_while_booting(&t);
    }
    assert_eq!(after["status"]["settings"], "Saved", "{after}");
    let (code, out, err) = board(&t, &["save"]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(err.contains("nothing to save") && err.contains("reset"), "{err}");
    // Sent again, it is saved.
    assert_eq!(board(&t, &["configure", "--set", "controller.f_n_ref=7"]).0, 0);
    let (code, out, err) = board(&t, &["save"]);
    assert!(code == 0 && out.contains("save: done"), "{out}{err}");
}

/// Issue 52 (1): `run` on a board (`--link twin`, `--link emulator`) with the
/// runaway limits off is refused before it starts (exit 2, naming the key);
/// without a board it runs: each way the refusal names (issue 66: it named a
/// `--link ipc` that does not exist) runs the same scenario.
#[test]
fn a_run_on_a_board_refuses_the_runaway_limits_off_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let off = ["--duration", "0.01", "--set", "controller.runaway_limits=false", "--out"];
    for link in ["twin", "emulator"] {
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .args(["run", "--link", link])
            .args(off)
            .arg(dir.path().join(link))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{link}: {err}");
        assert!(err.contains("controller.runaway_limits = false") && err.contains("cannot be turned off on a board"), "{link}: {err}");
        assert!(
            err.contains("`sil-host run --in-process`") && err.contains("`sil-host run` (the firmware process over iceoryx2)"),
            "{err}"
        );
        assert!(!err.contains("--link ipc"), "{err}");
    }
    for (name, way) in [("in-process", &["--in-process"][..]), ("iceoryx2", &[][..])] {
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).arg("run").args(way).args(off).arg(dir.path().join(name)).output().unwrap();
        assert!(o.status.success(), "{name}: the named way runs: {}", String::from_utf8_lossy(&o.stderr));
    }
}

/// Issue 80: a healthy start on the twin logs no safe state. Before the enable
/// button the drivers are off, the motors do nothing, and the wiring check
/// tripped on it (`Miswired`, "a joint accelerated against its motor's
/// torque") at every start: a board logs a motor check's stop only once its
/// drivers were on (`SafeReason::needs_the_motors`).
#[test]
fn a_healthy_start_on_the_twin_logs_no_safe_state() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["run", "--link", "twin", "--duration", "0.05", "--no-page", "--out"])
        .arg(dir.path().join("run"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{err}");
    let log = format!("{out}{err}");
    assert!(log.contains("enable button: firmware reset") && log.contains("drivers enabled"), "{log}");
    assert!(!log.contains("safe state"), "{log}");
}

/// Issue 66: the encoders' acquisition faults from a scenario read on standard
/// input (`run --link twin|emulator --scenario -`): each is named in the log of
/// the period it starts (the twin's; the emulated image's lines stay in its
/// RTT buffer), three faulted periods latch `Acquisition` in the third on both
/// boards (exit 1, the trace and `summary.json` written up to there); a link
/// without a board refuses them by name before it starts (exit 2).
#[test]
fn acquisition_faults_from_a_scenario_on_stdin_end_in_their_safe_state_on_both_boards() {
    let dir = tempfile::tempdir().unwrap();
    let default = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/default.toml")).unwrap();
    let runs = |link: &[&str], fault: &str, tag: &str| {
        use std::io::Write as _;
        let mut child = Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .arg("run")
            .args(link)
            .args(["--scenario", "-", "--duration", "0.3", "--out"])
            .arg(dir.path().join(tag))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let text = format!("{default}\n[[faults]]\n{fault}\nat_s = 0.2\nduration_s = 0.01\n");
        child.stdin.take().unwrap().write_all(text.as_bytes()).unwrap();
        let o = child.wait_with_output().unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    for (fault, named) in [
        ("kind = \"dma_transfer_error\"", "DMA transfer error (TEIF)"),
        ("kind = \"dma_fifo_error\"", "DMA FIFO error (FEIF)"),
        ("kind = \"dma_direct_mode_error\"", "DMA direct-mode error (DMEIF)"),
        ("kind = \"dma_late_transfer\"", "the encoders' frames did not complete in time"),
        ("kind = \"stuck_chip_select\"\nsignal = \"theta1\"", "an encoder's chip select is stuck low"),
        ("kind = \"stuck_chip_select\"\nsignal = \"elbow\"", "an encoder's chip select is stuck low"),
    ] {
        for link in ["twin", "emulator"] {
            let tag = format!("{link}-{}", fault.len());
            let (code, err) = runs(&["--link", link], fault, &tag);
            assert_eq!(code, Some(1), "{link} {fault}: {err}");
            assert!(err.contains("the firmware entered its safe state at period 202 (t = 0.202 s): Acquisition"), "{link} {fault}: {err}");
            if link == "twin" {
                assert!(err.contains(&format!("twin: period 200: the encoders' acquisition failed: {named}")), "{fault}: {err}");
            }
            let out = dir.path().join(&tag);
            let sm: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
            assert_eq!((sm["status"].as_str(), sm["periods"].as_u64()), (Some("failed"), Some(203)), "{link} {fault}");
            let rows = std::fs::read_to_string(out.join("trace.csv")).unwrap().lines().count();
            assert_eq!(rows, 1 + 203, "{link} {fault}: every period up to the safe state written");
        }
        let (code, err) = runs(&["--in-process"], fault, "refused");
        assert_eq!(code, Some(2), "{fault}: {err}");
        assert!(err.contains("acts on the board's bus and devices") && err.contains("--link emulator"), "{fault}: {err}");
    }
}

/// Issue 41: `configure` sends every friction term of the hybrid law, the robust
/// `estimated` among them, and the board's firmware (on the emulated image, the
/// flashed bytes) decodes and accepts each; a term that is not one is refused by
/// the scenario's check, naming the choices.
fn every_friction_term_is_accepted_by_configure(on: Board) {
    let t = twin(on, &[]);
    for friction in ["commanded", "measured_normal", "measured", "none", "estimated"] {
        let set = format!("controller.friction={friction}");
        let (code, _, err) = board(&t, &["configure", "--set", &set]);
        assert_eq!(code, 0, "{friction}: {err}");
    }
    let (code, _, err) = board(&t, &["configure", "--set", "controller.friction=guessed"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("estimated"), "{err}");
}

fn twin(on: Board, extra: &[&str]) -> Twin {
    let emulated: &[&str] = if on == Board::Emulated { &["--emulated"] } else { &[] };
    Twin::spawn(&[emulated, extra].concat())
}

/// Runs `sil-host board --port PORT ARGS`: exit code, stdout, stderr.
fn board(t: &Twin, args: &[&str]) -> (i32, String, String) {
    t.board(args)
}

/// Hangs a weight on the load cell (`normal 4.905`) or takes it off (`off`),
/// and waits until the board's ADC reads the change (the twin takes it at its
/// next tick; an emulated image slower than real time takes longer).
fn hang(t: &mut Twin, what: &str) {
    use std::io::Write;
    let f_n = |t: &Twin| status(t)["raw"]["adc_counts"][1].as_i64().unwrap_or(0);
    let before = f_n(t);
    writeln!(t.stdin, "weight {what}").unwrap();
    t.stdin.flush().unwrap();
    for _ in 0..200 {
        if (f_n(t) - before).abs() > 100 {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
    }
    panic!("the board never read the weight ({what})");
}

/// Raises the belt to the tip (`up`: the arm stood at the scenario's initial
/// pose, `x0d`, its tip on the belt) or lowers it (`down`), and waits until the
/// board's theta1 encoder reads the arm's new pose (more than 100 counts away).
fn belt(t: &mut Twin, what: &str) {
    use std::io::Write;
    let theta1 = |t: &Twin| status(t)["raw"]["encoder_counts"][0]["Ok"].as_i64().unwrap_or(-1);
    let before = theta1(t);
    writeln!(t.stdin, "belt {what}").unwrap();
    t.stdin.flush().unwrap();
    if what == "down" {
        // The arm stays where it is: only the belt moves.
        std::thread::sleep(std::time::Duration::from_millis(100));
        return;
    }
    for _ in 0..200 {
        let d = (theta1(t) - before).rem_euclid(16384);
        if d.min(16384 - d) > 100 {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
    }
    panic!("the board never read the arm on the raised belt");
}

/// Sends `request` over the board's line as a client would, without
/// `sil-host`'s own checks: what the firmware itself answers.
fn ask_raw(t: &Twin, request: arm_app::bringup::Request) -> arm_app::bringup::Reply {
    let line = std::fs::OpenOptions::new().read(true).write(true).open(&t.port).unwrap();
    let fd = std::os::fd::AsRawFd::as_raw_fd(&line);
    // SAFETY: our own descriptor.
    unsafe { libc::fcntl(fd, libc::F_SETFL, libc::fcntl(fd, libc::F_GETFL) | libc::O_NONBLOCK) };
    let mut c = board_link::bringup_line::Client::new(line);
    let wait = std::time::Duration::from_secs(10);
    c.request_until(&arm_app::bringup::Request::Hello, wait, |r| matches!(r, arm_app::bringup::Reply::Hello { .. })).unwrap();
    c.request(&request, wait).unwrap()
}

fn status(t: &Twin) -> serde_json::Value {
    let (code, out, err) = board(t, &["--json", "status"]);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// [`status`] of a board that may be rebooting (after the reset button): a
/// `hello` left unanswered while it boots is asked again, up to 10 times.
fn status_while_booting(t: &Twin) -> serde_json::Value {
    for _ in 0..10 {
        let (code, out, err) = board(t, &["--json", "status"]);
        if code == 0 {
            return serde_json::from_str(&out).unwrap();
        }
        assert!(err.contains("no reply to Hello"), "{err}");
    }
    panic!("the board never answered after its reset");
}

fn the_bring_up_procedure_runs_end_to_end_from_a_new_board_to_an_enabled_one(on: Board) {
    // The theta1 encoder's magnet glued anywhere: the zeros come from the jig.
    let mut t = twin(on, &["--set", "board.theta1_encoder.zero_count=5000.4"]);
    // A new board: nothing in flash, the drivers locked out, and said why.
    let s = status(&t);
    assert_eq!(s["status"]["settings"], "Missing", "{s}");
    assert_eq!(s["raw"]["encoder_counts"][0]["Ok"].as_u64().map(|c| c < 16384), Some(true), "raw counts are read: {s}");
    let (code, _, err) = board(&t, &["enable"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no settings in flash"), "{err}");

    // Calibration: zeros at the jig's pose, four jogs the right way, the tare.
    let pose = format!("--pose-deg={}", t.pose);
    let (code, out, err) = board(&t, &["calibrate", &pose]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(out.matches("moved its torque's way").count(), 4, "{out}");
    assert!(out.contains("load cell tared"), "{out}");
    // It ends in words, not a Rust dump.
    assert!(out.contains("calibrate: done") && out.contains("directions checked by the jogs"), "{out}");
    assert!(!out.contains("CalibrationRecord") && !out.contains('{'), "{out}");
    // The zeros found are the board's mounting (theta1's magnet at 5000.4 counts,
    // the elbow's at 0), to the encoder's quantisation.
    let s = status(&t);
    let zeros = &s["calibration"]["zero_counts"];
    assert!((zeros[0].as_f64().unwrap() - 5000.4).abs() <= 1.0, "{s}");
    assert!(zeros[1].as_i64().unwrap().min(16384 - zeros[1].as_i64().unwrap()) <= 1, "{s}");
    assert_eq!(s["status"]["directions_checked"], true, "{s}");
    assert_eq!(s["status"]["torque_limit_codes"], 410, "a new calibration runs at the reduced limit: {s}");
    assert_eq!(s["status"]["settings"], "Unsaved", "{s}");

    // Configuration, echoed (key = old -> new); a save refused until both spans
    // are measured or skipped.
    let (code, out, err) = board(&t, &["configure", "--set", "controller.f_n_ref=8"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("config.f_n_ref = 10.0 -> 8.0"), "{out}");
    let (code, out, _) = board(&t, &["configure", "--set", "controller.f_n_ref=8"]);
    assert!(code == 0 && out.contains("nothing changed"), "{out}");
    let (code, _, err) = board(&t, &["enable"]);
    assert!(code == 1 && err.contains("save"), "unsaved settings keep the drivers locked out: {err}");
    let (code, _, err) = board(&t, &["save"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("tangential span") && err.contains("normal span") && !err.contains("tare"), "{err}");
    let (code, out, err) = board(&t, &["span", "--axis", "tangential", "--skip"]);
    assert!(code == 0 && out.contains("span skipped"), "{out}{err}");
    // The normal axis's span with a 0.5 kg weight hung on the load cell.
    hang(&mut t, "normal 4.905");
    let (code, out, err) = board(&t, &["--json", "span", "--axis", "normal", "--newtons", "4.905"]);
    assert_eq!(code, 0, "{out}{err}");
    let gain = serde_json::from_str::<serde_json::Value>(&out).unwrap()["load_newtons_per_count"][1].as_f64().unwrap();
    // The twin's front end: 2048 counts per 25 N (the wire's scale), to a count of 60.
    assert!((gain / (25.0 / 2048.0) - 1.0).abs() < 0.03, "gain {gain} N/count");
    // Spanned, the load cell reads in newtons: the weight's 4.905 N.
    let (_, out, _) = board(&t, &["status"]);
    let line = out.lines().find(|l| l.starts_with("load cell:")).unwrap_or_default();
    let f_n: f64 = line.split("f_n ").nth(1).and_then(|r| r.split(' ').next()).and_then(|n| n.parse().ok()).unwrap_or(f64::NAN);
    assert!((f_n - 4.905).abs() < 0.1, "{line}");
    hang(&mut t, "off");
    assert_eq!(status(&t)["status"]["missing"], 0);
    let (code, out, err) = board(&t, &["save"]);
    assert!(code == 0 && out.contains("save: done") && out.contains("hybrid configuration"), "{out}{err}");
    assert_eq!(status(&t)["status"]["settings"], "Saved");
    assert_eq!(board(&t, &["lift-torque-limit"]).0, 0);
    assert_eq!(status(&t)["status"]["torque_limit_codes"], 2048);
    // The arm hangs free (the belt lowered): the closed loop's consistency check
    // stops it within periods, and `enable`, watching the drivers, says so.
    let (code, out, err) = board(&t, &["enable"]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(err.contains("came on at period") && err.contains("went off again"), "{err}");
    assert!(err.contains("safe state: the encoders and the load cell disagree"), "{err}");
    let (_, out, _) = board(&t, &["status"]);
    assert!(out.contains("off again"), "{out}");
    // Step 7: the belt raised to the tip; the closed loop runs.
    belt(&mut t, "up");
    let (code, out, err) = board(&t, &["enable"]);
    assert!(code == 0 && out.contains("enable: done: drivers enabled at period") && out.contains("50 periods watched"), "{out}{err}");
    // After calibration the joints read in degrees too.
    let (_, out, _) = board(&t, &["status"]);
    assert!(out.contains(" deg), AGC") && out.contains("drivers enabled"), "{out}");
    if on == Board::Twin {
        assert!(out.contains("step time not measured") && out.contains("stack not measured") && !out.contains(" 0 ticks"), "{out}");
    }
    // Step 8: watch the closed loop: one line per reading (into a pipe; a
    // terminal's line is rewritten in place), within 80 columns (issue 69), the
    // joints in degrees and the load cell in newtons.
    let (code, out, err) = board(&t, &["watch", "--count", "3", "--interval-ms", "10"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.lines().count(), 3, "{out}");
    for l in out.lines() {
        assert!(l.starts_with('#') && l.contains("drv on") && l.contains("°") && l.contains(" N  belt"), "{l}");
        assert!(!l.contains("nFAULT") && !l.contains("...") && l.chars().count() <= 80, "{} columns: {l}", l.chars().count());
    }
    assert_eq!(board(&t, &["disable"]).0, 0);
    belt(&mut t, "down");
    // Watch: one JSON document per reading.
    let (code, out, err) = board(&t, &["--json", "watch", "--count", "2", "--interval-ms", "10"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.lines().filter(|l| l.starts_with('{')).count(), 2, "{out}");
    // The span refuses a force it cannot see (nothing on the load cell).
    let (code, _, err) = board(&t, &["span", "--axis", "normal", "--newtons", "5"]);
    assert!(code == 1 && err.contains("is the weight on the load cell"), "{err}");
}

fn a_never_calibrated_board_cannot_be_saved_into_an_enabled_one(on: Board) {
    // The audit's reproducer (issue 39, 1): `save` on a fresh board lifted the
    // lockout and `enable` then drove an arm whose zeros were never set.
    let t = twin(on, &[]);
    let (code, _, err) = board(&t, &["save"]);
    assert_eq!(code, 1, "{err}");
    for step in ["encoders' zeros", "direction checks", "tare", "tangential span", "normal span"] {
        assert!(err.contains(step), "save names {step:?}: {err}");
    }
    let (code, _, err) = board(&t, &["enable"]);
    assert!(code == 1 && err.contains("no settings in flash"), "{err}");
    // A tare alone sets no zeros, and a span needs the tare first.
    let (code, _, err) = board(&t, &["span", "--axis", "normal", "--newtons", "5"]);
    assert!(code == 1 && err.contains("tare"), "{err}");
    let s = status(&t);
    assert_eq!(s["status"]["zeros_set"], false, "{s}");
    assert_eq!(s["status"]["settings"], "Missing", "{s}");
    let (code, _, err) = board(&t, &["lift-torque-limit"]);
    assert_eq!(code, 1, "{err}");
}

fn enable_says_why_the_drivers_stayed_off_and_status_words_are_in_words(on: Board) {
    // The audit's reproducer (issue 39, 2): a brought-up board whose drivers
    // assert their fault line; `enable` said "done".
    let t = twin(on, &["--flash", "saved", "--fault-line"]);
    let (code, out, err) = board(&t, &["enable"]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(err.contains("the drivers are off") && err.contains("fault line (nFAULT) is asserted"), "{err}");
    let s = status(&t);
    assert_eq!(s["status"]["drivers_enabled"], false, "{s}");
    assert!(s["status"]["last_enable"]["DriversRefused"].is_object(), "{s}");
    // The human status decodes the word.
    let (code, out, _) = board(&t, &["status"]);
    assert_eq!(code, 0);
    let line = out.lines().find(|l| l.starts_with("firmware status")).unwrap_or_default();
    assert!(line.contains(": ") && !line.ends_with(": "), "{out}");
    assert!(out.contains("last enable: the drivers refused to enable"), "{out}");
}

fn a_reversed_encoder_stops_the_calibration_naming_the_joint_until_it_is_declared(on: Board) {
    let t = twin(on, &["--set", "board.elbow_encoder.reversed=true"]);
    let pose = format!("--pose-deg={}", t.pose);
    let (code, out, err) = board(&t, &["calibrate", &pose]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(err.contains("jog of elbow") && err.contains("AGAINST its torque"), "{err}");
    assert_eq!(status(&t)["status"]["directions_checked"], false);
    // Declared reversed, the same encoder passes (the zeros are set again at the pose).
    let (code, out, err) = board(&t, &["calibrate", &pose, "--reversed", "elbow"]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(out.matches("moved its torque's way").count(), 4, "{out}");
}

fn a_corrupt_record_locks_the_drivers_out_and_a_sound_one_is_loaded(on: Board) {
    let t = twin(on, &["--flash", "corrupt"]);
    let s = status(&t);
    assert_eq!(s["status"]["settings"]["Corrupt"], "Crc", "{s}");
    let (code, _, err) = board(&t, &["enable"]);
    assert!(code == 1 && err.contains("damaged (CRC-32C"), "{err}");
    drop(t);
    let mut t = twin(on, &["--flash", "saved"]);
    let s = status(&t);
    assert_eq!(s["status"]["settings"], "Saved", "{s}");
    belt(&mut t, "up");
    let (code, out, err) = board(&t, &["enable"]);
    assert_eq!(code, 0, "{out}{err}");
}

fn a_record_saved_over_the_line_is_reloaded_after_the_reset_button(on: Board) {
    // Issue 38, "a reset that reloads the saved record from the emulated
    // flash", over the pseudo-terminal: a new board calibrated and saved, the
    // reset button pressed (`reset` on the twin's standard input), and the
    // record is what the board comes back with.
    use std::io::Write;
    let mut t = twin(on, &[]);
    let pose = format!("--pose-deg={}", t.pose);
    assert_eq!(board(&t, &["calibrate", &pose]).0, 0);
    assert_eq!(board(&t, &["configure"]).0, 0);
    for axis in ["tangential", "normal"] {
        assert_eq!(board(&t, &["span", "--axis", axis, "--skip"]).0, 0);
    }
    assert_eq!(board(&t, &["save"]).0, 0);
    let before = status(&t);
    let zeros = before["calibration"]["zero_counts"].clone();
    let periods = before["status"]["periods"].as_u64().unwrap();
    writeln!(t.stdin, "reset").unwrap();
    t.stdin.flush().unwrap();
    // The board's period count starts again at the reset (a hello sent while it
    // boots may go unanswered under load: asked again).
    let mut after = status_while_booting(&t);
    for _ in 0..400 {
        if after["status"]["periods"].as_u64().unwrap() < periods {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
        after = status_while_booting(&t);
    }
    assert!(after["status"]["periods"].as_u64().unwrap() < periods, "no reset: {after}");
    assert_eq!(after["status"]["settings"], "Saved", "{after}");
    assert_eq!(after["status"]["zeros_set"], true, "{after}");
    assert_eq!(after["status"]["directions_checked"], true, "{after}");
    assert_eq!(after["calibration"]["zero_counts"], zeros, "{after}");
    assert_eq!(after["status"]["drivers_enabled"], false, "a reset comes back with the drivers off: {after}");
    // The reloaded record lets the drivers on (the belt raised to the tip, so
    // that the closed loop runs).
    belt(&mut t, "up");
    let (code, out, err) = board(&t, &["enable"]);
    assert!(code == 0 && out.contains("drivers enabled at period"), "{out}{err}");
}

fn a_client_killed_mid_command_leaves_a_board_the_next_client_can_use(on: Board) {
    // Issue 39: a client killed in the middle of a command (here `calibrate`,
    // between its jogs, half a request possibly on the line) must not take the
    // board or the twin down: the next client is answered, the jog under way
    // ends, and the calibration runs again from the start.
    let mut t = twin(on, &[]);
    let pose = format!("--pose-deg={}", t.pose);
    let mut client = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["board", "--port", &t.port, "calibrate", &pose])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Event-driven: killed once the zeros are set, during the first jog.
    let mut line = String::new();
    BufReader::new(client.stdout.take().unwrap()).read_line(&mut line).unwrap();
    assert!(line.starts_with("zeros set"), "{line}");
    client.kill().unwrap();
    client.wait().unwrap();
    assert!(t.child.try_wait().unwrap().is_none(), "the twin survives the client");
    let mut s = status(&t);
    for _ in 0..400 {
        if s["status"]["activity"] == "Idle" {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
        s = status(&t);
    }
    assert_eq!(s["status"]["activity"], "Idle", "the jog under way ends: {s}");
    assert_eq!(s["status"]["drivers_enabled"], false, "{s}");
    let (code, out, err) = board(&t, &["calibrate", &pose]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(out.matches("moved its torque's way").count(), 4, "{out}");
}

fn an_asserted_fault_line_stops_the_calibration_and_shows_in_the_raw_readings(on: Board) {
    let t = twin(on, &["--fault-line"]);
    assert_eq!(status(&t)["raw"]["driver_fault"], true);
    let pose = format!("--pose-deg={}", t.pose);
    let (code, out, err) = board(&t, &["calibrate", &pose]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(err.contains("jog of theta1") && err.contains("fault line (nFAULT) is asserted"), "{err}");
}

#[test]
fn a_port_that_does_not_exist_is_bad_input() {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(["board", "--port", "/nonexistent/tty", "status"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot open the serial port /nonexistent/tty"));
}

#[test]
fn a_pose_out_of_range_or_another_rate_is_refused_naming_the_values() {
    let t = twin(Board::Twin, &[]);
    for pose in ["--pose-deg=1e308,5", "--pose-deg=400,5", "--pose-deg=0,-180"] {
        let (code, _, err) = board(&t, &["calibrate", pose]);
        assert!(code == 2 && err.contains("(-180, 180] degrees"), "{pose}: {err}");
    }
    // A rate the image does not run (issue 56: any other is configured).
    let (code, _, err) = board(&t, &["configure", "--set", "timing.rate_hz=100"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("timing.rate_hz") && err.contains("250 to 10000 Hz"), "{err}");
}

#[test]
fn watch_and_the_twin_stopped_by_a_signal_exit_with_the_shells_code() {
    let mut t = twin(Board::Twin, &[]);
    let mut watch = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["board", "--port", &t.port, "--json", "watch", "--interval-ms", "20"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    // SAFETY: a signal to our own child.
    unsafe { libc::kill(watch.id() as i32, libc::SIGINT) };
    assert_eq!(watch.wait().unwrap().code(), Some(130));
    unsafe { libc::kill(t.child.id() as i32, libc::SIGTERM) };
    assert_eq!(t.child.wait().unwrap().code(), Some(143));
}

#[test]
fn a_client_that_writes_faster_than_it_reads_does_not_kill_the_twin() {
    // The audit's reproducer (issue 39, 4): 3 000 requests at once, no reply
    // read; the twin's writes found the pseudo-terminal full and it exited.
    use std::io::{Read, Write};
    let mut t = twin(Board::Twin, &[]);
    let mut flood = std::fs::OpenOptions::new().read(true).write(true).open(&t.port).unwrap();
    let mut buf = [0u8; 64];
    let hello = firmware::pil::encode(&arm_app::bringup::Request::Hello, &mut buf).unwrap().to_vec();
    let frames: Vec<u8> = std::iter::repeat_n(hello, 3000).flatten().collect();
    flood.write_all(&frames).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert!(t.child.try_wait().unwrap().is_none(), "the twin is still serving");
    // The client that did not read now reads what waited for it, then goes.
    let fd = std::os::fd::AsRawFd::as_raw_fd(&flood);
    // SAFETY: our own descriptor.
    unsafe { libc::fcntl(fd, libc::F_SETFL, libc::fcntl(fd, libc::F_GETFL) | libc::O_NONBLOCK) };
    let mut got = 0;
    let mut chunk = [0u8; 4096];
    for _ in 0..200 {
        match flood.read(&mut chunk) {
            Ok(n) if n > 0 => got += n,
            _ => std::thread::sleep(std::time::Duration::from_millis(10)),
        }
    }
    assert!(got > 0, "replies were kept for the slow reader");
    drop(flood);
    let (code, out, err) = board(&t, &["status"]);
    assert_eq!(code, 0, "{out}{err}");
}

#[test]
fn a_twin_killed_during_calibrate_leaves_exit_1_saying_the_calibration_is_half_done() {
    // Issue 39: it said "invalid input: write: Broken pipe", exit 2, though the
    // zeros had been set. The calibration's four jogs and rests take over a
    // second of the board's periods; the zeros are its first request.
    let mut t = twin(Board::Twin, &[]);
    let pose = format!("--pose-deg={}", t.pose);
    let cal = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["board", "--port", &t.port, "calibrate", &pose])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(600));
    t.child.kill().unwrap();
    let o = cal.wait_with_output().unwrap();
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("zeros set"), "{out}{err}");
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(err.contains("half done"), "{err}");
}

#[test]
fn a_reader_that_goes_away_or_a_full_disk_ends_board_commands_as_every_command() {
    // Issue 39: `sil-host board ... status | true` panicked on the broken pipe (exit 101).
    // Issue 52, 7: one behaviour for every command (sil_host::stdout): a closed
    // pipe ends it quietly with exit 141 (`watch` at its first line), a full
    // device with exit 1 and a message.
    let t = twin(Board::Twin, &[]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["board", "--port", &t.port, "watch", "--interval-ms", "5"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes away at once.
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(141), "{:?}: {err}", o.status);
    assert!(!err.contains("panicked") && !err.contains("error"), "{err}");
    for args in [&["status"][..], &["--json", "status"]] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .args(["board", "--port", &t.port])
            .args(args)
            .stdout(full)
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("cannot write to standard output: No space left on device") && !err.contains("panicked"), "{err}");
    }
    // The twin itself, whose port nobody can read: ends at once, quietly.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["board-twin", "--pty", "--serve-for", "60"])
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(141), "board-twin | (closed): {err}");
}

/// Issue 84: `run --link emulator` names the image it loaded, so a copied binary
/// can never silently run the build tree's: the path given (absolute), its bytes
/// of flash and their CRC-32, the same for a copy elsewhere (the same bytes) and
/// another for another image.
#[test]
fn the_emulator_link_names_the_image_it_loaded_by_path_and_crc() {
    let dir = tempfile::tempdir().unwrap();
    let built = board_link::emulator_link::default_image();
    let copy = dir.path().join("my-arm.elf");
    std::fs::copy(&built, &copy).unwrap();
    let loaded = |elf: &std::path::Path, out: &str, scenario: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .args(["run", "--link", "emulator", "--duration", "0.002", "--no-page"])
            .args(scenario)
            .arg("--elf")
            .arg(elf)
            .arg("--out")
            .arg(dir.path().join(out))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{err}");
        let line = err.lines().find(|l| l.starts_with("emulator: loaded ")).unwrap_or_else(|| panic!("no image named: {err}")).to_string();
        let crc = line.rsplit_once("CRC-32 0x").map(|(_, c)| c.trim_end_matches(')').to_string()).expect("a CRC-32");
        (line, crc)
    };
    let (line, crc) = loaded(&copy, "copy", &[]);
    assert!(line.contains(&copy.display().to_string()) && line.contains(" B of flash"), "{line}");
    let (line_built, crc_built) = loaded(&built, "built", &[]);
    assert!(line_built.contains(&std::path::absolute(&built).unwrap().display().to_string()), "{line_built}");
    assert_eq!(crc, crc_built, "the same bytes: {line} / {line_built}");
    assert_eq!(crc.len(), 8, "{line}");
    // The template's image (scripts/test.sh builds it beside the board's), with its law's scenario.
    let law = built.parent().unwrap().join("law-arm");
    assert!(law.exists(), "{} is missing: cargo law-arm (scripts/test.sh builds it)", law.display());
    let scenario = format!("{}/../examples/law-template/impedance.toml", env!("CARGO_MANIFEST_DIR"));
    let (line_law, crc_law) = loaded(&law, "law", &["--scenario", &scenario]);
    assert_ne!(crc_law, crc, "another image, another CRC: {line_law}");
}
