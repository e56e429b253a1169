//! The firmware's protection around this crate's law (issue 70): the same
//! checks as around the paper's laws, on the board twin (the `arm` image's
//! application on bus-level device models) over random admissible scenarios.
//!
//! - Every wiring fault of issue 52 is stopped within 0.1 s (100 periods at
//!   1 kHz) and before the tip strays 30 mm from the healthy arm's path, the
//!   drivers disabled. A fault of a signal the law does not read (the load
//!   cell: the impedance law reads no measured force) cannot move the arm
//!   through the law; as for the paper's PID (issue 52's rule), the tip must
//!   then stay within 30 mm of the healthy path over the whole run, stopped
//!   by the firmware's own sensor checks at any period or not at all.
//! - No false alarm: the healthy runs end without a safe state.
//!
//! `PAINLEVE_WIRING_SCENARIOS` sets how many scenarios (default 200, as for the paper's laws).

use board_link::{random_scenarios::random_admissible, twin_link::TwinLink, wiring_faults::WIRING_FAULTS};
use law_template::Impedance;
use rig::{
    law::LawTable,
    period_loop::run_loop,
    record::{PeriodRecord, RunError},
    scenario::Scenario,
    setup::RunSetup,
};

/// Random admissible scenario `i` (board-link's draw: x0 d or u, mu 0.3 to
/// 0.8, v_belt -1 to -0.1 m/s, f_n* 3 to 10 N, z_t* -0.05 to 0.14 m), `duration`
/// s, under the impedance law at its declared defaults.
fn scenario(i: u64, duration: f64) -> Scenario {
    let mut s = random_admissible(i, "hybrid", duration);
    s.law = Some(LawTable { name: "impedance".into(), params: Default::default() });
    s
}

/// Whether the impedance law leaves `fault` without an input to act on: it
/// reads no measured force ([`law_template::Impedance`]'s step).
fn unused(fault: &str) -> bool {
    fault.starts_with("load cell")
}

fn twin_run(s: &Scenario) -> (Vec<PeriodRecord>, Option<RunError>, TwinLink<Impedance>) {
    let setup = RunSetup::new(s.clone()).unwrap();
    let mut link = TwinLink::<Impedance>::for_law(&setup).unwrap();
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    (records, err, link)
}

#[test]
fn every_wiring_fault_is_stopped_within_a_tenth_of_a_second_and_30_mm_under_the_impedance_law() {
    let n: u64 = std::env::var("PAINLEVE_WIRING_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let healthy: Vec<(Scenario, Vec<PeriodRecord>)> = (0..n)
        .map(|i| {
            let s = scenario(i, 0.3);
            let (records, err, _) = twin_run(&s);
            assert!(err.is_none(), "healthy scenario {i}: {err:?}");
            (s, records)
        })
        .collect();
    for (fault, wire) in WIRING_FAULTS {
        let (mut worst_k, mut worst_stray) = (0usize, 0.0f64);
        for (i, (s, h)) in healthy.iter().enumerate() {
            let mut f = s.clone();
            wire(&mut f.board);
            let (records, err, link) = twin_run(&f);
            let stopped = match err {
                Some(RunError::SafeState { k, .. }) => Some(k),
                None => None,
                Some(other) => panic!("{fault}, scenario {i}: {other}"),
            };
            let upto = stopped.unwrap_or(records.len() - 1).min(records.len() - 1).min(h.len() - 1);
            let stray = records[..=upto].iter().zip(h).map(|(a, b)| (a.z_t - b.z_t).hypot(a.z_n - b.z_n)).fold(0.0, f64::max);
            assert!(stray < 0.030, "{fault}, scenario {i}: the tip strayed {:.1} mm (stopped at {stopped:?})", stray * 1e3);
            match stopped {
                Some(k) => {
                    assert!(k <= 100 || unused(fault), "{fault}, scenario {i}: stopped at period {k}");
                    assert!(!link.twin().drivers_enabled(), "{fault}, scenario {i}: drivers still enabled");
                    worst_k = worst_k.max(k);
                }
                None => assert!(unused(fault), "{fault}, scenario {i}: never stopped"),
            }
            worst_stray = worst_stray.max(stray);
        }
        println!("{fault}: stopped by period {worst_k} at the latest, the tip at most {:.1} mm from the healthy path", worst_stray * 1e3);
    }
}

/// The same over the envelope the validator accepts: board-link's
/// `random_envelope` draws (the rate log-uniform over 250 Hz to 10 kHz,
/// `mu_hat` up to 25 % off `mu`, `f_n*` 2 to 20 N, any belt speed and target),
/// each under the impedance law with random parameters of its declared ranges
/// (stiffnesses log-uniform over a decade about the defaults). A healthy run the
/// firmware stops is the law's own failure at that rate (its instability): it
/// must be stopped as such (`Unstable`, `Saturated`, `LiftOff`),
/// never as a wiring fault; a healthy run that ends is the baseline of every
/// wiring fault, stopped within 0.1 s and 30 mm as above.
///
/// **Fails today** (issue 70, left open): the wiring checks' rules were derived
/// for the paper's laws. Measured 2026-11-27 over the 200 draws: 63 healthy runs
/// stopped (6 as `Miswired`, 18 by the runaway limits: `Runaway`, `Overload`;
/// the rest `Unstable`), and of the 137 that ran, 155 motor reversals stopped
/// past 0.1 s, after 30 mm, or never (e.g. motor 2 reversed from x0u at 451 us,
/// `k_n` 2 341 N/m: 102 mm, stopped at period 88).
/// Run it with `cargo test --release -p law-template --test protection --
/// --ignored --nocapture`.
#[test]
#[ignore = "issue 70, open: the wiring checks do not yet hold a law of one's own to 0.1 s and 30 mm over the whole envelope"]
fn over_the_envelope_every_wiring_fault_is_stopped_and_no_healthy_run_is_called_miswired() {
    let n: u64 = std::env::var("PAINLEVE_WIRING_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let (mut healthy_runs, mut law_failures, mut late) = (0, Vec::new(), Vec::new());
    for i in 0..n {
        let (mut s, what) = board_link::random_scenarios::random_envelope(7000 + i, "hybrid", 0.3);
        let mut r = 0x9E37_79B9u64.wrapping_mul(i + 1);
        let mut draw = || {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            (r >> 11) as f64 / (1u64 << 53) as f64
        };
        let params = [
            ("k_t", 630.0 * 10f64.powf(draw())),
            ("d_t", 30.0 + 120.0 * draw()),
            ("k_n", 316.0 * 10f64.powf(draw())),
            ("d_n", 20.0 + 80.0 * draw()),
        ];
        s.law = Some(LawTable { name: "impedance".into(), params: params.iter().map(|(k, v)| ((*k).to_string(), *v)).collect() });
        let what = format!("{what}, {params:?}");
        let periods_in_a_tenth = (0.1 / s.timing.period().as_secs_f64()).ceil() as usize;
        let (h, err, _) = twin_run(&s);
        match err {
            None => healthy_runs += 1,
            Some(RunError::SafeState { reason, k, .. }) => {
                use firmware::SafeReason::*;
                if !matches!(reason, Unstable | Saturated | LiftOff) {
                    late.push(format!("healthy {what}: stopped at {k} as {reason:?}"));
                }
                law_failures.push(format!("{reason:?}"));
                continue;
            }
            Some(other) => panic!("healthy {what}: {other}"),
        }
        for (fault, wire) in WIRING_FAULTS {
            let mut f = s.clone();
            wire(&mut f.board);
            let (records, err, _) = twin_run(&f);
            let stopped = match err {
                Some(RunError::SafeState { k, .. }) => Some(k),
                None => None,
                Some(other) => panic!("{fault}, {what}: {other}"),
            };
            let upto = stopped.unwrap_or(records.len() - 1).min(records.len() - 1).min(h.len() - 1);
            let stray = records[..=upto].iter().zip(&h).map(|(a, b)| (a.z_t - b.z_t).hypot(a.z_n - b.z_n)).fold(0.0, f64::max);
            if stray >= 0.030 {
                late.push(format!("{fault}, {what}: the tip strayed {:.1} mm (stopped at {stopped:?})", stray * 1e3));
            }
            match stopped {
                Some(k) if k > periods_in_a_tenth && !unused(fault) => {
                    late.push(format!("{fault}, {what}: stopped at period {k} ({:.3} s)", k as f64 * s.timing.period().as_secs_f64()))
                }
                Some(_) => {}
                None if !unused(fault) => late.push(format!("{fault}, {what}: never stopped")),
                None => {}
            }
        }
    }
    println!("{healthy_runs} of {n} healthy runs ended; the law's own failures: {law_failures:?}");
    assert!(late.is_empty(), "{} faults stopped past 0.1 s or 30 mm:\n{}", late.len(), late.join("\n"));
    assert!(healthy_runs >= n as usize / 2, "{healthy_runs} of {n}: too few baselines to test the faults on");
}
