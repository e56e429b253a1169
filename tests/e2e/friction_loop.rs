//! The discrete algebraic loop through the contact when the hybrid law compensates
//! friction with a one-period-old measurement (firmware `FrictionCompensation`):
//! `f_n(k) = g f_n(k-1) + const` with `g = -mu s Q_21 / p`, unstable when
//! `p < Q_22 / 2`. The loop is closed here through the plant's own (f64) contact
//! model at a fixed sliding state, an independent path from the analysis.

use firmware::{
    config::{Config, FrictionCompensation},
    law::{self, HybridInput, HybridState},
    reference::RefPoint,
};
use nalgebra::Vector2;
use shared::{Arm, ElbowBranch, Params, SlipDirection, contact::sliding_force, kinematics::inverse_kinematics};

/// Iterates the loop at the sliding state with the tip at `z_t` (elbow down, at rest,
/// belt at -0.4 m/s so z_r_dot > 0); returns (f_n sequence, p/Q_22).
fn iterate(z_t: f64, comp: FrictionCompensation, steps: usize) -> (Vec<f64>, f64) {
    let params = Params::<f64>::paper();
    let plant = Arm::new(params);
    let cfg = Config::default();
    let law_arm = Arm::new(cfg.params);
    let q = inverse_kinematics(params.l, &Vector2::new(z_t, -params.h), ElbowBranch::Down).unwrap();
    let qd = Vector2::zeros();
    let dir = SlipDirection::Positive;
    let td0 = plant.tip_dynamics(&q, &qd, &Vector2::zeros());
    let ratio = td0.p(params.mu, dir) / td0.qmat[(1, 1)];
    let reference = RefPoint { pos: z_t as f32, vel: 0.0, acc: 0.0, moving: false };
    // Start from a slightly wrong measurement.
    let (mut f_t, mut f_n) = (-0.6 * 9.0, 9.0);
    let mut seq = Vec::new();
    for _ in 0..steps {
        let input = HybridInput { q: q.cast(), qd: qd.cast(), f_t: f_t as f32, f_n: f_n as f32, v_belt: -0.4 };
        let mut st = HybridState::default(); // no integral action: isolate the algebraic loop
        let gains = firmware::config::HybridGains { ki: 0.0, ..cfg.hybrid };
        let (motor, _) = law::hybrid(&law_arm, &gains, comp, &reference, 10.0, &input, &mut st, 1e-3, false).unwrap();
        let u = Arm::generalised_torque(&Vector2::new(motor[0] as f64, motor[1] as f64));
        let f = sliding_force(&plant.tip_dynamics(&q, &qd, &u), params.mu, dir);
        (f_t, f_n) = (f[0], f[1]);
        seq.push(f_n);
    }
    (seq, ratio)
}

#[test]
fn measured_friction_term_flips_the_normal_force_where_p_is_below_half_q22() {
    let mut seen_unstable = false;
    let mut seen_stable = false;
    for i in 0..40 {
        let z_t = -0.15 + i as f64 * 0.0079;
        let (seq, ratio) = iterate(z_t, FrictionCompensation::Measured, 12);
        if ratio <= 0.0 {
            continue; // not a sliding state
        }
        // Early differences (later ones reach the f32 resolution of the law).
        let d: Vec<f64> = seq.windows(2).map(|w| w[1] - w[0]).collect();
        let growth = d[2] / d[1];
        // The predicted loop gain g = -mu s Q_21 / p = (p/Q_22 - 1) / (p/Q_22).
        let g = (ratio - 1.0) / ratio;
        assert!((growth - g).abs() < 0.02 * g.abs().max(1.0), "z_t {z_t}: growth {growth} vs predicted {g}");
        if ratio < 0.45 {
            assert!(growth < -1.0, "z_t {z_t}: p/Q22 = {ratio:.3}, g = {growth:.3}: the normal force should flip and grow");
            seen_unstable = true;
        } else if ratio > 0.55 {
            assert!(growth.abs() < 1.0, "z_t {z_t}: p/Q22 = {ratio:.3}, g = {growth:.3}: should settle");
            seen_stable = true;
        }
    }
    assert!(seen_unstable && seen_stable, "the belt covers both regimes");
}

#[test]
fn commanded_normal_friction_term_gives_f_n_equal_a_f_at_once() {
    for i in 0..40 {
        let z_t = -0.15 + i as f64 * 0.0079;
        let (seq, ratio) = iterate(z_t, FrictionCompensation::ModelCommandedNormal, 3);
        if ratio <= 0.02 {
            continue;
        }
        for f_n in seq {
            assert!((f_n - 10.0).abs() < 1e-3 * 10.0 / ratio, "z_t {z_t}: f_n {f_n}, p/Q22 {ratio}");
        }
    }
}

/// With the force integrator (`K'_I = 650`) and the measured normal force one
/// period old, the normal force converges to `f_n*` (paper eq. 11), at every
/// sliding state on the belt.
#[test]
fn normal_force_converges_to_the_reference_with_the_integrator() {
    let params = Params::<f64>::paper();
    let plant = Arm::new(params);
    let cfg = Config::default();
    let law_arm = Arm::new(cfg.params);
    for i in 0..30 {
        let z_t = -0.15 + i as f64 * 0.01;
        let q = inverse_kinematics(params.l, &Vector2::new(z_t, -params.h), ElbowBranch::Down).unwrap();
        let qd = Vector2::zeros();
        let td0 = plant.tip_dynamics(&q, &qd, &Vector2::zeros());
        if td0.p(params.mu, SlipDirection::Positive) <= 0.0 {
            continue;
        }
        let reference = RefPoint { pos: z_t as f32, vel: 0.0, acc: 0.0, moving: false };
        let mut st = HybridState::default();
        let mut f_n = 4.0;
        for _ in 0..200 {
            let input = HybridInput { q: q.cast(), qd: qd.cast(), f_t: 0.0, f_n: f_n as f32, v_belt: -0.4 };
            let (motor, _) = law::hybrid(
                &law_arm,
                &cfg.hybrid,
                FrictionCompensation::ModelCommandedNormal,
                &reference,
                10.0,
                &input,
                &mut st,
                1e-3,
                false,
            )
            .unwrap();
            let u = Arm::generalised_torque(&Vector2::new(motor[0] as f64, motor[1] as f64));
            f_n = sliding_force(&plant.tip_dynamics(&q, &qd, &u), params.mu, SlipDirection::Positive)[1];
        }
        assert!((f_n - 10.0).abs() < 1e-3, "z_t {z_t}: f_n = {f_n} after 0.2 s");
    }
}
