//! End-to-end: the firmware step drives the plant in-process, sampled at 1 kHz
//! with quantised sensors and torques and a zero-order hold (the SIL issue adds
//! the iceoryx2 transport around the same loop).

use firmware::{Config, ControllerKind, Firmware, board::FrozenClock};
use plant::initial::{X0D, deg_to_state};
use plant::{Plant, SimConfig};
use shared::{
    Params,
    wire::{self, SensorFrame},
};

struct Run {
    max_abs_err_after_move: f64,
    final_z_t: f64,
    lift_offs: u64,
    min_f_n_after_settle: f64,
    max_f_n_after_settle: f64,
    safe: Option<firmware::SafeReason>,
}

/// Runs `duration` s of the default scenario: from x0d, target `target` m over 2 s, f_n* = 10 N.
fn run(cfg: Config, target: f32, duration: f64) -> Run {
    let params = Params::<f64>::paper();
    let mut plant = Plant::new(params, SimConfig::default(), deg_to_state(X0D.deg), 0.0, [0.0, 0.0]).unwrap();
    let mut fw = Firmware::new(Config { target_z_t: target, ..cfg }).unwrap();
    let ts = 1e-3;
    let delta = 0.2e-3;
    let mut u_applied = [0.0f64; 2];
    // The load cell reads the contact force of the state the firmware wakes up in.
    let mut f_prev = plant.contact_force([0.0, 0.0]);
    let mut out = Run {
        max_abs_err_after_move: 0.0,
        final_z_t: 0.0,
        lift_offs: 0,
        min_f_n_after_settle: f64::INFINITY,
        max_f_n_after_settle: 0.0,
        safe: None,
    };
    let n = (duration / ts).round() as u32;
    for k in 0..n {
        let x = plant.state();
        let frame = SensorFrame {
            t_us: k as u64 * 1000,
            seq: k,
            theta1_count: wire::encode_angle(x[0]),
            elbow_count: wire::encode_angle(x[2] - x[0]),
            f_t_code: wire::encode_force(f_prev[0]),
            f_n_code: wire::encode_force(f_prev[1]),
            belt_count: (params.v_belt * 1000.0).round() as i16,
            flags: 0,
        };
        let cmd = fw.step(shared::time::Instant::from_us(k as u64 * 1000), &frame, &FrozenClock);
        let u_new = [wire::decode_torque(cmd.u1_code) as f64, wire::decode_torque(cmd.u2_code) as f64];
        plant.advance(&plant::Hold(u_applied), delta, &mut plant::NoObserver).unwrap();
        let r = plant.advance(&plant::Hold(u_new), ts - delta, &mut plant::NoObserver).unwrap();
        u_applied = u_new;
        f_prev = r.f;
        let t = plant.time();
        if t > 2.5 {
            out.max_abs_err_after_move = out.max_abs_err_after_move.max((plant.tip()[0] - target as f64).abs());
        }
        if t > 1.0 && r.mode != shared::ContactMode::Flight {
            out.min_f_n_after_settle = out.min_f_n_after_settle.min(r.f[1]);
            out.max_f_n_after_settle = out.max_f_n_after_settle.max(r.f[1]);
        }
    }
    out.final_z_t = plant.tip()[0];
    out.lift_offs = plant.counters().lift_offs;
    out.safe = fw.safe_state();
    out
}

#[test]
fn hybrid_controller_tracks_the_default_scenario_without_lift_off() {
    let r = run(Config::default(), 0.10, 5.0);
    eprintln!(
        "hybrid: final z_t {:.5}, max err after move {:.2e}, lift-offs {}, f_n in [{:.2}, {:.2}]",
        r.final_z_t, r.max_abs_err_after_move, r.lift_offs, r.min_f_n_after_settle, r.max_f_n_after_settle
    );
    assert_eq!(r.safe, None);
    assert_eq!(r.lift_offs, 0);
    assert!(r.max_abs_err_after_move < 1e-3, "tracking error {}", r.max_abs_err_after_move);
    assert!(r.min_f_n_after_settle > 9.5 && r.max_f_n_after_settle < 10.5, "f_n near 10 N");
}

#[test]
fn pid_controller_runs_the_same_loop() {
    let cfg = Config { controller: ControllerKind::Pid, ..Config::default() };
    let r = run(cfg, -0.05, 5.0);
    eprintln!("pid: final z_t {:.5}, max err after move {:.2e}, lift-offs {}", r.final_z_t, r.max_abs_err_after_move, r.lift_offs);
    assert_eq!(r.safe, None);
    assert!(r.max_abs_err_after_move < 3e-3, "tracking error {}", r.max_abs_err_after_move);
    assert_eq!(r.lift_offs, 0);
}
