//! The Cortex-M4F image and the host library produce the same commands for the
//! recorded replay sequence: the image runs in QEMU (netduinoplus2), its defmt log
//! is decoded from the ELF's table with `defmt-decoder`, and each command is
//! compared with `Firmware::step` on the host (codes within one count of f32
//! rounding, status equal but for the deadline bit, which depends on the clock).
//!
//! Needs `qemu-system-arm` (Debian's package; `.ci/run` installs it).

use std::{path::PathBuf, process::Command};

use firmware::{Config, Firmware, board::FrozenClock};
use shared::wire::{SensorFrame, status};

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn parse_frames(bytes: &[u8]) -> Vec<SensorFrame> {
    bytes
        .chunks_exact(24)
        .map(|b| SensorFrame {
            t_us: u64::from_le_bytes(b[0..8].try_into().unwrap()),
            seq: u32::from_le_bytes(b[8..12].try_into().unwrap()),
            theta1_count: u16::from_le_bytes([b[12], b[13]]),
            elbow_count: u16::from_le_bytes([b[14], b[15]]),
            f_t_code: i16::from_le_bytes([b[16], b[17]]),
            f_n_code: i16::from_le_bytes([b[18], b[19]]),
            belt_count: i16::from_le_bytes([b[20], b[21]]),
            flags: u16::from_le_bytes([b[22], b[23]]),
        })
        .collect()
}

/// `cmd seq=.. u1=.. u2=.. status=.. ticks=..` -> (seq, u1, u2, status).
fn parse_cmd(line: &str) -> Option<(u32, i16, i16, u32)> {
    let rest = line.strip_prefix("cmd ")?;
    let mut v = rest.split(' ').map(|kv| kv.split_once('=').map(|(_, v)| v));
    let seq = v.next()??.parse().ok()?;
    let u1 = v.next()??.parse().ok()?;
    let u2 = v.next()??.parse().ok()?;
    let st = v.next()??.parse().ok()?;
    Some((seq, u1, u2, st))
}

#[test]
fn mcu_image_in_qemu_matches_the_host_library() {
    assert!(
        Command::new("qemu-system-arm").arg("--version").output().is_ok(),
        "qemu-system-arm is missing: apt-get install -y qemu-system-arm (CI installs it)"
    );
    let root = workspace();
    // Its own target folder: the outer `cargo test` holds the workspace's lock.
    let target_dir = root.join("target/mcu-test");
    let build = Command::new(env!("CARGO"))
        .args(["build", "-p", "firmware", "--profile", "mcu", "--target", "thumbv7em-none-eabihf", "--bin", "mcu"])
        .env("CARGO_TARGET_DIR", &target_dir)
        .current_dir(&root)
        .output()
        .unwrap();
    assert!(build.status.success(), "building the image failed:\n{}", String::from_utf8_lossy(&build.stderr));
    let elf_path = target_dir.join("thumbv7em-none-eabihf/mcu/mcu");
    // HARDWARE.md budgets: flash <= 64 KiB, static RAM <= 16 KiB, no heap.
    let budgets = Command::new("python3").arg(root.join("scripts/budgets.py")).arg(&elf_path).output().unwrap();
    assert!(budgets.status.success(), "over budget:\n{}", String::from_utf8_lossy(&budgets.stdout));
    let run = Command::new("bash").arg(root.join("scripts/qemu-run.sh")).arg(&elf_path).output().unwrap();
    assert!(run.status.success(), "QEMU run failed ({}): {}", run.status, String::from_utf8_lossy(&run.stderr));

    let elf = std::fs::read(&elf_path).unwrap();
    let table = defmt_decoder::Table::parse(&elf).unwrap().expect("the image has a defmt table");
    let mut decoder = table.new_stream_decoder();
    decoder.received(&run.stdout);
    let mut image_cmds = Vec::new();
    let mut done = false;
    loop {
        match decoder.decode() {
            Ok(frame) => {
                let msg = frame.display_message().to_string();
                if let Some(c) = parse_cmd(&msg) {
                    image_cmds.push(c);
                } else if msg.starts_with("done") {
                    done = true;
                }
            }
            Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
            Err(e) => panic!("corrupt defmt stream: {e}"),
        }
    }
    assert!(done, "the image logged its end");

    let frames = parse_frames(&std::fs::read(root.join("firmware/replay/frames.bin")).unwrap());
    assert_eq!(image_cmds.len(), frames.len(), "one command per replayed frame");
    let mut fw = Firmware::new(Config::default()).unwrap();
    // The host evaluates sin/cos with the platform's libm, the image with the `libm`
    // crate: last-bit differences, carried by the observer and integrator states,
    // can move a code by a few counts late in the run (see the note in the README).
    let (mut max_diff, mut exact) = (0, 0usize);
    for (frame, (seq, u1, u2, st)) in frames.iter().zip(&image_cmds) {
        let host = fw.step(frame.t_us, frame, &FrozenClock);
        assert_eq!(host.seq, *seq);
        let d = (host.u1_code as i32 - *u1 as i32).abs().max((host.u2_code as i32 - *u2 as i32).abs());
        max_diff = max_diff.max(d);
        if d == 0 {
            exact += 1;
        }
        assert!(d <= 4, "seq {seq}: image ({u1}, {u2}) vs host ({}, {})", host.u1_code, host.u2_code);
        assert_eq!(host.status & !status::DEADLINE_MISS, st & !status::DEADLINE_MISS, "seq {seq}: status");
        assert_eq!(st & status::SAFE_STATE, 0, "the replay never goes safe");
    }
    eprintln!("{} commands compared: {exact} identical, largest code difference {max_diff}", frames.len());
    assert!(exact * 10 >= frames.len() * 9, "at least 90 % identical: {exact} of {}", frames.len());
}
