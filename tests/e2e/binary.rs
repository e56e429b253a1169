//! The real `sil-host` binary: exit codes, `--json` on stdout, `--help`.

use std::process::Command;

fn sil_host() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sil-host"))
}

#[test]
fn json_summary_on_stdout_parses_and_matches_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = sil_host().args(["simulate", "--x0", "d", "--duration", "0.5", "--json", "--out"]).arg(dir.path()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON document");
    let file: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap()).unwrap();
    assert_eq!(stdout, file);
    assert_eq!(stdout["initial_condition"]["name"], "x0d");
    assert_eq!(stdout["initial_condition"]["projection"]["branch"], "down");
}

#[test]
fn unknown_flags_and_bad_values_exit_with_2_and_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let out = sil_host().args(["simulate", "--bogus"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--bogus"));
    let out = sil_host().args(["simulate", "--v-belt", "NaN", "--out"]).arg(dir.path()).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("v_belt"), "{}", String::from_utf8_lossy(&out.stderr));
    let out = sil_host().args(["simulate", "--x0-deg", "0,0,0,0", "--out"]).arg(dir.path()).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("below the belt"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written");
}

#[test]
fn version_names_the_commit_it_was_built_from() {
    let out = sil_host().arg("--version").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with(concat!("sil-host ", env!("CARGO_PKG_VERSION"), " (commit ")), "{text}");
    // The tests run from the checkout the binary was built from: its commit is HEAD's
    // (`git describe --always` abbreviates it to at least 7 hex digits).
    let head = Command::new("git").args(["rev-parse", "HEAD"]).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    assert!(head.status.success(), "the tests run in a git checkout");
    let head = String::from_utf8_lossy(&head.stdout);
    assert!(text.contains(&head[..7]), "{text} does not name HEAD {head}");
    // The tests build everything (`required-features = ["full"]`): the four optional parts.
    assert!(text.trim_end().ends_with("; features: board, live, formats, pdf)"), "{text}");
}

#[test]
fn help_explains_the_commands() {
    let out = sil_host().arg("--help").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for cmd in ["simulate", "admissible", "modes"] {
        assert!(text.contains(cmd));
    }
}

/// A board key where there is no board (issue 42): `--set board.*` refused with
/// exit 2 before anything is written; a scenario file's `[board]` warned about on
/// standard error, the run done; on the twin link the same key is taken.
#[test]
fn board_keys_do_nothing_without_a_board_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = sil_host()
        .args(["run", "--in-process", "--duration", "0.01", "--set", "board.pwm_max_duty=4000", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("board.pwm_max_duty") && stderr.contains("in-process"), "{stderr}");
    assert!(!dir.path().join("trace.csv").exists(), "nothing written");

    let scenario = dir.path().join("board.toml");
    std::fs::write(&scenario, format!("{}\n[board]\npwm_max_duty = 4000\n", rig::scenario::DEFAULT_TOML)).unwrap();
    let out = sil_host()
        .args(["run", "--in-process", "--duration", "0.01", "--scenario"])
        .arg(&scenario)
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("warning: the scenario's [board]") && stderr.contains("ignored"), "{stderr}");

    let out = sil_host()
        .args(["run", "--link", "twin", "--duration", "0.01", "--set", "board.pwm_max_duty=4000", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !stderr.contains("warning"), "{stderr}");
}

/// Runs `sil-host ARGS` (with `--out OUT` when `out` is given) twice, as text and
/// as `--json`: with standard output a pipe whose reader is gone, it must end
/// quietly with exit 141 after writing its files; with standard output
/// `/dev/full`, with exit 1 and a message naming standard output. Never a panic.
fn check_stdout_failures(args: &[String], out: Option<&std::path::Path>, runs: &[(bool, bool)]) {
    use std::process::Stdio;
    let command = |json: bool| {
        let mut c = sil_host();
        c.args(args).args(json.then_some("--json")).stderr(Stdio::piped());
        if let Some(out) = out {
            c.arg("--out").arg(out);
        }
        c
    };
    for &(json, closed) in runs {
        let what = format!("{}{}", args.join(" "), if json { " --json" } else { "" });
        if closed {
            // A pipe whose reader is gone before the command starts.
            let (reader, writer) = std::io::pipe().unwrap();
            drop(reader);
            let o = command(json).stdout(writer).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!err.contains("panicked"), "{what} | (closed): {err}");
            assert_eq!(o.status.code(), Some(141), "{what} | (closed): {err}");
            assert!(!err.contains("error"), "{what} | (closed): quietly: {err}");
            if let Some(out) = out {
                // Its files are written all the same.
                assert!(std::fs::read_dir(out).unwrap().count() > 0, "{what}: nothing written");
            }
        } else {
            let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
            let o = command(json).stdout(full).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!err.contains("panicked"), "{what} > /dev/full: {err}");
            assert_eq!(o.status.code(), Some(1), "{what} > /dev/full: {err}");
            assert!(err.contains("error: cannot write to standard output: No space left on device"), "{what} > /dev/full: {err}");
        }
    }
}

/// Every (closed, full) case, as text and as JSON.
const ALL: &[(bool, bool)] = &[(false, true), (false, false), (true, true), (true, false)];

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

/// Issue 52, 7: `simulate`, `run`, `zmax` and `sweep` panicked (exit 101) when
/// standard output was a closed pipe (`--json | true`, `| head -c 10`) or full
/// (`> /dev/full`). One behaviour for every command that prints: a closed pipe
/// ends it quietly with exit 141 after its work (its files written), a full
/// device with exit 1 and a message naming standard output. Each command runs
/// on a tiny case. (`board` and `board-twin` need a board twin:
/// tests/e2e/board.rs; `sensitivity` and `report` take minutes: the ignored
/// test below; `pil` needs QEMU and the image: tried when they are there;
/// `firmware` prints nothing.)
#[test]
fn a_closed_or_full_standard_output_ends_every_command_without_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut commands: Vec<Vec<String>> = vec![
        strings(&["simulate", "--duration", "0.2"]),
        strings(&["admissible"]),
        strings(&["modes", "--grid", "10"]),
        strings(&["poincare", "--v-belt=-0.4", "--transient", "1", "--record", "1"]),
        strings(&["run", "--in-process", "--set", "timing.duration_s=0.1"]),
        strings(&["run", "--set", "timing.duration_s=0.1"]),
        strings(&["sweep", "--mu", "0.6", "--v-belt=-0.5,-0.4", "--v-belt-step", "0.1", "--transient", "2", "--record", "1"]),
        strings(&["zmax", "--duration", "3.5", "--tol", "0.05"]),
    ];
    // `cargo build-pil`'s image, the one the e2e tests build too (tests/e2e/common.rs).
    let image = Some(crate::common::target_dir().join("thumbv7em-none-eabihf/qemu/pil")).filter(|p| p.is_file());
    let qemu = Command::new("qemu-system-arm").arg("--version").output().is_ok_and(|o| o.status.success());
    if let Some(image) = image.filter(|_| qemu) {
        commands.push(vec!["pil".into(), "--image".into(), image.display().to_string(), "--duration".into(), "0.05".into()]);
    }
    for (i, args) in commands.iter().enumerate() {
        check_stdout_failures(args, Some(&dir.path().join(i.to_string())), ALL);
    }
    // `merge` of the sweep's folder; `bench` (no folder; its flash figures are
    // skipped without the images, and printed all the same).
    let sweep = dir.path().join(commands.iter().position(|a| a[0] == "sweep").unwrap().to_string());
    check_stdout_failures(&strings(&["merge", &sweep.display().to_string()]), Some(&dir.path().join("merged")), ALL);
    check_stdout_failures(&strings(&["bench", "--only", "flash"]), None, ALL);
}

/// [`a_closed_or_full_standard_output_ends_every_command_without_a_panic`] for
/// the two commands that take minutes (`sensitivity --size quick` about 3 min,
/// `report` 2 to 3 min, less when it resumes): a closed pipe as JSON, a full
/// device as text. `cargo test --release -p sil-host --features full --test binary -- --ignored`.
#[test]
#[ignore = "takes about 10 minutes"]
fn a_closed_or_full_standard_output_ends_the_long_commands_without_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    for (i, args) in [strings(&["sensitivity", "--size", "quick"]), strings(&["report"])].iter().enumerate() {
        check_stdout_failures(args, Some(&dir.path().join(i.to_string())), &[(true, true), (false, false)]);
    }
}

/// Issue 52, 8: `pil --image` with a damaged file exited 1 (not bad input), and
/// with an ELF of another machine waited 20 s for a boot that never came. The
/// header is checked first: exit 2 at once, naming the file and what is wrong.
#[test]
fn a_pil_image_that_is_not_an_arm_elf_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let damaged = dir.path().join("damaged.elf");
    // An ELF header cut after its magic and class.
    std::fs::write(&damaged, b"\x7fELF\x01\x01\x01\0garbage").unwrap();
    let cases = [
        (damaged.clone(), "not an ELF image"),
        // This test's own binary: an ELF of the host's machine.
        (std::path::PathBuf::from(env!("CARGO_BIN_EXE_sil-host")), "not 32-bit little-endian ARM"),
    ];
    for (image, why) in cases {
        let started = std::time::Instant::now();
        let o =
            sil_host().args(["pil", "--duration", "0.01", "--image"]).arg(&image).arg("--out").arg(dir.path().join("o")).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", image.display());
        assert!(err.contains(why) && err.contains(&image.display().to_string()), "{err}");
        assert!(started.elapsed() < std::time::Duration::from_secs(5), "refused at once: {:?}", started.elapsed());
        assert!(!dir.path().join("o").exists(), "nothing written");
    }
}

/// Issue 52, 5: `run` wrote its streamed trace through a link planted in `--out`.
#[test]
fn run_writes_no_trace_through_a_link_planted_in_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "keep").unwrap();
    for format in ["csv", "arrow", "mcap"] {
        let planted = out.join(format!("trace.{format}.partial"));
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        let o = sil_host()
            .args(["run", "--in-process", "--set", "timing.duration_s=0.05", "--format", format, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep", "{format}: written through the link");
        assert!(std::fs::symlink_metadata(out.join(format!("trace.{format}"))).unwrap().is_file());
        assert!(!planted.exists());
    }
}

/// Issue 52, 4: the rig's locks were opened through links another user planted
/// in the shared temporary folder. They live in the user's own 0700 folder
/// (`<temp>/painleve-<uid>` here, `$XDG_RUNTIME_DIR` unset), which is refused
/// when it is a link, open to others or another user's, with a message saying
/// why and exit 2 (a refusal before anything ran, as a rig in use: issue 66);
/// a run killed by SIGKILL leaves a lock file the next run removes.
#[test]
fn a_run_keeps_its_locks_in_a_private_folder_and_refuses_one_that_is_not() {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let temp = tempfile::tempdir().unwrap();
    let uid = unsafe { libc::geteuid() };
    let private = temp.path().join(format!("painleve-{uid}"));
    let run = |out: &str| {
        sil_host()
            .args(["run", "--set", "timing.duration_s=0.05", "--out"])
            .arg(temp.path().join(out))
            .env("TMPDIR", temp.path())
            .env_remove("XDG_RUNTIME_DIR")
            .output()
            .unwrap()
    };
    // A killed run's lock (its pid dead), then a run: made 0700, the stale lock gone.
    std::fs::DirBuilder::new().recursive(true).create(&private).unwrap();
    std::fs::set_permissions(&private, std::fs::Permissions::from_mode(0o700)).unwrap();
    let mut child = Command::new("true").spawn().unwrap();
    let dead = child.id();
    child.wait().unwrap();
    let stale = private.join(format!("painleve-rig-painleve-{dead}.plant.lock"));
    std::fs::write(&stale, dead.to_string()).unwrap();
    let o = run("a");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::metadata(&private).unwrap().mode() & 0o777, 0o700);
    assert!(!stale.exists(), "the killed run's lock was removed");
    let left: Vec<_> = std::fs::read_dir(&private).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(left.is_empty(), "the run leaves no lock: {left:?}");
    // A link planted at the folder's name: refused, nothing made through it.
    std::fs::remove_dir(&private).unwrap();
    let elsewhere = temp.path().join("planted");
    std::fs::create_dir(&elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, &private).unwrap();
    let o = run("b");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("symbolic link") && err.contains(&private.display().to_string()), "{err}");
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0, "nothing made through the link");
    assert!(!temp.path().join("b").exists(), "nothing written");
    // A folder of ours that others can enter (made before us, 0755): refused, its mode named.
    std::fs::remove_file(&private).unwrap();
    std::fs::create_dir(&private).unwrap();
    std::fs::set_permissions(&private, std::fs::Permissions::from_mode(0o755)).unwrap();
    let o = run("c");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("mode 755") && err.contains(&private.display().to_string()), "{err}");
    // Another user's folder made before us (as root: given to nobody), refused naming its owner.
    if uid == 0 {
        std::fs::set_permissions(&private, std::fs::Permissions::from_mode(0o700)).unwrap();
        std::os::unix::fs::chown(&private, Some(65534), Some(65534)).unwrap();
        let o = run("d");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("owned by uid 65534") && err.contains("another user's"), "{err}");
        assert!(!temp.path().join("d").exists(), "nothing written");
    }
}
