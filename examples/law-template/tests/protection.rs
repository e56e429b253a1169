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
//! - Over the whole envelope the firmware accepts and the law's parameter
//!   ranges, every fault class of the FMEA (docs/hardware.md) keeps its
//!   promise, and no healthy arm is stopped where, unprotected, it neither
//!   lifts off nor saturates (the second test; `board_link::fmea`).
//!
//! `PAINLEVE_WIRING_SCENARIOS` sets how many scenarios the first test takes
//! (default 200, as for the paper's laws), `PAINLEVE_FMEA_NEW_SCENARIOS` how
//! many of them issue 80's classes take (default 50), `PAINLEVE_FMEA_SCENARIOS` the
//! second's healthy runs (default 200). Copy this file with the crate: it is
//! the gate a law of one's own passes before it runs on a board.

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

/// Random parameters of the impedance law for envelope scenario `i`, within
/// its declared ranges ([`Impedance`]'s `SPEC`): the stiffnesses log-uniform
/// over a decade about the defaults (`k_t` 630 to 6 300 N/m, `k_n` 316 to
/// 3 160 N/m), the dampings uniform (`d_t` 30 to 150, `d_n` 20 to 100 N s/m).
/// Returns the `[law]` table and a line that says what it is.
fn random_impedance(i: u64) -> (LawTable, String) {
    let mut r = board_link::random_scenarios::Uniform::new(0x1A77_0000 ^ (i * 7919 + 3));
    let params = [
        ("k_t", 630.0 * 10f64.powf(r.draw())),
        ("d_t", 30.0 + 120.0 * r.draw()),
        ("k_n", 316.0 * 10f64.powf(r.draw())),
        ("d_n", 20.0 + 80.0 * r.draw()),
    ];
    let what = params.iter().map(|(k, v)| format!("{k} {v:.0}")).collect::<Vec<_>>().join(", ");
    (LawTable { name: "impedance".into(), params: params.iter().map(|(k, v)| ((*k).to_string(), *v)).collect() }, what)
}

/// The FMEA (issue 66's promise, `board_link::fmea`) under the impedance law
/// over the envelope the validator accepts: board-link's `random_envelope`
/// draws (the rate log-uniform over 250 Hz to 10 kHz, `mu_hat` up to 25 % off
/// `mu`, `f_n*` 2 to 20 N, any belt speed and target), each with random
/// parameters of the law ([`random_impedance`]).
///
/// - **No false alarm**: a healthy run the firmware stops is one where the
///   same arm, unprotected, lifts off or saturates a motor (issue 66's
///   criterion: the law's own failure at that rate and those gains, which the
///   protection is right to stop). Half the draws are (stiff springs at a slow
///   rate chatter; soft ones beyond the law's `Z_t,sliding` lift off).
/// - **Every fault class of the FMEA keeps the promise** in every one of the
///   first `PAINLEVE_FMEA_SCENARIOS` (default 200) healthy runs: the safe
///   state before the tip strays 30 mm from the healthy path (issue 66's
///   classes: no open rows, unlike the paper's laws; issue 80's: [`OPEN`]).
///
/// Before the law declared `on_belt` (issue 70), 13 of 50 `motor 2 reversed`
/// runs from `x0u` strayed 42 to 91 mm: the wiring check alone saw the elbow
/// thrown off the belt 13 to 26 ms late. `--nocapture` prints the table.
#[test]
fn over_the_envelope_no_healthy_arm_is_stopped_falsely_and_every_fmea_class_keeps_its_promise() {
    use board_link::fmea::{DURATION_S, Healthy, classes, line, twin_run, unprotected};
    let n: usize = std::env::var("PAINLEVE_FMEA_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let (mut stopped, mut false_alarms) = (0usize, Vec::new());
    let healthy: Vec<Healthy> = (0..20 * n as u64)
        .filter_map(|i| {
            let (mut scenario, what) = board_link::random_scenarios::random_envelope(20_000 + i, "hybrid", DURATION_S);
            let (law, params) = random_impedance(i);
            scenario.law = Some(law);
            let what = format!("{what}, impedance {params}");
            let (records, e) = twin_run::<Impedance>(&scenario);
            match e {
                None => Some(Healthy { scenario, what, records }),
                Some(RunError::SafeState { k, reason, .. }) => {
                    stopped += 1;
                    let (lifts, saturates) = unprotected::<Impedance>(&scenario);
                    if !(lifts || saturates) {
                        false_alarms.push(format!("{what}: {reason:?} at period {k}; unprotected it neither lifts off nor saturates"));
                    }
                    None
                }
                Some(other) => panic!("{what}: {other}"),
            }
        })
        .take(n)
        .collect();
    assert!(false_alarms.is_empty(), "false alarms:\n{}", false_alarms.join("\n"));
    assert_eq!(healthy.len(), n, "too few healthy runs of the envelope");
    println!("{stopped} healthy draws stopped, each where the unprotected arm lifts off or saturates; {n} ran to their end");
    let threads = std::thread::available_parallelism().map_or(2, |p| p.get()).min(4);
    let only = std::env::var("PAINLEVE_FMEA_CLASS").unwrap_or_default();
    // Issue 66's classes over every healthy run, issue 80's over the first
    // `PAINLEVE_FMEA_NEW_SCENARIOS` (50 by default: CI's time; `board_link::fmea::ISSUE_66_CLASSES`).
    let n_new: usize = std::env::var("PAINLEVE_FMEA_NEW_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(50).min(n);
    let all = classes();
    let measured = board_link::fmea::rows_split::<Impedance>(&all, &only, &healthy, n_new, threads);
    let mut broken = Vec::new();
    for (class, row) in measured {
        println!("{}", line("impedance", class, &row));
        let allowed = OPEN.iter().find(|(c, _)| *c == class.name()).map_or(0, |o| o.1);
        if row.broken.len() > allowed {
            broken.extend(row.broken.iter().map(|b| format!("{}: {b}", class.name())));
        } else {
            for b in &row.broken {
                println!("    open, {} ({} of at most {allowed}): {b}", class.name(), row.broken.len());
            }
        }
    }
    assert!(
        broken.is_empty(),
        "runs strayed 30 mm from the healthy run before the safe state, more than the open rows allow (OPEN):\n{}",
        broken.join("\n")
    );
}

/// The rows that do not keep the promise yet under the impedance law
/// (docs/hardware.md "FMEA", issue 80's rows marked **open**): class, and how
/// many of the 200 runs strayed 30 mm before the safe state, as measured. The
/// test holds each to that count: a detector that gets worse fails it, one
/// that gets better passes, and the count here and in the docs comes down.
/// Issue 66's classes from their own onsets have none; measured after issue
/// 80's belt check and 2 ms lift-off (12 rows and 38 runs before them).
const OPEN: [(&str, usize); 1] = [("motor 2 reversed, mid-run", 7)];
