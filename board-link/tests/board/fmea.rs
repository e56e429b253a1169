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
//! 200), `PAINLEVE_FMEA_CLASS` keeps the classes whose name contains it;
//! `--nocapture` prints the table's measured columns.

use board_link::random_scenarios::random_envelope;
use board_twin::BoardDescription;
use rig::{
    record::{PeriodRecord, RunError},
    scenario::Scenario,
};

/// When every fault of a scenario entry starts, s: after the force ramp, in the move.
const AT_S: f64 = 0.4;
/// Each run's length, s.
const DURATION_S: f64 = 1.0;
/// The promise: the safe state within this long of the fault, s.
const WITHIN_S: f64 = 0.1;
/// The promise: before the tip strays this far, m.
const STRAY_M: f64 = 0.030;

/// The rows that do not keep the promise yet (docs/hardware.md "FMEA", the rows
/// marked **open**): law, class, and how many of the 200 runs strayed 30 mm
/// before the safe state, as measured. The test holds each to that count (a
/// detector that gets worse fails it; one that gets better passes, and the
/// count here and in the docs comes down).
const OPEN: [(&str, &str, usize); 6] = [
    ("hybrid", "elbow encoder offset +3 deg", 6),
    ("hybrid", "theta1 encoder stuck", 1),
    ("hybrid", "elbow encoder stuck", 2),
    ("hybrid", "load cell tangential axis stuck", 2),
    ("hybrid", "belt speed sensor stuck", 1),
    ("pid", "load cell normal axis dead", 1),
];

/// A fault class: its name, and the change of the board's truth (present
/// from the start) or a scenario fault entry (from [`AT_S`]).
enum Class {
    /// No fault: the same scenario with another seed of the sensors' noise,
    /// the healthy arm's own spread (the floor under every row).
    Reseed(&'static str),
    Board(&'static str, fn(&mut BoardDescription)),
    Entry(&'static str, &'static str),
}

impl Class {
    fn name(&self) -> &'static str {
        match self {
            Self::Reseed(n) | Self::Board(n, _) | Self::Entry(n, _) => n,
        }
    }

    /// `s` with the fault, and its onset, s.
    fn inject(&self, s: &Scenario) -> (Scenario, f64) {
        let mut f = s.clone();
        match self {
            Self::Reseed(_) => {
                f.sensors.seed += 7919;
                (f, 0.0)
            }
            Self::Board(_, change) => {
                change(&mut f.board);
                (f, 0.0)
            }
            Self::Entry(_, entry) => {
                let fault: rig::faults::Fault = toml::from_str(&format!("{entry}\nat_s = {AT_S}\nduration_s = 5.0\n")).unwrap();
                f.faults.push(fault);
                (f, AT_S)
            }
        }
    }
}

/// One encoder count short of 10 degrees, counts of 16 384 per turn.
const TEN_DEG: f64 = 455.0;
/// Three degrees, counts.
const THREE_DEG: f64 = 137.0;

fn shift(zero: &mut f64, by: f64) {
    *zero = (*zero + by).rem_euclid(16384.0);
}

fn classes() -> Vec<Class> {
    use Class::{Board, Entry};
    vec![
        Class::Reseed("no fault (another noise seed)"),
        Board("motor 1 reversed", |b| b.motor1.reversed = true),
        Board("motor 2 reversed", |b| b.motor2.reversed = true),
        Board("motor 1 weak (30 %)", |b| b.motor1.full_scale_nm *= 0.3),
        Board("motor 1 weak (70 %)", |b| b.motor1.full_scale_nm *= 0.7),
        Board("motor 2 weak (30 %)", |b| b.motor2.full_scale_nm *= 0.3),
        Board("motor 2 weak (70 %)", |b| b.motor2.full_scale_nm *= 0.7),
        Board("motor 1 dead", |b| b.motor1.full_scale_nm *= 1e-3),
        Board("motor 2 dead", |b| b.motor2.full_scale_nm *= 1e-3),
        Entry("motor drivers' fault line", "kind = \"driver_fault\""),
        Board("theta1 encoder reversed", |b| b.theta1_encoder.reversed = true),
        Board("elbow encoder reversed", |b| b.elbow_encoder.reversed = true),
        Board("encoders swapped", |b| b.encoders_swapped = true),
        Board("theta1 encoder offset +10 deg", |b| shift(&mut b.theta1_encoder.zero_count, TEN_DEG)),
        Board("theta1 encoder offset -10 deg", |b| shift(&mut b.theta1_encoder.zero_count, -TEN_DEG)),
        Board("theta1 encoder offset +3 deg", |b| shift(&mut b.theta1_encoder.zero_count, THREE_DEG)),
        Board("elbow encoder offset +10 deg", |b| shift(&mut b.elbow_encoder.zero_count, TEN_DEG)),
        Board("elbow encoder offset -10 deg", |b| shift(&mut b.elbow_encoder.zero_count, -TEN_DEG)),
        Board("elbow encoder offset +3 deg", |b| shift(&mut b.elbow_encoder.zero_count, THREE_DEG)),
        Entry("theta1 encoder stuck", "kind = \"stuck_sensor\"\nsignal = \"theta1\""),
        Entry("elbow encoder stuck", "kind = \"stuck_sensor\"\nsignal = \"elbow\""),
        Entry("theta1 encoder drops out (SPI)", "kind = \"spi_error\"\nsignal = \"theta1\""),
        Entry("elbow encoder drops out (magnet)", "kind = \"magnet_lost\"\nsignal = \"elbow\""),
        Entry("theta1 encoder drops out (parity)", "kind = \"parity_error\"\nsignal = \"theta1\""),
        Board("load cell normal axis reversed", |b| b.load_cell.counts_per_newton[1] *= -1.0),
        Board("load cell tangential axis reversed", |b| b.load_cell.counts_per_newton[0] *= -1.0),
        Board("load cell reversed", |b| b.load_cell.counts_per_newton = b.load_cell.counts_per_newton.map(|c| -c)),
        Board("load cell normal gain x0.5", |b| b.load_cell.counts_per_newton[1] *= 0.5),
        Board("load cell normal gain x2", |b| b.load_cell.counts_per_newton[1] *= 2.0),
        Board("load cell tangential gain x0.5", |b| b.load_cell.counts_per_newton[0] *= 0.5),
        Board("load cell tangential gain x2", |b| b.load_cell.counts_per_newton[0] *= 2.0),
        Board("load cell normal axis dead", |b| b.load_cell.counts_per_newton[1] *= 1e-3),
        Board("load cell tangential axis dead", |b| b.load_cell.counts_per_newton[0] *= 1e-3),
        Entry("load cell normal axis stuck", "kind = \"stuck_sensor\"\nsignal = \"f_n\""),
        Entry("load cell tangential axis stuck", "kind = \"stuck_sensor\"\nsignal = \"f_t\""),
        Entry("load cell conversion missing", "kind = \"missing_conversion\""),
        Entry("belt speed sensor stuck", "kind = \"stuck_sensor\"\nsignal = \"belt\""),
        Entry("DMA transfer error", "kind = \"dma_transfer_error\""),
        Entry("DMA FIFO error", "kind = \"dma_fifo_error\""),
        Entry("DMA direct mode error", "kind = \"dma_direct_mode_error\""),
        Entry("DMA late transfer", "kind = \"dma_late_transfer\""),
        Entry("encoder chip select stuck", "kind = \"stuck_chip_select\"\nsignal = \"theta1\""),
    ]
}

fn twin_run(s: &Scenario) -> (Vec<PeriodRecord>, Option<RunError>) {
    let setup = rig::RunSetup::new(s.clone()).unwrap();
    let mut link = board_link::twin_link::TwinLink::new(&setup).unwrap();
    rig::run_loop(&setup, &mut link, &mut ())
}

/// A healthy run of the envelope: its scenario, what it is, its records.
struct Healthy {
    scenario: Scenario,
    what: String,
    records: Vec<PeriodRecord>,
}

/// One faulty run against its healthy run: the safe state's time after the
/// onset (s), and the stray (m).
fn measure(class: &Class, h: &Healthy) -> (Option<f64>, f64) {
    let (f, onset) = class.inject(&h.scenario);
    let (r, e) = twin_run(&f);
    let stop = match &e {
        Some(RunError::SafeState { t, .. }) => Some(t - onset),
        Some(other) => panic!("{}: {} ({}): {other}", class.name(), h.what, h.scenario.sensors.seed),
        None => None,
    };
    let on_belt = h.records.iter().position(|p| p.lift_off_true).unwrap_or(h.records.len());
    let stray = r
        .iter()
        .zip(&h.records[..on_belt])
        .filter(|(_, b)| b.t >= onset)
        .map(|(a, b)| (a.z_t - b.z_t).hypot(a.z_n - b.z_n))
        .fold(0.0, f64::max);
    (stop, stray)
}

/// What one class did over the healthy runs of one law.
#[derive(Default)]
struct Row {
    runs: usize,
    /// Stopped within [`WITHIN_S`] and under [`STRAY_M`].
    caught: usize,
    /// Stopped later, or never, and never strayed [`STRAY_M`].
    harmless: usize,
    stopped: usize,
    worst_stop_s: f64,
    worst_stray_m: f64,
    broken: Vec<String>,
}

fn row(class: &Class, healthy: &[Healthy]) -> Row {
    let mut row = Row { runs: healthy.len(), ..Row::default() };
    for h in healthy {
        let (stop, stray) = measure(class, h);
        row.worst_stray_m = row.worst_stray_m.max(stray);
        if let Some(t) = stop {
            row.stopped += 1;
            row.worst_stop_s = row.worst_stop_s.max(t);
        }
        if stray >= STRAY_M {
            let sat = h
                .records
                .iter()
                .filter(|p| p.status & (shared::wire::status::SATURATED_U1 | shared::wire::status::SATURATED_U2) != 0)
                .count();
            row.broken.push(format!(
                "{} (seed {}): stop {stop:?} s, stray {:.1} mm; healthy saturated {:.0} % of periods",
                h.what,
                h.scenario.sensors.seed,
                stray * 1e3,
                100.0 * sat as f64 / h.records.len() as f64
            ));
        } else if stop.is_some_and(|t| t <= WITHIN_S) {
            row.caught += 1;
        } else {
            row.harmless += 1;
        }
    }
    row
}

#[test]
fn every_fault_class_is_stopped_within_100_ms_and_30_mm_or_never_moves_the_tip_30_mm() {
    let n: usize = std::env::var("PAINLEVE_FMEA_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let only = std::env::var("PAINLEVE_FMEA_CLASS").unwrap_or_default();
    let classes: Vec<Class> = classes().into_iter().filter(|c| c.name().contains(only.as_str())).collect();
    let threads = std::thread::available_parallelism().map_or(2, |p| p.get()).min(4);
    let mut broken = Vec::new();
    for kind in ["hybrid", "pid"] {
        let healthy: Vec<Healthy> = (0..20 * n as u64)
            .filter_map(|i| {
                let (scenario, what) = random_envelope(20_000 + i, kind, DURATION_S);
                let (records, e) = twin_run(&scenario);
                e.is_none().then_some(Healthy { scenario, what, records })
            })
            .take(n)
            .collect();
        assert_eq!(healthy.len(), n, "{kind}: too few healthy runs of the envelope");
        let rows: Vec<Row> = std::thread::scope(|scope| {
            let chunks: Vec<_> = classes.chunks(classes.len().div_ceil(threads).max(1)).collect();
            let handles: Vec<_> =
                chunks.into_iter().map(|chunk| scope.spawn(|| chunk.iter().map(|c| row(c, &healthy)).collect::<Vec<_>>())).collect();
            handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
        });
        for (class, row) in classes.iter().zip(rows) {
            println!(
                "{kind:6} | {:36} | {:3} runs | caught (0.1 s, 30 mm) {:3} | stray under 30 mm, stopped later or never {:3} | stopped {:3} | worst stop {:5.0} ms | worst stray {:5.1} mm",
                class.name(),
                row.runs,
                row.caught,
                row.harmless,
                row.stopped,
                row.worst_stop_s * 1e3,
                row.worst_stray_m * 1e3
            );
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
fn image_sample_s(class: &Class) -> f64 {
    match class {
        Class::Entry(..) => AT_S + 0.15,
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
                let healthy = (0..200u64)
                    .map(|i| random_envelope(20_000 + i, kind, DURATION_S))
                    .filter(|(s, _)| twin_run(s).1.is_none())
                    .take(classes.len());
                let mut periods = Vec::new();
                for (class, (mut s, what)) in classes.iter().zip(healthy) {
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
