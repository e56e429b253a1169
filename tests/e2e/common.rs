//! Helpers of the end-to-end tests: the workspace, the board's images, running
//! the command line in-process and reading what it writes.

use std::{
    io::{BufRead, BufReader},
    path::{Path, PathBuf},
    process::{Child, ChildStdin, Command, Stdio},
    sync::{Mutex, OnceLock},
};

/// The workspace root.
pub fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The workspace's target folder, where the MCU images are built: `target/`. The
/// tests' own cargo runs build there too (the outer `cargo test` releases its
/// lock once the test binaries are built), so an image scripts/test.sh built is
/// found fresh, not built a second time.
pub fn target_dir() -> PathBuf {
    workspace().join("target")
}

/// Builds image `bin` of `boards/stm32f405` for QEMU (profile `qemu`, feature
/// `qemu`) in the workspace's target folder ([`target_dir`]; a no-op when it is
/// fresh), once per test binary; its path.
pub fn qemu_image(bin: &str) -> PathBuf {
    static BUILT: OnceLock<()> = OnceLock::new();
    let root = workspace();
    let target_dir = target_dir();
    BUILT.get_or_init(|| {
        assert!(
            Command::new("qemu-system-arm").arg("--version").output().is_ok(),
            "qemu-system-arm is missing: apt-get install -y qemu-system-arm (CI installs it)"
        );
        let build = Command::new(env!("CARGO"))
            .args(["build", "-p", "board-stm32f405", "--profile", "qemu", "--target", "thumbv7em-none-eabihf"])
            .args(["--no-default-features", "--features", "qemu", "--bin", "arm", "--bin", "pil"])
            .env("CARGO_TARGET_DIR", &target_dir)
            .current_dir(&root)
            .output()
            .unwrap();
        assert!(build.status.success(), "building the images failed:\n{}", String::from_utf8_lossy(&build.stderr));
    });
    target_dir.join("thumbv7em-none-eabihf/qemu").join(bin)
}

/// The defmt lines of `bytes` (an image's semihosting output), decoded with the table of `elf`
/// ([`decode_defmt_stamped`] without the timestamps).
pub fn decode_defmt(elf: &Path, bytes: &[u8]) -> Vec<String> {
    decode_defmt_stamped(elf, bytes).into_iter().map(|(_, line)| line).collect()
}

/// The defmt lines of `bytes` with their timestamps (`mcu::log_time`: seconds with
/// six decimals), decoded with the table of `elf`: `(timestamp, "[level] message")`.
pub fn decode_defmt_stamped(elf: &Path, bytes: &[u8]) -> Vec<(Option<String>, String)> {
    let elf = std::fs::read(elf).unwrap();
    let table = defmt_decoder::Table::parse(&elf).unwrap().expect("the image has a defmt table");
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = Vec::new();
    loop {
        match decoder.decode() {
            Ok(frame) => {
                let level = frame.level().map_or("println", |l| l.as_str()).to_string();
                lines.push((frame.display_timestamp().map(|t| t.to_string()), format!("[{level}] {}", frame.display_message())));
            }
            Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
            Err(e) => panic!("corrupt defmt stream: {e}"),
        }
    }
    lines
}

/// The numbers after `key` in a log line (`key 123`, `key 1..2 of 3`).
pub fn numbers_after(line: &str, key: &str) -> Vec<u64> {
    let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
    rest.split(|c: char| !c.is_ascii_digit()).filter(|s| !s.is_empty()).map(|s| s.parse().unwrap()).collect()
}

/// Runs `sil-host args` through the binary's entry point in this process; its exit code.
pub fn run(args: &[&str]) -> i32 {
    let mut full = vec!["sil-host"];
    full.extend_from_slice(args);
    sil_host::run(full)
}

/// The `summary.json` of an output folder.
pub fn summary_of(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// A CSV file's lines split at commas (the header first): for tables with no quoted cells.
pub fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path).unwrap().lines().map(|l| l.split(',').map(String::from).collect()).collect()
}

/// Issue 67's short, light arm (`m` 0.02 kg, `l` 0.06 m; 535 rad/s, nine times the
/// paper's fastest mode): its `--set` assignments.
pub const SHORT_ARM: [&str; 6] = ["plant.m=0.02", "plant.l=0.06", "plant.sigma=0.0003", "plant.k=1.5", "plant.h=0.11", "plant.alpha0=0.2"];
/// A long, heavy arm (`m` 0.5 kg, `l` 0.5 m; 15.7 rad/s), its belt at the short arm's
/// `h / l`: its `--set` assignments.
pub const LONG_ARM: [&str; 6] =
    ["plant.m=0.5", "plant.l=0.5", "plant.sigma=0.02", "plant.k=1.3", "plant.h=0.9166666666666666", "plant.alpha0=0.2"];
/// The start of both arms at rest with the tip on the belt (the same `h / l`), deg and deg/s.
pub const OTHER_ARM_X0: &str = "--x0-deg=27.696865482139,0,18.573779305261,0";

/// A law crate of the workspace: a member whose Cargo.toml has a
/// `[package.metadata.painleve.law]` table (scripts/laws.py reads the same):
/// its package, the binaries of its MCU images and firmware process, and the
/// scenario it runs in (absolute).
#[derive(Debug, Clone)]
pub struct Law {
    /// The package's name.
    pub package: String,
    /// The `arm` image's binary (the flashed application).
    pub arm: String,
    /// The PIL image's binary.
    pub pil: String,
    /// The firmware process's binary (a host binary).
    pub firmware: String,
    /// Its scenario.
    pub scenario: PathBuf,
}

/// Every law crate of the workspace, found by its `[package.metadata.painleve.law]`
/// table (`cargo metadata --no-deps`), in member order; at least one (the template's).
pub fn laws() -> Vec<Law> {
    static LAWS: OnceLock<Vec<Law>> = OnceLock::new();
    LAWS.get_or_init(|| {
        let out = Command::new(env!("CARGO"))
            .args(["metadata", "--no-deps", "--format-version", "1", "--offline"])
            .current_dir(workspace())
            .output()
            .unwrap();
        assert!(out.status.success(), "cargo metadata failed:\n{}", String::from_utf8_lossy(&out.stderr));
        let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let laws: Vec<Law> = meta["packages"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|p| p["metadata"]["painleve"]["law"].is_object())
            .map(|p| {
                let t = &p["metadata"]["painleve"]["law"];
                let key = |k: &str| t[k].as_str().unwrap_or_else(|| panic!("{}: law.{k} missing", p["name"])).to_string();
                let dir = Path::new(p["manifest_path"].as_str().unwrap()).parent().unwrap().to_path_buf();
                Law {
                    package: p["name"].as_str().unwrap().to_string(),
                    scenario: dir.join(key("scenario")),
                    arm: key("arm"),
                    pil: key("pil"),
                    firmware: key("firmware"),
                }
            })
            .collect();
        assert!(!laws.is_empty(), "no member has [package.metadata.painleve.law]: the template's was removed");
        laws
    })
    .clone()
}

/// Builds the MCU images of `law` (a law of one's own, issue 70) in the
/// workspace's target folder, once per law and test binary (a no-op when
/// fresh): its PIL image for QEMU (profile `qemu`), its `arm` image as flashed
/// (profile `mcu`, what the emulated board runs); their paths.
pub fn law_images(law: &Law) -> (PathBuf, PathBuf) {
    static BUILT: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let (root, target_dir) = (workspace(), target_dir());
    let mut built = BUILT.lock().unwrap_or_else(|p| p.into_inner());
    if !built.contains(&law.package) {
        for (profile, features, bin) in
            [("qemu", ["--no-default-features", "--features", "qemu"], &law.pil), ("mcu", ["--features", "rtt", "--quiet"], &law.arm)]
        {
            let build = Command::new(env!("CARGO"))
                .args(["build", "-p", &law.package, "--profile", profile, "--target", "thumbv7em-none-eabihf", "--bin", bin])
                .args(features)
                .env("CARGO_TARGET_DIR", &target_dir)
                .current_dir(&root)
                .output()
                .unwrap();
            assert!(build.status.success(), "building {bin} failed:\n{}", String::from_utf8_lossy(&build.stderr));
        }
        built.push(law.package.clone());
    }
    let images = target_dir.join("thumbv7em-none-eabihf");
    (images.join("qemu").join(&law.pil), images.join("mcu").join(&law.arm))
}

/// The firmware process of `law` (a host binary), built with the workspace's
/// tests (`cargo test --workspace` builds every member's binaries for its own tests).
pub fn law_firmware(law: &Law) -> PathBuf {
    let exe = target_dir().join("release").join(&law.firmware);
    assert!(
        exe.is_file(),
        "{} is missing: cargo test --workspace --release builds it (or cargo build --release -p {})",
        exe.display(),
        law.package
    );
    exe
}

/// Builds `law`'s example `panicking_arm` (the `arm` image of a law that panics
/// at period 500, profile `mcu`), once per test binary; its path.
pub fn panicking_law_image(law: &Law) -> PathBuf {
    static BUILT: OnceLock<()> = OnceLock::new();
    let (root, target_dir) = (workspace(), target_dir());
    BUILT.get_or_init(|| {
        let build = Command::new(env!("CARGO"))
            .args(["build", "-p", &law.package, "--profile", "mcu", "--target", "thumbv7em-none-eabihf", "--example", "panicking_arm"])
            .env("CARGO_TARGET_DIR", &target_dir)
            .current_dir(&root)
            .output()
            .unwrap();
        assert!(build.status.success(), "building panicking_arm failed:\n{}", String::from_utf8_lossy(&build.stderr));
    });
    target_dir.join("thumbv7em-none-eabihf/mcu/examples/panicking_arm")
}

/// A board serving the bring-up protocol on a pseudo-terminal (`sil-host
/// board-twin --pty`: the twin, or with `--emulated [--elf ELF]` an image on
/// the emulated board); killed when dropped.
pub struct BoardTwin {
    /// Its process.
    pub child: Child,
    /// The twin's standard input: `weight normal N` hangs a weight on the load cell.
    pub stdin: ChildStdin,
    /// The pseudo-terminal's path.
    pub port: String,
    /// The arm's pose as the jig would hold it, degrees, `THETA1,ELBOW`.
    pub pose: String,
}

impl BoardTwin {
    /// `sil-host board-twin --pty --json --serve-for 600 ARGS`, once its port is
    /// open (its first line, after the arm has settled).
    pub fn spawn(args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .args(["board-twin", "--pty", "--json", "--serve-for", "600"])
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let stdin = child.stdin.take().unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let v: serde_json::Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line:?}"));
        let pose = v["pose_deg"].as_array().unwrap().iter().map(|d| d.as_f64().unwrap().to_string()).collect::<Vec<_>>().join(",");
        Self { child, stdin, port: v["port"].as_str().unwrap().to_string(), pose }
    }

    /// Runs `sil-host board --port PORT ARGS` against it: exit code, stdout, stderr.
    pub fn board(&self, args: &[&str]) -> (i32, String, String) {
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(["board", "--port", &self.port]).args(args).output().unwrap();
        (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
    }
}

impl Drop for BoardTwin {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
