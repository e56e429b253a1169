//! Records the sensor frames of a closed-loop plant run for the firmware's replay
//! board: the default scenario (hybrid law from x0d, f_n* = 10 N, target 0.10 m,
//! HARDWARE.md's sensor models with the scenario's seed) run in-process.
//!
//! Writes consecutive 24-byte little-endian `SensorFrame` records (field order of
//! `shared::wire::SensorFrame`).
//!
//! Run: `cargo run --release -p sil-host --example record_replay_frames -- [PATH] [PERIODS]`
//! (defaults `firmware/replay/frames.bin`, 500: 12 KB, which keeps the replay image
//! inside the 64 KiB flash budget).

use std::io::Write;

use shared::wire::SensorFrame;
use sil_host::sil::{in_process, scenario::Scenario};

fn to_le_bytes(f: &SensorFrame) -> [u8; 24] {
    let mut b = [0u8; 24];
    b[0..8].copy_from_slice(&f.t_us.to_le_bytes());
    b[8..12].copy_from_slice(&f.seq.to_le_bytes());
    b[12..14].copy_from_slice(&f.theta1_count.to_le_bytes());
    b[14..16].copy_from_slice(&f.elbow_count.to_le_bytes());
    b[16..18].copy_from_slice(&f.f_t_code.to_le_bytes());
    b[18..20].copy_from_slice(&f.f_n_code.to_le_bytes());
    b[20..22].copy_from_slice(&f.belt_count.to_le_bytes());
    b[22..24].copy_from_slice(&f.flags.to_le_bytes());
    b
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "firmware/replay/frames.bin".into());
    let periods: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(500);
    let mut scenario = Scenario::default_scenario();
    scenario.timing.duration_s = periods as f64 / scenario.timing.rate_hz;
    let mut bytes = Vec::with_capacity(periods as usize * 24);
    let (_, failure) = in_process::run_recording(&scenario, |_, _| true, |f| bytes.extend_from_slice(&to_le_bytes(f)));
    if let Some(e) = failure {
        return Err(e.into());
    }
    if let Some(dir) = std::path::Path::new(&path).parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::File::create(&path)?.write_all(&bytes)?;
    eprintln!("wrote {periods} frames ({} bytes) to {path}", bytes.len());
    Ok(())
}
