//! Issue 80, item 7, "bounded inputs everywhere": every file a command reads is
//! opened only if it is a regular file and read within its bound
//! (`tables::input`). `/dev/zero`, a FIFO, a 10 GB sparse file and a directory,
//! given as each kind of input of each command that reads one, exit 2 at once
//! naming the bound; a recording that is empty, cut off or of another scenario
//! is exit 2 saying so, never "identical" nor a divergence; an ELF that
//! declares no law is refused where a law is bound.
//!
//! The commands run as processes (`CARGO_BIN_EXE_sil-host`), each killed by a
//! watchdog after [`HANG`]: before issue 80 a FIFO blocked in `open` forever and
//! `/dev/zero` was read until the kernel killed the process (24 GB). A refusal
//! is a `stat`, milliseconds; the time is asserted under [`WITHIN`], the
//! issue's 1 s.

use std::{
    path::{Path, PathBuf},
    process::{Command, Stdio},
    time::{Duration, Instant},
};

/// How long a command may run before it counts as hung and is killed.
const HANG: Duration = Duration::from_secs(20);
/// The bound on a refusal: a `stat` and a message (measured: about
/// 10 ms, the process's start included).
const WITHIN: Duration = Duration::from_secs(1);

/// The bad inputs, each made once: `(label, path)`.
struct Bad {
    _dir: tempfile::TempDir,
    zero: PathBuf,
    fifo: PathBuf,
    sparse: PathBuf,
    dir: PathBuf,
}

impl Bad {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success(), "mkfifo");
        let sparse = dir.path().join("sparse");
        std::fs::File::create(&sparse).unwrap().set_len(10_000_000_000).unwrap();
        let folder = dir.path().join("folder");
        std::fs::create_dir(&folder).unwrap();
        Self { zero: "/dev/zero".into(), fifo, sparse, dir: folder, _dir: dir }
    }

    /// Each bad input with the words its refusal must hold.
    fn each(&self) -> [(&Path, &'static str); 4] {
        [
            (&self.zero, "it is a character device, not a regular file"),
            (&self.fifo, "it is a FIFO, not a regular file"),
            (&self.sparse, "it is 10000000000 bytes, over the"),
            (&self.dir, "it is a directory, not a regular file"),
        ]
    }
}

/// Runs `sil-host args` (standard input `stdin`, else none) under the
/// watchdog: its exit code, stderr, and how long it took.
fn sil_host_in(args: &[&str], stdin: Stdio) -> (i32, String, Duration) {
    let started = Instant::now();
    let mut child =
        Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).stdin(stdin).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let elapsed = started.elapsed();
            let mut err = String::new();
            std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
            return (status.code().unwrap_or(-1), err, elapsed);
        }
        if started.elapsed() > HANG {
            let _ = child.kill();
            let _ = child.wait();
            panic!("sil-host {args:?} hung: killed after {HANG:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn sil_host(args: &[&str]) -> (i32, String, Duration) {
    sil_host_in(args, Stdio::null())
}

/// `args` is refused with exit 2 within [`WITHIN`], its message holding each of `words`.
fn refused(args: &[&str], words: &[&str]) {
    let (code, err, elapsed) = sil_host(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: no {w:?} in {err}");
    }
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(elapsed < WITHIN, "{args:?} took {elapsed:?}");
}

/// A 32-bit little-endian ARM ELF header and nothing else: an image QEMU's
/// check takes (`pil --image`), without `PAINLEVE_LAW_SPEC`.
fn elf_without_a_law(dir: &Path) -> PathBuf {
    let mut h = vec![0x7f, b'E', b'L', b'F', 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    h.extend(2u16.to_le_bytes()); // e_type: executable
    h.extend(40u16.to_le_bytes()); // e_machine: ARM
    h.extend(1u32.to_le_bytes()); // e_version
    h.extend([0u8; 12]); // e_entry, e_phoff, e_shoff
    h.extend(0x0500_0400u32.to_le_bytes()); // e_flags: EABI 5, hard float
    h.extend(52u16.to_le_bytes()); // e_ehsize
    h.extend(32u16.to_le_bytes()); // e_phentsize
    h.extend(0u16.to_le_bytes()); // e_phnum
    h.extend(40u16.to_le_bytes()); // e_shentsize
    h.extend([0u8; 4]); // e_shnum, e_shstrndx
    assert_eq!(h.len(), 52);
    let path = dir.join("no-law.elf");
    std::fs::write(&path, h).unwrap();
    path
}

/// Folder `to`, a copy of the run folder `from`'s summary and frames.
fn copy_run(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for f in ["summary.json", "frames.csv"] {
        std::fs::copy(from.join(f), to.join(f)).unwrap();
    }
}

/// Puts bad input `bad` in the place of file `name` of folder `dir`: a link
/// to it (a `summary.json` linked to `/dev/zero`, issue 80), or, for the FIFO,
/// the sparse file and the directory, one of them made there.
fn replace(dir: &Path, name: &str, bad: &Path) {
    let at = dir.join(name);
    std::fs::remove_file(&at).unwrap();
    if bad == Path::new("/dev/zero") {
        std::os::unix::fs::symlink(bad, &at).unwrap();
    } else if bad.is_dir() {
        std::fs::create_dir(&at).unwrap();
    } else if bad.is_file() {
        std::fs::File::create(&at).unwrap().set_len(10_000_000_000).unwrap();
    } else {
        assert!(Command::new("mkfifo").arg(&at).status().unwrap().success());
    }
}

/// The ELF inputs (`board configure --elf`, `pil --image`, the emulated
/// board's `--elf`), the scenario (`run --scenario`, standard input too) and
/// the board's backup (`board restore`): refused before anything starts (the
/// board's port is not even opened), naming the bound.
#[test]
fn elf_images_scenarios_and_backups_that_are_not_bounded_files_exit_2_at_once() {
    let bad = Bad::new();
    let out = tempfile::tempdir().unwrap();
    let o = out.path().join("out");
    let o = o.to_str().unwrap();
    for (path, words) in bad.each() {
        let p = path.to_str().unwrap();
        refused(&["board", "--port", "/nonexistent", "configure", "--elf", p], &["ELF image", words, "64 MiB"]);
        refused(&["pil", "--image", p, "--duration", "0.01", "--out", o], &["ELF image", words, "64 MiB"]);
        refused(&["board-twin", "--pty", "--emulated", "--elf", p, "--serve-for", "1"], &["ELF image", words, "64 MiB"]);
        refused(&["run", "--in-process", "--scenario", p, "--out", o], &["scenario", words, "4 MiB"]);
        refused(&["board", "--port", "/nonexistent", "restore", p], &["board backup", words, "1 MiB"]);
    }
    assert!(!out.path().join("out").exists(), "nothing written");
    // Standard input is bounded as a file is: `cat /dev/zero | run --scenario -`.
    let (code, err, _) =
        sil_host_in(&["run", "--in-process", "--scenario", "-", "--out", o], Stdio::from(std::fs::File::open("/dev/zero").unwrap()));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("standard input: it is longer than 4194304 bytes as read") && err.contains("4 MiB"), "{err}");
}

/// An image that declares no law (no `PAINLEVE_LAW_SPEC`) is refused where a
/// scenario's law is bound to it, not taken for the paper's: every image of
/// these sources declares its law.
#[test]
fn an_elf_without_a_law_declaration_is_refused_where_a_law_is_bound() {
    let dir = tempfile::tempdir().unwrap();
    let elf = elf_without_a_law(dir.path());
    let e = elf.to_str().unwrap();
    refused(&["board", "--port", "/nonexistent", "configure", "--elf", e], &["no-law.elf", "the image declares no law"]);
    let out = dir.path().join("out");
    refused(
        &["pil", "--image", e, "--qemu", "/nonexistent-qemu", "--duration", "0.01", "--out", out.to_str().unwrap()],
        &["no-law.elf", "the image declares no law"],
    );
}

/// `replay DIR` with the run's `summary.json` or `frames.csv` replaced by each
/// bad input, and `merge` with a sweep's `sweep.json` or `runs.csv` replaced.
#[test]
fn summaries_recordings_and_sweep_files_that_are_not_bounded_files_exit_2_at_once() {
    let bad = Bad::new();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    let (code, err, _) = sil_host(&["run", "--in-process", "--no-page", "--duration", "0.05", "--out", rec.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let sweep = dir.path().join("sweep");
    let s = sweep.to_str().unwrap();
    let (code, err, _) = sil_host(&["sweep", "--mu", "0.6", "--v-belt=-0.4", "--transient", "1", "--record", "1", "--out", s]);
    assert_eq!(code, 0, "{err}");
    for (i, (path, words)) in bad.each().into_iter().enumerate() {
        for (name, what, bound) in [("summary.json", "summary", "64 MiB"), ("frames.csv", "recording", "4 GiB")] {
            let folder = dir.path().join(format!("{name}-{i}"));
            copy_run(&rec, &folder);
            replace(&folder, name, path);
            refused(&["replay", folder.to_str().unwrap()], &[what, words, bound]);
        }
        for (name, what, bound) in [("sweep.json", "sweep manifest", "4 MiB"), ("runs.csv", "sweep journal", "1 GiB")] {
            let folder = dir.path().join(format!("{name}-{i}"));
            std::fs::create_dir(&folder).unwrap();
            for f in ["sweep.json", "runs.csv"] {
                std::fs::copy(sweep.join(f), folder.join(f)).unwrap();
            }
            replace(&folder, name, path);
            let merged = dir.path().join(format!("merged-{name}-{i}"));
            refused(&["merge", folder.to_str().unwrap(), "--out", merged.to_str().unwrap()], &[what, words, bound]);
        }
    }
}

/// A recording with no rows, fewer rows than its summary's periods, or a last
/// row cut mid-line is exit 2 saying so, not "identical"; frames of another
/// scenario than the one the replay runs are exit 2 naming the setting, not a
/// firmware divergence.
#[test]
fn an_empty_cut_or_foreign_recording_is_exit_2_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    let (code, err, _) = sil_host(&["run", "--in-process", "--no-page", "--duration", "0.05", "--out", rec.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (code, err, _) = sil_host(&["replay", rec.to_str().unwrap()]);
    assert_eq!(code, 0, "the recording itself replays: {err}");
    let text = std::fs::read_to_string(rec.join("frames.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 51, "a header and 50 periods");
    let variant = |name: &str, frames: String| {
        let folder = dir.path().join(name);
        copy_run(&rec, &folder);
        std::fs::write(folder.join("frames.csv"), frames).unwrap();
        folder
    };
    let header_only = variant("header-only", format!("{}\n", lines[0]));
    let fewer = variant("fewer", lines[..31].iter().map(|l| format!("{l}\n")).collect());
    let cut = variant("cut", text[..text.len() - 20].to_string());
    let cases: [(&Path, &[&str]); 3] = [
        (&header_only, &["no frames: a header only", "not \"identical\""]),
        (&fewer, &["30 rows, but the run's summary.json says it ran 50 periods", "truncated"]),
        (&cut, &["its last row is cut mid-line", "truncated"]),
    ];
    for (folder, words) in cases {
        refused(&["replay", folder.to_str().unwrap()], words);
    }
    // A recording of another scenario: its summary says x0u, its frames start
    // from x0d; and the replay's own --set moving the rate or the length.
    let other = dir.path().join("other");
    copy_run(&rec, &other);
    let mut summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(other.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["scenario_used"]["plant"]["x0"], "d");
    summary["scenario_used"]["plant"]["x0"] = "u".into();
    std::fs::write(other.join("summary.json"), summary.to_string()).unwrap();
    let r = rec.to_str().unwrap();
    let foreign: [(Vec<&str>, &str); 3] = [
        (vec![other.to_str().unwrap()], "plant.x0: its first frame's state"),
        (vec![r, "--set", "timing.rate_hz=500"], "timing.rate_hz: its frames are 1000 us apart"),
        (vec![r, "--set", "timing.duration_s=0.01"], "timing.duration_s: it holds 50 periods, the scenario runs 10"),
    ];
    for (args, words) in foreign {
        let mut full = vec!["replay"];
        full.extend(&args);
        refused(&full, &["the recording is not of the scenario the replay runs", words]);
    }
}
