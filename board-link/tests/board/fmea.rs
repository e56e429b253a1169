//! The FMEA (issue 66, docs/hardware.md "FMEA"): every fault class of the
//! table, under both laws, over random scenarios of the envelope
//! (`random_envelope`: rates 250 Hz to 10 kHz, `mu_hat` up to 25 % off, every
//! friction term, the paper's or random gains of both laws), on the twin.
//!
//! **The promise, per run:** the safe state within 0.1 s of the fault and
//! before the tip strays 30 mm from the healthy run at the same period, or a
//! fault that never moves the tip 30 mm. Both halves end in the same
//! measurable property, the stray under 30 mm; the first is what the
//! detectors are for, and the test reports, per class, how many runs each half
//! keeps.
//!
//! **The stray** is the tip's largest distance from the healthy run (same
//! scenario, same period), from the fault's onset up to the safe state, and
//! only while the healthy arm is on the belt: where the healthy arm itself
//! lifts off (the PID from `x0u`, the paper's failure, flies up to 0.12 m
//! above the belt within 10 ms), there is no controlled path left to stray
//! from. The healthy runs are those of the envelope that end without a stop
//! (a stopped healthy run has no path to compare).
//!
//! The rows in [`OPEN`] do not keep the promise in every run yet: each is held
//! to the count measured.
//!
//! `PAINLEVE_FMEA_SCENARIOS` sets the scenarios per class and law (default
//! 200), `PAINLEVE_FMEA_NEW_SCENARIOS` how many of them issue 80's classes take
//! (default 50: CI's time, `board_link::fmea::ISSUE_66_CLASSES`; their open
//! counts were measured over 200 and bound the count over the first 50),
//! `PAINLEVE_FMEA_CLASS` keeps the classes whose name contains it;
//! `--nocapture` prints the table's measured columns.

use board_link::{
    fmea::{Class, DURATION_S, Healthy, classes, line, rows_split, twin_run},
    random_scenarios::random_envelope,
};
use firmware::PaperLaws;

/// When a scenario entry's fault starts, s (the library's onset, `fmea::AT_S`).
const AT_S: f64 = board_link::fmea::AT_S;

/// The rows that do not keep the promise yet (docs/hardware.md "FMEA", the rows
/// marked **open**): law, class, and how many of the 200 runs strayed 30 mm
/// before the safe state, as measured. The test holds each to that count (a
/// detector that gets worse fails it; one that gets better passes, and the
/// count here and in the docs comes down).
///
/// Issue 80's rows (the faults of a real arm, and every class from mid-run)
/// follow issue 66's five, as measured after issue 80's belt check and 2 ms lift-off: the causes
/// and the detectors that would close them are in docs/hardware.md "FMEA".
const OPEN: [(&str, &str, usize); 16] = [
    ("hybrid", "elbow encoder offset +3 deg", 6),
    ("hybrid", "theta1 encoder stuck", 1),
    ("hybrid", "elbow encoder stuck", 2),
    ("hybrid", "load cell tangential axis stuck", 1),
    ("pid", "load cell normal axis dead", 1),
    ("hybrid", "load cell tangential offset drifts", 2),
    ("hybrid", "load cell normal offset drifts", 2),
    ("hybrid", "belt sensor gain x0.5", 1),
    ("hybrid", "motor 1 weak (30 %), mid-run", 1),
    ("hybrid", "theta1 encoder stuck, mid-run", 1),
    ("hybrid", "elbow encoder stuck, mid-run", 1),
    ("hybrid", "load cell normal gain x0.5, mid-run", 1),
    ("hybrid", "load cell normal gain x2, mid-run", 1),
    ("hybrid", "load cell normal axis stuck, mid-run", 1),
    ("hybrid", "load cell tangential axis stuck, mid-run", 1),
    ("hybrid", "load cell tangential offset drifts, mid-run", 2),
];

#[test]
fn every_fault_class_is_stopped_within_100_ms_and_30_mm_or_never_moves_the_tip_30_mm() {
    let n: usize = std::env::var("PAINLEVE_FMEA_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let n_new: usize = std::env::var("PAINLEVE_FMEA_NEW_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(50).min(n);
    let only = std::env::var("PAINLEVE_FMEA_CLASS").unwrap_or_default();
    let all = classes();
    let threads = std::thread::available_parallelism().map_or(2, |p| p.get()).min(4);
    let mut broken = Vec::new();
    for kind in ["hybrid", "pid"] {
        let healthy: Vec<Healthy> = (0..20 * n as u64)
            .filter_map(|i| {
                let (scenario, what) = random_envelope(20_000 + i, kind, DURATION_S);
                let (records, e) = twin_run::<PaperLaws>(&scenario);
                e.is_none().then_some(Healthy { scenario, what, records })
            })
            .take(n)
            .collect();
        assert_eq!(healthy.len(), n, "{kind}: too few healthy runs of the envelope");
        let measured = rows_split::<PaperLaws>(&all, &only, &healthy, n_new, threads);
        for (class, row) in measured {
            println!("{}", line(kind, class, &row));
            let allowed = OPEN.iter().find(|(k, c, _)| *k == kind && *c == class.name()).map_or(0, |o| o.2);
            if row.broken.len() > allowed {
                broken.extend(row.broken.iter().map(|b| format!("{kind}, {}: {b}", class.name())));
            } else {
                for b in &row.broken {
                    println!("    open, {kind}, {} ({} of at most {allowed}): {b}", class.name(), row.broken.len());
                }
            }
        }
    }
    assert!(
        broken.is_empty(),
        "runs strayed 30 mm from the healthy run before the safe state, more than the open rows allow (OPEN):\n{}",
        broken.join("\n")
    );
}

/// How long each run of the flashed image's sample lasts, s: a board's fault
/// acts from the start, and 0.2 s show it; a scenario's fault starts at
/// [`AT_S`], and its run goes on 0.15 s past it (the promise's 0.1 s and the
/// slowest stop of those classes' caught runs).
/// A drawn fault from its own onset goes on as long past it; one from mid-run
/// has its onset drawn in a run of 0.3 s.
fn image_sample_s(class: &Class) -> f64 {
    match class {
        Class::Entry(..) => AT_S + 0.15,
        Class::Drawn(_, at, _) => (at + 0.15).max(0.2),
        Class::MidRun(..) => 0.3,
        Class::Reseed(_) | Class::Board(..) => 0.2,
    }
}

#[test]
fn a_sample_of_the_fmea_on_the_flashed_image_is_the_twins_run_bit_for_bit() {
    // Issue 66, "a sample on the flashed image, byte for byte": every class under
    // each law on one healthy scenario of the envelope (a different one per
    // class, rates 250 Hz to 10 kHz among them), the unmodified `arm` ELF on the
    // emulated board against the twin: every record the same, and the same stop,
    // so the twin's measurement above holds for the bytes that are flashed.
    let image = board_link::emulator_link::default_image();
    assert!(image.exists(), "{} is missing: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let classes = classes();
    let periods: Vec<u64> = std::thread::scope(|scope| {
        let laws = ["hybrid", "pid"].map(|kind| {
            let (classes, image) = (&classes, &image);
            scope.spawn(move || {
                let healthy: Vec<_> = (0..400u64)
                    .map(|i| random_envelope(20_000 + i, kind, DURATION_S))
                    .filter(|(s, _)| twin_run::<PaperLaws>(s).1.is_none())
                    .take(classes.len() + 20)
                    .collect();
                // The emulated belt encoder makes at most 1 066 quadrature edges a
                // tick (board-emulator's TIM4 model): a belt read at twice its speed
                // takes a belt within 0.4 m/s (the counted mode's), the next such
                // healthy scenario.
                let fits = |class: &Class, s: &rig::scenario::Scenario| !class.name().contains("gain x2") || s.plant.v_belt.abs() <= 0.4;
                let mut periods = Vec::new();
                for (i, class) in classes.iter().enumerate() {
                    let (mut s, what) = healthy[i..]
                        .iter()
                        .find(|(s, _)| fits(class, s))
                        .cloned()
                        .unwrap_or_else(|| panic!("{}: no scenario fits", class.name()));
                    s.timing.duration_s = image_sample_s(class);
                    let (f, _) = class.inject(&s);
                    periods.push(f.timing.period().as_us());
                    let setup = rig::RunSetup::new(f).unwrap();
                    let mut emu = board_link::emulator_link::EmulatorLink::new(&setup, image).unwrap_or_else(|e| panic!("{e}"));
                    let (e_records, e_end) = rig::run_loop(&setup, &mut emu, &mut ());
                    let mut twin = board_link::twin_link::TwinLink::new(&setup).unwrap();
                    let (t_records, t_end) = rig::run_loop(&setup, &mut twin, &mut ());
                    let name = format!("{}, {what}", class.name());
                    assert_eq!(format!("{e_end:?}"), format!("{t_end:?}"), "{name}: the same outcome");
                    assert_eq!(e_records.len(), t_records.len(), "{name}");
                    for (k, (a, b)) in e_records.iter().zip(&t_records).enumerate() {
                        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{name}: period {k} differs");
                    }
                }
                periods
            })
        });
        laws.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    println!("{} runs, periods from {} to {} us", periods.len(), periods.iter().min().unwrap(), periods.iter().max().unwrap());
}
