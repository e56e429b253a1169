use super::*;
use crate::admissible::{belt_reach, positive_intervals};
use firmware::ControllerKind;
use firmware::{
    config::FrictionCompensation,
    law::{HybridInput, HybridState, PidState, hybrid, pid},
    reference::{Quintic, RefPoint as FwRef},
};
use nalgebra::Vector2;
use plant::initial::{X0D, X0U, deg_to_state};
use plant::{Controller, Phase};
use shared::{
    Arm, ElbowBranch, Params, SlipDirection,
    kinematics::{inverse_kinematics, jacobian},
};

fn on_belt(z_t: f64, branch: ElbowBranch, qd1: f64) -> [f64; 4] {
    let p = Params::<f64>::paper();
    let q = inverse_kinematics(p.l, &Vector2::new(z_t, -p.h), branch).unwrap();
    // A velocity tangent to the belt (z_n_dot = 0).
    let j = jacobian(p.l, &q);
    [q[0], qd1, q[1], -j[(1, 0)] * qd1 / j[(1, 1)]]
}

fn fw_ref(r: &Quintic, t: f64) -> FwRef {
    r.at(t as f32)
}

#[test]
fn reference_mirrors_the_firmware_quintic() {
    let fw = Quintic::new(-0.1624, 0.12, 2.0);
    let ours = Reference { start: -0.1624, target: 0.12, duration: 2.0 };
    for i in -5..=300 {
        let t = i as f64 * 0.01;
        let (a, b) = (ours.at(t), fw.at(t as f32));
        assert!((a.pos - f64::from(b.pos)).abs() < 1e-6, "t {t}: {a:?} vs {b:?}");
        assert!((a.vel - f64::from(b.vel)).abs() < 1e-5, "t {t}");
        assert!((a.acc - f64::from(b.acc)).abs() < 1e-4, "t {t}");
    }
    assert_eq!(ours.at(2.0), RefPoint { pos: 0.12, vel: 0.0, acc: 0.0 });
}

/// Same state, same reference, same integral: the ideal PID and the firmware's
/// sampled PID (f32, zero period so its integral does not move) give the same torque.
#[test]
fn ideal_and_firmware_pid_agree_at_the_same_state() {
    let params = Params::<f64>::paper();
    let cfg = firmware::Config::default();
    let arm32 = Arm::new(cfg.params);
    let fw_q = Quintic::new(-0.16, 0.1, 2.0);
    let reference = Reference { start: -0.16, target: 0.1, duration: 2.0 };
    let mut checked = 0;
    for (i, branch) in [ElbowBranch::Down, ElbowBranch::Up].into_iter().enumerate() {
        let ideal = IdealPid::paper(params, branch, reference);
        for k in 0..20 {
            let z_t = -0.15 + 0.014 * k as f64;
            let x = on_belt(z_t, branch, 0.7 - 0.07 * k as f64);
            let t = 0.13 * k as f64 + 0.05 * i as f64;
            let integral = [0.002 * (k as f64 - 10.0), 0.001];
            let (u, e) = ideal.evaluate(t, &x, &integral).unwrap();
            let mut st = PidState { integral: [integral[0] as f32, integral[1] as f32] };
            let q = Vector2::new(x[0] as f32, x[2] as f32);
            let qd = Vector2::new(x[1] as f32, x[3] as f32);
            let u_fw = pid(&arm32, &cfg.pid, branch, &fw_ref(&fw_q, t), q, qd, &mut st, 0.0, 1e9).unwrap();
            for j in 0..2 {
                let tol = 2e-3 + 1e-4 * u[j].abs();
                assert!((f64::from(u_fw[j]) - u[j]).abs() < tol, "{branch:?} k {k} joint {j}: firmware {} vs ideal {}", u_fw[j], u[j]);
            }
            // The integrand is the error of q' = [theta1, theta2 - theta1].
            let q_ref = inverse_kinematics(params.l, &Vector2::new(reference.at(t).pos, -params.h), branch).unwrap();
            assert!((e[0] - (q_ref[0] - x[0])).abs() < 1e-12 && (e[1] - (q_ref[1] - q_ref[0] - (x[2] - x[0]))).abs() < 1e-12);
            checked += 1;
        }
    }
    assert_eq!(checked, 40);
}

/// Same state and integral, in sliding: the ideal hybrid law and the firmware's
/// (f32, friction term `-mu_hat s a_f`, exact in sliding) give the same torque.
#[test]
fn ideal_and_firmware_hybrid_agree_at_the_same_state() {
    let params = Params::<f64>::paper();
    let cfg = firmware::Config::default();
    let arm32 = Arm::new(cfg.params);
    let fw_q = Quintic::new(-0.16, 0.1, 2.0);
    let reference = Reference { start: -0.16, target: 0.1, duration: 2.0 };
    let ideal = IdealHybrid::paper(params, reference, 10.0, 650.0);
    for branch in [ElbowBranch::Down, ElbowBranch::Up] {
        for k in 0..20 {
            let z_t = -0.15 + 0.014 * k as f64;
            let x = on_belt(z_t, branch, 1.2 - 0.13 * k as f64);
            let t = 0.11 * k as f64;
            let integral = 1e-3 * (k as f64 - 10.0) / 10.0;
            let z_dot = jacobian(params.l, &Vector2::new(x[0], x[2])) * Vector2::new(x[1], x[3]);
            let dir = SlipDirection::of(z_dot[0] - params.v_belt);
            let out = ideal.evaluate(Phase::Sliding(dir), t, &x, &[integral, 0.0]).unwrap();
            let input = HybridInput {
                q: Vector2::new(x[0] as f32, x[2] as f32),
                qd: Vector2::new(x[1] as f32, x[3] as f32),
                f_t: out.f[0] as f32,
                f_n: out.f[1] as f32,
                v_belt: params.v_belt as f32,
            };
            let mut st = HybridState { force_integral: integral as f32, ..HybridState::default() };
            let (u_fw, sig) = hybrid(
                &arm32,
                &cfg.hybrid,
                FrictionCompensation::ModelCommandedNormal,
                &fw_ref(&fw_q, t),
                10.0,
                &input,
                &mut st,
                0.0,
                false,
            )
            .unwrap();
            assert!((f64::from(sig.a_f) - out.a_f).abs() < 1e-4 * out.a_f.abs().max(1.0));
            assert!((f64::from(sig.a_v) - out.a_v).abs() < 1e-3 * out.a_v.abs().max(1.0), "a_v {} vs {}", sig.a_v, out.a_v);
            for (j, (fw, id)) in u_fw.iter().zip(out.motor).enumerate() {
                let tol = 1e-3 + 1e-3 * id.abs();
                assert!((f64::from(*fw) - id).abs() < tol, "{branch:?} k {k} joint {j}: {fw} vs {id}");
            }
            // The law's force (the fixed point [-mu s a_f, a_f], module docs) is the
            // plant model's sliding force -b/p under the law's own torque.
            let q = Vector2::new(x[0], x[2]);
            let td = ideal.arm.tip_dynamics(&q, &Vector2::new(x[1], x[3]), &Arm::generalised_torque(&Vector2::from(out.motor)));
            if td.p(params.mu, dir) > 0.05 * td.qmat[(1, 1)] {
                let f = shared::contact::sliding_force(&td, params.mu, dir);
                assert!((f[1] - out.f[1]).abs() < 1e-8 * out.a_f.abs().max(1.0), "f_n {} vs {}", f[1], out.f[1]);
                assert!((f[0] - out.f[0]).abs() < 1e-8 * out.a_f.abs().max(1.0));
            }
        }
    }
}

/// In sliding the ideal hybrid law drives f_n to f_n* and z_t along z_t*(t) to the
/// target (paper eqs. 9 to 11): here exactly, up to the integrator's tolerance.
#[test]
fn ideal_hybrid_slides_to_the_target_with_f_n_at_its_reference() {
    for (x0, ki) in [(X0D, 650.0), (X0U, 0.0)] {
        let mut setup = IdealSetup::paper(ControllerKind::Hybrid, deg_to_state(x0.deg), 0.05);
        setup.duration_s = 3.0;
        assert_eq!(setup.hybrid_ki, ki);
        let run = simulate(&setup, |_| {}).unwrap();
        assert!(run.error.is_none() && run.law_fault.is_none(), "{:?} {:?}", run.error, run.law_fault);
        assert!(run.no_lift_off(), "{}: {} lift-offs", x0.name, run.lift_offs);
        for s in &run.samples {
            assert_eq!(s.mode, "sliding", "{} at t {}", x0.name, s.t);
            assert!((s.f_n - 10.0).abs() < 1e-4, "{} t {}: f_n {}", x0.name, s.t, s.f_n);
            assert!((s.z_t - s.z_t_ref).abs() < 1e-6, "{} t {}: z_t {} vs {}", x0.name, s.t, s.z_t, s.z_t_ref);
        }
        let last = run.samples.last().unwrap();
        assert!((last.t - 3.0).abs() < 1e-9);
        assert!((last.z_t - 0.05).abs() < 1e-6);
    }
}

/// The ideal hybrid law keeps the tip on the belt exactly while `p > 0` (module
/// docs), so driven past the end of the admissible range (paper Table II; found here
/// independently by the admissible command's scan of `p` on the belt) it lifts off
/// where that range ends.
#[test]
fn ideal_hybrid_lifts_off_where_p_vanishes() {
    let params = Params::<f64>::paper();
    let arm = Arm::new(params);
    for (x0, branch) in [(X0D, ElbowBranch::Down), (X0U, ElbowBranch::Up)] {
        let reach = belt_reach(&params);
        let ends =
            positive_intervals(|z| crate::admissible::p_on_belt(&arm, z, branch, SlipDirection::Positive), -reach, reach, 20_000, 1e-10);
        let end = ends.last().unwrap().hi;
        let mut setup = IdealSetup::paper(ControllerKind::Hybrid, deg_to_state(x0.deg), (reach - 5e-4).min(end + 0.01));
        setup.duration_s = 2.5;
        setup.stop_at_lift_off = true;
        let run = simulate(&setup, |_| {}).unwrap();
        let t_lift = run.first_lift_off_s.expect("lifts off past the admissible range");
        let at = run.samples.iter().rev().find(|s| s.t <= t_lift).unwrap();
        // The tip moves at most ~0.25 m/s: within a 1 ms sample it moves < 0.3 mm.
        assert!((at.z_t - end).abs() < 3e-4, "{}: lift-off at z_t {} (t {t_lift}), p = 0 at {end}", x0.name, at.z_t);
    }
}

#[test]
fn singular_and_unreachable_give_errors_and_zero_torque_not_panics() {
    let params = Params::<f64>::paper();
    let reference = Reference { start: 0.0, target: 0.0, duration: 1.0 };
    let hybrid = IdealHybrid::paper(params, reference, 10.0, 650.0);
    let straight = [0.3, 0.1, 0.3, -0.2];
    let e = hybrid.evaluate(Phase::Sliding(SlipDirection::Positive), 0.5, &straight, &[0.0; 2]).unwrap_err();
    assert_eq!(e, LawFault::Singular { t: 0.5 });
    let mut xi_dot = [1.0; 2];
    assert_eq!(hybrid.torque(0.5, &straight, &[0.0; 2], &mut xi_dot), [0.0; 2]);
    assert_eq!(xi_dot, [0.0; 2]);
    assert_eq!(hybrid.fault(), Some(LawFault::Singular { t: 0.5 }));
    // NaN state: an error, not a panic.
    assert!(hybrid.evaluate(Phase::Flight, 0.0, &[f64::NAN, 0.0, 0.2, 0.0], &[0.0; 2]).is_err());
    // PID with its reference out of reach.
    let far = Reference { start: 0.0, target: 0.3, duration: 1.0 };
    let pid = IdealPid::paper(params, ElbowBranch::Down, far);
    assert!(matches!(pid.evaluate(2.0, &on_belt(0.0, ElbowBranch::Down, 0.0), &[0.0; 2]), Err(LawFault::Unreachable { .. })));
    // A set-up with an unreachable target is bad input.
    let e = build(&IdealSetup::paper(ControllerKind::Pid, deg_to_state(X0D.deg), 0.3)).unwrap_err();
    assert!(e.is_bad_input(), "{e}");
}

/// The torque law without the plant's phase (the `torque` path) sees a tip on the
/// belt as sliding, and gives the same torque as with the phase.
#[test]
fn hybrid_phase_from_geometry_matches_the_plant() {
    let setup = IdealSetup::paper(ControllerKind::Hybrid, deg_to_state(X0D.deg), 0.0);
    let (mut plant, law) = build(&setup).unwrap();
    plant.advance(&law, 0.5, &mut plant::NoObserver).unwrap();
    let IdealLaw::Hybrid(h) = &law else { unreachable!() };
    assert_eq!(h.phase_from_geometry(&plant.state()), plant.phase());
    let xi = plant.controller_state();
    let a = h.torque(plant.time(), &plant.state(), &xi, &mut [0.0; 2]);
    let b = h.torque_in(plant.phase(), plant.time(), &plant.state(), &xi, &mut [0.0; 2]);
    assert_eq!(a, b);
    // The law's own force is the plant's contact force.
    let out = h.evaluate(plant.phase(), plant.time(), &plant.state(), &xi).unwrap();
    let f = plant.contact_force_with(&law);
    assert!((out.f[1] - f[1]).abs() < 1e-6 && (out.f[0] - f[0]).abs() < 1e-6, "{:?} vs {f:?}", out.f);
}
