//! One firmware step per controller on the host (issue 3's speed figure; the
//! Cortex-M4F instruction budget is measured in QEMU by the timing issue).
//!
//! Run: `cargo bench -p firmware --bench step`.

use criterion::{Criterion, criterion_group, criterion_main};
use firmware::{Config, ControllerKind, Firmware, board::FrozenClock};
use nalgebra::Vector2;
use shared::{
    ElbowBranch,
    kinematics::inverse_kinematics,
    wire::{self, SensorFrame},
};

fn frames() -> Vec<SensorFrame> {
    // A tip sliding slowly along the belt, elbow down.
    (0..1000u32)
        .map(|k| {
            let z_t = -0.16 + 1e-4 * k as f64;
            let q = inverse_kinematics(0.21, &Vector2::new(z_t, -0.3775), ElbowBranch::Down).unwrap();
            SensorFrame {
                t_us: k as u64 * 1000,
                seq: k,
                theta1_count: wire::encode_angle(q[0]),
                elbow_count: wire::encode_angle(q[1] - q[0]),
                f_t_code: wire::encode_force(-6.0),
                f_n_code: wire::encode_force(10.0),
                belt_count: -400,
                flags: 0,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let frames = frames();
    for (name, kind) in [("step_hybrid", ControllerKind::Hybrid), ("step_pid", ControllerKind::Pid)] {
        let cfg = Config { controller: kind, ..Config::default() };
        c.bench_function(name, |b| {
            let mut fw = Firmware::new(cfg).unwrap();
            let mut k = 0usize;
            b.iter(|| {
                if k == frames.len() {
                    fw.reset();
                    k = 0;
                }
                let f = &frames[k];
                k += 1;
                fw.step(f.sampled_at(), f, &FrozenClock)
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
