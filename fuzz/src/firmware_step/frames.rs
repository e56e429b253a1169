//! The frame of each step, made from the previous frame and the script's moves,
//! and which frames the firmware must refuse.

use firmware::Config;
use nalgebra::Vector2;
use shared::{
    ElbowBranch,
    kinematics::inverse_kinematics,
    wire::{self, SensorFrame, frame_flags},
};

use super::case::{Counts, EDGE_I16, EDGE_U16, SeqMove, TimeMove};

/// The frame of a step, from the previous frame and the case's moves.
pub(super) struct FrameMaker {
    pub(super) seq: u32,
    pub(super) t_us: u64,
    pub(super) z_t: f64,
    pub(super) first: bool,
}

fn edge_u16(i: u8) -> u16 {
    EDGE_U16[i as usize % EDGE_U16.len()]
}

fn edge_i16(i: u8) -> i16 {
    EDGE_I16[i as usize % EDGE_I16.len()]
}

impl FrameMaker {
    pub(super) fn frame(
        &mut self,
        cfg: &Config,
        (elbow_up, pressed): (bool, bool),
        counts: &Counts,
        flags: u16,
        seq: &SeqMove,
        t: &TimeMove,
    ) -> SensorFrame {
        let period = cfg.period.as_us();
        if self.first {
            self.first = false;
        } else {
            self.seq = match *seq {
                SeqMove::Next => self.seq.wrapping_add(1),
                SeqMove::Same => self.seq,
                SeqMove::Back(n) => self.seq.wrapping_sub(n),
                SeqMove::Skip(n) => self.seq.wrapping_add(n),
                SeqMove::Set(n) => n,
                SeqMove::NearWrap(n) => u32::MAX - u32::from(n),
            };
            self.t_us = match *t {
                TimeMove::Period => self.t_us.saturating_add(period),
                TimeMove::Back(n) => self.t_us.saturating_sub(n),
                TimeMove::Forward(n) => self.t_us.saturating_add(n),
                TimeMove::Set(n) => n,
                TimeMove::NearMax(n) => u64::MAX - u64::from(n),
            };
        }
        let bits = cfg.encoder_bits;
        let mask = (1u32 << bits) - 1;
        let (theta1_count, elbow_count, f_t_code, f_n_code, belt_count) = match *counts {
            Counts::Plausible { dz_t, dz_n, f_t, f_n, belt } => {
                let p = cfg.params;
                let (l, h) = (f64::from(p.l), f64::from(p.h));
                self.z_t = (self.z_t + f64::from(dz_t) * 1e-5).clamp(-1.9 * l, 1.9 * l);
                let z = Vector2::new(self.z_t, -h + if pressed { 0.0 } else { f64::from(dz_n) * 2e-5 });
                let branch = if elbow_up { ElbowBranch::Up } else { ElbowBranch::Down };
                let q = inverse_kinematics(l, &z, branch).map(|q| [q[0], q[1]]).unwrap_or([0.0, 0.0]);
                let f_n_n = if pressed { 30.0 } else { 10.0 + f64::from(f_n) * 0.05 };
                let f_t_n = -f64::from(p.mu) * f_n_n + f64::from(f_t) * 0.02;
                (
                    wire::encode_angle_bits(q[0], bits),
                    wire::encode_angle_bits(q[1] - q[0], bits),
                    wire::encode_force(f_t_n),
                    wire::encode_force(f_n_n),
                    // Within the belt check's 40 mm/s a period (`firmware::belt_check`): +-15 mm/s.
                    -400 + i16::from(belt) / 8,
                )
            }
            Counts::InRange { theta1, elbow, f_t, f_n, belt } => {
                ((u32::from(theta1) & mask) as u16, (u32::from(elbow) & mask) as u16, f_t, f_n, belt)
            }
            Counts::Raw { theta1, elbow, f_t, f_n, belt } => (theta1, elbow, f_t, f_n, belt),
            Counts::Edge { theta1, elbow, f_t, f_n, belt } => {
                (edge_u16(theta1), edge_u16(elbow), edge_i16(f_t), edge_i16(f_n), edge_i16(belt))
            }
        };
        SensorFrame { t_us: self.t_us, seq: self.seq, theta1_count, elbow_count, f_t_code, f_n_code, belt_count, flags }
    }
}

/// Whether the firmware must refuse the frame's counts or flags (docs/hardware.md
/// "Sensors": encoders in `[0, 2^bits)`, load cell in `[-2048, 2047]`, belt within
/// +-5 m/s, no invalid flag), written independently of `firmware::decode`.
pub fn out_of_range(frame: &SensorFrame, encoder_bits: u8) -> bool {
    let counts = 1u32 << encoder_bits;
    let load = |c: i16| !(-2048..=2047).contains(&c);
    frame.flags & frame_flags::ANY_INVALID != 0
        || u32::from(frame.theta1_count) >= counts
        || u32::from(frame.elbow_count) >= counts
        || load(frame.f_t_code)
        || load(frame.f_n_code)
        || !(-5000..=5000).contains(&frame.belt_count)
}
