//! Records the sensor frames of a closed-loop plant run for the firmware's replay
//! board: the default scenario (hybrid law from x0d, f_n* = 10 N, target 0.10 m)
//! with the firmware step in-process at 1 kHz, quantised sensors and torques.
//!
//! Writes consecutive 24-byte little-endian `SensorFrame` records (field order of
//! `shared::wire::SensorFrame`).
//!
//! Run: `cargo run --release -p sil-host --example record_replay_frames -- [PATH] [PERIODS]`
//! (defaults `firmware/replay/frames.bin`, 500: 12 KB, which keeps the replay image
//! inside the 64 KiB flash budget).

use std::io::Write;

use firmware::{Config, Firmware, board::FrozenClock};
use shared::{
    Params,
    wire::{self, SensorFrame},
};
use sil_host::{
    initial::{X0D, deg_to_state},
    plant::{Plant, SimConfig},
};

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
    let params = Params::<f64>::paper();
    let mut plant = Plant::new(params, SimConfig::default(), deg_to_state(X0D.deg), 0.0, [0.0, 0.0])?;
    let mut fw = Firmware::new(Config::default()).map_err(|e| e.to_string())?;
    let (ts, delta) = (1e-3, 0.2e-3);
    let mut u_applied = [0.0f64; 2];
    let mut f_meas = plant.contact_force([0.0, 0.0]);
    let mut bytes = Vec::with_capacity(periods as usize * 24);
    for k in 0..periods {
        let x = plant.state();
        let frame = SensorFrame {
            t_us: k as u64 * 1000,
            seq: k,
            theta1_count: wire::encode_angle(x[0]),
            elbow_count: wire::encode_angle(x[2] - x[0]),
            f_t_code: wire::encode_force(f_meas[0]),
            f_n_code: wire::encode_force(f_meas[1]),
            belt_count: (params.v_belt * 1000.0).round() as i16,
            flags: 0,
        };
        bytes.extend_from_slice(&to_le_bytes(&frame));
        let cmd = fw.step(frame.t_us, &frame, &FrozenClock);
        let u_new = [wire::decode_torque(cmd.u1_code) as f64, wire::decode_torque(cmd.u2_code) as f64];
        plant.advance(u_applied, delta)?;
        f_meas = plant.advance(u_new, ts - delta)?.f;
        u_applied = u_new;
    }
    if let Some(dir) = std::path::Path::new(&path).parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::File::create(&path)?.write_all(&bytes)?;
    eprintln!("wrote {periods} frames ({} bytes) to {path}", bytes.len());
    Ok(())
}
