//! The envelope the firmware accepts on a board (issue 66, docs/hardware.md
//! "The envelope"): no healthy arm inside it is stopped. Every random
//! scenario of the envelope (`board_link::random_scenarios::random_envelope`:
//! rates 250 Hz to 10 kHz, `mu` 0.2 to 1.0 with `mu_hat` up to 25 % off, every
//! friction term, `f_n*` 2 to 20 N, random gains of the validator's ranges)
//! runs with the protection on, and, where it stops, again with it off: a stop
//! is a false alarm unless the unprotected arm lifts off or saturates a motor
//! (the law's own failure, which the protection is right to stop).

use board_link::random_scenarios::random_envelope;
use rig::{in_process, record::RunError};
use shared::wire::status;

#[test]
fn no_healthy_arm_of_the_envelope_is_stopped_where_the_unprotected_arm_neither_lifts_off_nor_saturates() {
    let n: u64 = std::env::var("PAINLEVE_ENVELOPE_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(500);
    let (mut stops, mut runs, mut worst_error, mut worst_what) = (Vec::new(), 0usize, 0.0f64, String::new());
    for kind in ["hybrid", "pid"] {
        for i in 0..n {
            let (s, what) = random_envelope(i, kind, 2.0);
            let (records, err) = in_process::run(&s, &mut ());
            runs += 1;
            match err {
                None => {
                    if kind == "hybrid" {
                        let e = records.iter().map(|p| (p.z_t - p.z_t_ref).abs()).fold(0.0, f64::max);
                        if e > worst_error {
                            (worst_error, worst_what) = (e, what.clone());
                        }
                    }
                }
                Some(RunError::SafeState { k, reason, .. }) => {
                    let mut off = s.clone();
                    off.controller.runaway_limits = false;
                    let (free, _) = in_process::run(&off, &mut ());
                    let lifts = free.iter().any(|p| p.lift_off_true);
                    let saturates = free.iter().any(|p| p.status & (status::SATURATED_U1 | status::SATURATED_U2) != 0);
                    assert!(
                        lifts || saturates,
                        "false alarm: {what} (scenario {i}) stopped at period {k} ({reason:?}); without the protection it neither lifts off nor saturates"
                    );
                    stops.push(format!("{what}: {reason:?} at period {k} (unprotected: lifts off {lifts}, saturates {saturates})"));
                }
                Some(other) => panic!("{what} (scenario {i}): {other}"),
            }
        }
    }
    for s in &stops {
        println!("{s}");
    }
    println!(
        "{runs} runs, {} stopped, each where the unprotected arm lifts off or saturates; the hybrid law's largest |z_t - z_t*| in a completed run {:.1} mm ({worst_what})",
        stops.len(),
        worst_error * 1e3
    );
}
