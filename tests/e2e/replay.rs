//! Issue 69 (3): `sil-host replay` (docs/rig.md "Replay"). A run records every
//! frame the firmware read and every answer (`frames.csv`, `frames.arrow`, the
//! `/wire` channels of `trace.mcap`); replayed through today's firmware on every
//! link (in-process, iceoryx2, the board twin, the `arm` ELF on the emulated
//! board, the PIL image in QEMU) the goldens' runs answer the same, bit for bit;
//! a gain changed in its last bit is found at the first period it moves an
//! answer, which a closed-loop run with that gain finds independently; bad
//! input is refused with its reason.

use std::{
    path::{Path, PathBuf},
    process::{Command, Output},
};

use crate::common;

/// `sil-host args`, as a process (the iceoryx2 link spawns the firmware from the executable).
fn sil_host(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).output().unwrap()
}

/// Records `sil-host run --in-process` (or `pil`) of `args` into `dir`.
fn record(command: &str, args: &[&str], dir: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).arg(command).args(args).arg("--out").arg(dir).output().unwrap();
    assert!(o.status.success(), "{command} {args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// `replay dir --json` with `args`: its exit code and document.
fn replay(dir: &Path, args: &[&str]) -> (i32, serde_json::Value, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).arg("replay").arg(dir).args(args).arg("--json").output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let doc = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("replay {args:?}: not JSON ({e}): {err}"));
    (o.status.code().unwrap_or(-1), doc, err)
}

/// The links and their options: every way the firmware can be fed.
fn links() -> Vec<(&'static str, Vec<String>)> {
    let pil = common::qemu_image("pil").display().to_string();
    let elf = board_link::emulator_link::default_image();
    assert!(elf.exists(), "{} is missing: {}", elf.display(), board_link::emulator_link::BUILD_HINT);
    vec![
        ("in-process", vec![]),
        ("iceoryx2", vec![]),
        ("twin", vec![]),
        ("emulator", vec!["--elf".into(), elf.display().to_string()]),
        ("pil", vec!["--image".into(), pil]),
    ]
}

/// Replays `dir` on every link and asserts "identical over `n` periods".
fn identical_on_every_link(dir: &Path, n: u64) {
    for (link, opts) in links() {
        let mut args = vec!["--link", link];
        args.extend(opts.iter().map(String::as_str));
        let (code, doc, err) = replay(dir, &args);
        assert_eq!(code, 0, "{link}: {doc} {err}");
        assert_eq!(doc["identical"], true, "{link}: {doc}");
        assert_eq!((doc["periods_recorded"].as_u64(), doc["periods_replayed"].as_u64()), (Some(n), Some(n)), "{link}: {doc}");
        assert!(doc["first_divergence"].is_null() && doc["link_error"].is_null(), "{link}: {doc}");
    }
}

fn scenario(name: &str) -> String {
    common::workspace().join("scenarios").join(format!("{name}.toml")).display().to_string()
}

/// A golden run (10 s, 10 000 periods) of `name`, recorded in `format`, replayed on every link.
fn golden_run_replays_identically(name: &str, format: &str) {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    record("run", &["--in-process", "--scenario", &scenario(name), "--format", format, "--no-page"], &rec);
    identical_on_every_link(&rec, 10_000);
}

#[test]
fn the_hybrid_run_from_x0d_replays_identically_on_every_link() {
    golden_run_replays_identically("hybrid-x0d", "csv");
}

#[test]
fn the_hybrid_run_from_x0u_replays_identically_on_every_link() {
    golden_run_replays_identically("hybrid-x0u", "arrow");
}

#[test]
fn the_pid_run_from_x0d_replays_identically_on_every_link() {
    golden_run_replays_identically("pid-x0d", "mcap");
}

#[test]
fn the_pid_run_from_x0u_replays_identically_on_every_link() {
    golden_run_replays_identically("pid-x0u", "csv");
}

/// The PIL golden (`pil-default`): recorded from the image in QEMU, replayed on
/// every link; and its frames are the in-process run's, byte for byte.
#[test]
fn the_pil_run_replays_identically_on_every_link_and_records_the_in_process_frames() {
    let dir = tempfile::tempdir().unwrap();
    let (pil, sil) = (dir.path().join("pil"), dir.path().join("sil"));
    record("pil", &["--image", &common::qemu_image("pil").display().to_string(), "--no-page", "--duration", "3"], &pil);
    record("run", &["--in-process", "--no-page", "--duration", "3"], &sil);
    assert_eq!(std::fs::read(pil.join("frames.csv")).unwrap(), std::fs::read(sil.join("frames.csv")).unwrap());
    identical_on_every_link(&pil, 3_000);
}

/// The next `f32` above `x`'s: a change in the gain's last bit as the firmware holds it.
fn next_f32_up(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1)
}

/// The first period whose answer differs between two recordings (`frames.csv`
/// of two runs): the period and the first differing column of the answer.
fn first_answer_difference(a: &Path, b: &Path) -> Option<(u64, String)> {
    let (ra, rb) = (common::csv_rows(&a.join("frames.csv")), common::csv_rows(&b.join("frames.csv")));
    let header = &ra[0];
    let answer_from = header.iter().position(|c| c == "answer").unwrap();
    for (x, y) in ra.iter().zip(&rb).skip(1) {
        // The runs are the same until the answers differ; the frames after that may too.
        assert_eq!(x[..answer_from], y[..answer_from], "the frames differ before any answer did");
        if let Some(i) = (answer_from..header.len()).find(|&i| x[i] != y[i]) {
            return Some((x[1].parse().unwrap(), header[i].clone()));
        }
    }
    None
}

/// A planted change: a gain one bit above the recorded one (as the firmware's
/// `f32`). The replay names the first period it moves an answer and the first
/// signal there; a closed-loop run with the same gain (whose frames are the
/// recording's until its answers differ) finds the same period and signal
/// independently. Over the paper's gains of both laws, and through the emulated
/// board's `arm` ELF too.
#[test]
fn a_gain_changed_in_its_last_bit_is_found_at_the_first_period_it_moves_an_answer() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, f32); 5] = [
        ("hybrid-x0d", "controller.hybrid.kp", 900.0),
        ("hybrid-x0d", "controller.hybrid.kd", 900.0),
        ("hybrid-x0u", "controller.f_n_ref", 10.0),
        ("pid-x0d", "controller.pid.kp", 200.0),
        ("pid-x0u", "controller.pid.kd", 2.0),
    ];
    for (i, (name, key, value)) in cases.into_iter().enumerate() {
        let rec = dir.path().join(format!("rec-{i}"));
        record("run", &["--in-process", "--scenario", &scenario(name), "--no-page", "--duration", "3"], &rec);
        let planted = next_f32_up(value);
        // The PID's gains are arrays (joint 1, joint 2): the first joint's changed.
        let set = if key.starts_with("controller.pid") { format!("{key}=[{planted}, 0.0]") } else { format!("{key}={planted}") };
        let changed = dir.path().join(format!("changed-{i}"));
        record("run", &["--in-process", "--scenario", &scenario(name), "--no-page", "--duration", "3", "--set", &set], &changed);
        let (period, signal) =
            first_answer_difference(&rec, &changed).unwrap_or_else(|| panic!("{key}: the change moved no answer in 3 s"));
        let (code, doc, err) = replay(&rec, &["--set", &set]);
        assert_eq!(code, 1, "{key}: {doc} {err}");
        assert_eq!(doc["identical"], false);
        let d = &doc["first_divergence"];
        assert_eq!((d["period"].as_u64(), d["signal"].as_str()), (Some(period), Some(signal.as_str())), "{key}: {doc}");
        assert!(err.contains(&format!("diverged from the recording at period {period}")), "{err}");
        // The recording itself replays identically: the difference is the gain's.
        assert_eq!(replay(&rec, &[]).0, 0, "{key}");
        if i == 0 {
            let elf = board_link::emulator_link::default_image().display().to_string();
            let (code, doc, _) = replay(&rec, &["--set", &set, "--link", "emulator", "--elf", &elf]);
            assert_eq!((code, doc["first_divergence"]["period"].as_u64()), (1, Some(period)), "the ELF: {doc}");
        }
    }
}

/// `--all` compares every period and counts the ones that differ; the human
/// verdict names the period, the signal and both values.
#[test]
fn all_counts_every_divergent_period_and_the_text_names_both_values() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    record("run", &["--in-process", "--no-page", "--duration", "2"], &rec);
    let set = "controller.hybrid.kp=1000";
    let (code, doc, _) = replay(&rec, &["--set", set, "--all"]);
    assert_eq!(code, 1);
    let (n, differ) = (doc["periods_replayed"].as_u64().unwrap(), doc["divergent_periods"].as_u64().unwrap());
    assert!(n == 2000 && differ > 100 && differ <= n, "{doc}");
    // How much, per signal (issue 84): the first divergence's signal first, from its
    // period; every count within the periods that differ, and together covering them;
    // a torque code's largest difference also in N m (5 N m over 2048 codes).
    let per = doc["per_signal"].as_array().expect("per_signal");
    let first = &doc["first_divergence"];
    assert_eq!(per[0]["signal"], first["signal"], "{doc}");
    assert_eq!(per[0]["first_period"], first["period"], "{doc}");
    let mut covered = 0;
    for d in per {
        let (count, largest) = (d["divergent_periods"].as_u64().unwrap(), d["largest_difference"].as_f64().unwrap());
        assert!(count >= 1 && count <= differ && largest > 0.0, "{d}");
        assert!(
            d["first_period"].as_u64() >= first["period"].as_u64() && d["largest_at_period"].as_u64() >= d["first_period"].as_u64(),
            "{d}"
        );
        covered += count;
        if d["unit"] == "code" {
            assert_eq!(d["largest_difference_nm"].as_f64().unwrap(), largest * 5.0 / 2048.0, "{d}");
        } else {
            assert!(d["largest_difference_nm"].is_null(), "{d}");
        }
    }
    assert!(covered >= differ, "every divergent period has a signal that differs: {covered} < {differ}");
    let code = per.iter().find(|d| d["unit"] == "code").expect("a gain changes the torque codes");
    let (codes, nm) = (code["largest_difference"].as_f64().unwrap(), code["largest_difference_nm"].as_f64().unwrap());
    let o = sil_host(&["replay", rec.to_str().unwrap(), "--set", set, "--all"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("{}: from period {}", code["signal"].as_str().unwrap(), code["first_period"])), "{text}");
    assert!(text.contains(&format!("at most {codes} code ({nm} N m)")), "{text}");
    let o = sil_host(&["replay", rec.to_str().unwrap(), "--set", set]);
    let out = String::from_utf8_lossy(&o.stdout);
    let d = &doc["first_divergence"];
    assert!(out.contains(&format!("DIVERGED at period {}", d["period"])), "{out}");
    assert!(out.contains(&format!("recorded {}, replayed {}", d["recorded"].as_str().unwrap(), d["replayed"].as_str().unwrap())), "{out}");
}

/// The scenario's faults act again where they act on the link: lost commands
/// (`drop_command`, recorded `dropped`) and a stuck sensor (in the frames)
/// replay identically in-process and over iceoryx2.
#[test]
fn a_run_with_faults_replays_identically() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scenario("default")).unwrap()
        + "\n[[faults]]\nkind = \"drop_command\"\nat_s = 0.5\nduration_s = 0.004\n\n[[faults]]\nkind = \"stuck_sensor\"\nat_s = 0.8\nduration_s = 0.003\nsignal = \"f_n\"\n";
    let path = dir.path().join("faults.toml");
    std::fs::write(&path, text).unwrap();
    let rec = dir.path().join("rec");
    record("run", &["--in-process", "--scenario", path.to_str().unwrap(), "--no-page", "--duration", "1.5"], &rec);
    let rows = common::csv_rows(&rec.join("frames.csv"));
    let answer = rows[0].iter().position(|c| c == "answer").unwrap();
    assert_eq!(rows.iter().filter(|r| r[answer] == "dropped").count(), 4, "four lost commands recorded");
    for link in ["in-process", "iceoryx2"] {
        let (code, doc, err) = replay(&rec, &["--link", link]);
        assert_eq!((code, &doc["identical"]), (0, &serde_json::Value::Bool(true)), "{link}: {doc} {err}");
    }
}

/// Bad input is refused with its reason (exit 2), before any link starts.
#[test]
fn bad_input_is_refused_with_its_reason() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    record("run", &["--in-process", "--no-page", "--duration", "0.2"], &rec);
    let sim = dir.path().join("sim");
    record("simulate", &["--duration", "0.1", "--no-page"], &sim);
    let no_frames = dir.path().join("no-frames");
    std::fs::create_dir(&no_frames).unwrap();
    std::fs::copy(rec.join("summary.json"), no_frames.join("summary.json")).unwrap();
    let cut = dir.path().join("cut");
    std::fs::create_dir(&cut).unwrap();
    std::fs::copy(rec.join("summary.json"), cut.join("summary.json")).unwrap();
    let text = std::fs::read_to_string(rec.join("frames.csv")).unwrap();
    let without_column: String = text.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n").collect();
    std::fs::write(cut.join("frames.csv"), without_column).unwrap();
    let missing: PathBuf = dir.path().join("nowhere");
    let r = rec.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec![missing.to_str().unwrap()], "no such folder"),
        (vec![sim.to_str().unwrap()], "no `scenario_used`"),
        (vec![no_frames.to_str().unwrap()], "no frames recorded"),
        (vec![cut.to_str().unwrap()], "no column `u2_raw`"),
        (vec![r, "--elf", "x.elf"], "--elf goes with --link emulator"),
        (vec![r, "--image", "x.elf"], "--image goes with --link pil"),
        (vec![r, "--set", "controller.nope=1"], "controller.nope"),
        (vec![r, "--set", "controller.hybrid.kp=-5"], "controller.hybrid.kp"),
        (vec![r, "--link", "pil", "--image", missing.to_str().unwrap()], "no PIL image"),
        (vec![r, "--link", "emulator", "--elf", missing.to_str().unwrap()], "nowhere"),
    ];
    for (args, expected) in cases {
        let mut full = vec!["replay"];
        full.extend(&args);
        let o = sil_host(&full);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// Not only the goldens: runs of random scenarios over the whole envelope the
/// validator accepts (both laws, every friction term the draw gives, rates 250 Hz
/// to 10 kHz, random gains, `mu_hat` off by up to 25 %; board-link's
/// `random_envelope`) replay identically in-process and over iceoryx2, however
/// each run ended (a safe state included). The board links with them:
/// `a_run_recorded_on_any_link_replays_identically_on_every_other` below.
#[test]
fn runs_of_random_scenarios_over_the_envelope_replay_identically() {
    let dir = tempfile::tempdir().unwrap();
    for i in 0..6u64 {
        let kind = if i % 2 == 0 { "hybrid" } else { "pid" };
        let (scenario, what) = board_link::random_scenarios::random_envelope(6900 + i, kind, 0.4);
        let file = dir.path().join(format!("s{i}.toml"));
        std::fs::write(&file, toml::to_string(&scenario).unwrap()).unwrap();
        let rec = dir.path().join(format!("rec{i}"));
        // A run may end early (a safe state): its frames up to then are the record.
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .args(["run", "--in-process", "--no-page", "--scenario", file.to_str().unwrap(), "--out"])
            .arg(&rec)
            .output()
            .unwrap();
        assert!(matches!(o.status.code(), Some(0 | 1)), "{what}: {}", String::from_utf8_lossy(&o.stderr));
        let n = common::csv_rows(&rec.join("frames.csv")).len() as u64 - 1;
        assert!(n > 0, "{what}: no period recorded");
        for args in [vec![], vec!["--link", "iceoryx2"]] {
            let (code, doc, err) = replay(&rec, &args);
            assert_eq!(
                (code, &doc["identical"], doc["periods_replayed"].as_u64()),
                (0, &serde_json::Value::Bool(true), Some(n)),
                "{what} {args:?}: {doc} {err}"
            );
        }
    }
}

/// The links in a run (`sil-host run --link`) and their options.
fn run_links() -> Vec<(&'static str, Vec<String>)> {
    let elf = board_link::emulator_link::default_image();
    assert!(elf.exists(), "{} is missing: {}", elf.display(), board_link::emulator_link::BUILD_HINT);
    vec![("in-process", vec![]), ("twin", vec![]), ("emulator", vec!["--elf".into(), elf.display().to_string()])]
}

/// Issue 80 (3): one belt measurement on every link. The board links read the
/// belt with their quadrature counter (the twin's and the emulated TIM4's, set
/// by `drivers::belt::count_at` from the belt's travel `v_belt t_k`) and the
/// `arm` application's driver; the wire-level links' sensor model runs the same
/// pair (`drivers::belt::SampledBelt`), so the frame's `belt_count` is the
/// board's reading: 0 in period 0, then the counts of each period with their
/// jitter. Random scenarios over the envelope (`random_envelope`: both x0,
/// rates 250 Hz to 10 kHz, random gains, `v_belt` -1 to -0.1 m/s), one per
/// friction term of the hybrid law and one PID, recorded on the in-process
/// link, the board twin and the `arm` ELF on the emulated board, each replay
/// identically on every other link, iceoryx2 included (its frames are the
/// in-process link's). Before the one model, every `estimated` run diverged
/// on the board links from period 1 on (`u1_raw`).
#[test]
fn a_run_recorded_on_any_link_replays_identically_on_every_other() {
    let dir = tempfile::tempdir().unwrap();
    let frictions = board_link::random_scenarios::FRICTIONS;
    let replay_links = ["in-process", "iceoryx2", "twin", "emulator"];
    let elf = board_link::emulator_link::default_image().display().to_string();
    for i in 0..=frictions.len() {
        let kind = if i < frictions.len() { "hybrid" } else { "pid" };
        let (mut scenario, mut what) = board_link::random_scenarios::random_envelope(8000 + i as u64, kind, 0.3);
        if let Some(&f) = frictions.get(i) {
            scenario.controller.friction = f;
            what += &format!(" (run with {})", board_link::random_scenarios::friction_name(f));
        }
        let file = dir.path().join(format!("s{i}.toml"));
        std::fs::write(&file, toml::to_string(&scenario).unwrap()).unwrap();
        for (from, opts) in run_links() {
            let rec = dir.path().join(format!("rec{i}-{from}"));
            // A run may end early (a safe state): its frames up to then are the record.
            let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
                .args(["run", "--link", from, "--no-page", "--scenario", file.to_str().unwrap()])
                .args(&opts)
                .arg("--out")
                .arg(&rec)
                .output()
                .unwrap();
            assert!(matches!(o.status.code(), Some(0 | 1)), "{what} on {from}: {}", String::from_utf8_lossy(&o.stderr));
            let n = common::csv_rows(&rec.join("frames.csv")).len() as u64 - 1;
            assert!(n > 0, "{what} on {from}: no period recorded");
            for to in replay_links.into_iter().filter(|&to| to != from) {
                let mut args = vec!["--link", to];
                if to == "emulator" {
                    args.extend(["--elf", elf.as_str()]);
                }
                let (code, doc, err) = replay(&rec, &args);
                assert_eq!(
                    (code, &doc["identical"], doc["periods_replayed"].as_u64()),
                    (0, &serde_json::Value::Bool(true), Some(n)),
                    "{what}: recorded on {from}, replayed on {to}: {doc} {err}"
                );
            }
        }
    }
}

/// The issue's own commands: a run on the twin with the estimated friction
/// term replays identically in-process; and the default scenario's run
/// in-process replays identically on the twin under every friction term, the
/// belt moving or stopped.
#[test]
fn a_twin_run_with_the_estimated_friction_term_replays_identically_in_process() {
    let dir = tempfile::tempdir().unwrap();
    let twin = dir.path().join("twin");
    record("run", &["--link", "twin", "--no-page", "--set", "controller.friction=estimated"], &twin);
    let (code, doc, err) = replay(&twin, &["--link", "in-process"]);
    assert_eq!(
        (code, &doc["identical"], doc["periods_replayed"].as_u64()),
        (0, &serde_json::Value::Bool(true), Some(10_000)),
        "{doc} {err}"
    );
    for friction in board_link::random_scenarios::FRICTIONS {
        for v_belt in ["0", "-0.4"] {
            let name = board_link::random_scenarios::friction_name(friction);
            let rec = dir.path().join(format!("{name}{v_belt}"));
            let (f, v) = (format!("controller.friction={name}"), format!("plant.v_belt={v_belt}"));
            // A run may end early (the measured term's safe state): its frames up to then are the record.
            let o = sil_host(&[
                "run",
                "--in-process",
                "--no-page",
                "--duration",
                "0.3",
                "--set",
                &f,
                "--set",
                &v,
                "--out",
                rec.to_str().unwrap(),
            ]);
            assert!(matches!(o.status.code(), Some(0 | 1)), "{name}: {}", String::from_utf8_lossy(&o.stderr));
            let (code, doc, err) = replay(&rec, &["--link", "twin"]);
            assert_eq!((code, &doc["identical"]), (0, &serde_json::Value::Bool(true)), "{name}, v_belt {v_belt}: {doc} {err}");
        }
    }
}

/// The frame's belt reading is the belt encoder's (docs/hardware.md "The belt
/// sensor's model"): 0 in period 0 (no earlier count), then `v_belt` to one
/// count of the rate's scale (1 mm/s at 1 kHz, 10 mm/s at 10 kHz) with the
/// count's jitter, not the exact speed's mm/s in every period.
#[test]
fn the_recorded_belt_is_the_encoders_reading() {
    let dir = tempfile::tempdir().unwrap();
    for (rate, lsb) in [("1000", 1i64), ("10000", 10)] {
        let rec = dir.path().join(format!("r{rate}"));
        let set = format!("timing.rate_hz={rate}");
        // The command's delay within the shortest period (0.1 ms).
        record("run", &["--in-process", "--no-page", "--duration", "0.3", "--set", &set, "--set", "timing.delta_s=0.00005"], &rec);
        let rows = common::csv_rows(&rec.join("frames.csv"));
        let col = rows[0].iter().position(|c| c == "belt_count").unwrap();
        let belt: Vec<i64> = rows[1..].iter().map(|r| r[col].parse().unwrap()).collect();
        assert_eq!(belt[0], 0, "{rate} Hz");
        assert!(belt[1..].iter().all(|v| v % lsb == 0 && (-400 - lsb..=-400 + lsb).contains(v)), "{rate} Hz: {belt:?}");
        assert!(belt[1..].iter().any(|&v| v != -400), "{rate} Hz: the count's jitter: {belt:?}");
    }
}

/// Issue 84: `replay --out DIR` writes the replayed answers as a run's frames
/// table (the recorded frames, this build's answers) beside the comparison: every
/// period replayed is a row, the frames' columns equal the recording's bit for bit,
/// the answers differ from it in exactly `divergent_periods` rows (with `--all`),
/// and an identical replay writes the recording's rows again; in MCAP, the
/// `/wire/*` channels read back as the same table.
#[test]
fn out_writes_the_replayed_answers_as_a_frames_table() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    record("run", &["--in-process", "--no-page", "--duration", "1"], &rec);
    let (_, recorded) = rig::frames::read_frames(&rec).unwrap();
    let frame = |r: &rig::frames::FrameRow| format!("{:?}", (r.frame(), r.truth()));
    for (set, format) in [("controller.hybrid.kp=1000", "csv"), ("controller.hybrid.kp=1000", "mcap"), ("", "csv")] {
        let out = dir.path().join(format!("out-{format}-{}", set.is_empty()));
        let mut args = vec!["--all", "--format", format, "--out", out.to_str().unwrap()];
        if !set.is_empty() {
            args.extend(["--set", set]);
        }
        let (code, doc, err) = replay(&rec, &args);
        assert_eq!(code, if set.is_empty() { 0 } else { 1 }, "{doc} {err}");
        let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["divergent_periods"], doc["divergent_periods"]);
        // The folder is read as a recording's frames are (frames.csv, or trace.mcap's /wire channels).
        let (_, replayed) = rig::frames::read_frames(&out).unwrap();
        let n = doc["periods_replayed"].as_u64().unwrap() as usize;
        assert_eq!((replayed.len(), n), (recorded.len(), 1000), "{format}");
        let mut differ = 0;
        for (a, b) in replayed.iter().zip(&recorded) {
            assert_eq!(frame(a), frame(b), "{format}: period {}", a.seq);
            differ += usize::from(a.first_difference(b).is_some());
        }
        assert_eq!(differ as u64, doc["divergent_periods"].as_u64().unwrap(), "{format} {set}");
        assert_eq!(differ == 0, set.is_empty(), "{format} {set}: {differ}");
    }
}
