//! The FMEA's measurement (issue 66, "every fault class of an FMEA table"):
//! each fault class of the list below, under both laws, over random scenarios of
//! the envelope (`random_envelope`: rates 250 Hz to 10 kHz, `mu_hat` up to 25 %
//! off, every friction term, random hybrid gains), on the twin: when the safe
//! state came after the fault, and how far the tip strayed from the healthy run
//! at the same period up to then. Each class prints one row: the stops, the
//! worst time to the stop, the worst stray, and the runs beyond the promise
//! (0.1 s, 30 mm). A measurement for docs/hardware.md's FMEA table, run by hand
//! (`cargo test --release -p board-link --test board -- fmea --ignored
//! --nocapture`, `PAINLEVE_FMEA_SCENARIOS` per class and law, default 40); the
//! promise is asserted where it holds (`twin.rs`, `envelope.rs`).

use board_link::random_scenarios::random_envelope;
use board_twin::BoardDescription;
use rig::{record::RunError, scenario::Scenario};

/// When every fault starts, s: after the force ramp, in the move.
const AT_S: f64 = 0.4;

/// A fault class: its name, the change of the board's truth (from the start),
/// or a scenario fault entry (from [`AT_S`]).
enum Class {
    Board(&'static str, fn(&mut BoardDescription)),
    Entry(&'static str, &'static str),
}

fn classes() -> Vec<Class> {
    use Class::{Board, Entry};
    vec![
        Board("motor 1 weak (50 %)", |b| b.motor1.full_scale_nm *= 0.5),
        Board("motor 2 weak (50 %)", |b| b.motor2.full_scale_nm *= 0.5),
        Board("motor 1 weak (70 %)", |b| b.motor1.full_scale_nm *= 0.7),
        Board("motor 1 dead", |b| b.motor1.full_scale_nm *= 1e-3),
        Board("motor 2 dead", |b| b.motor2.full_scale_nm *= 1e-3),
        Board("theta1 encoder offset 10 deg", |b| b.theta1_encoder.zero_count = (b.theta1_encoder.zero_count + 455.0) % 16384.0),
        Board("elbow encoder offset 10 deg", |b| b.elbow_encoder.zero_count = (b.elbow_encoder.zero_count + 455.0) % 16384.0),
        Board("load cell normal gain x0.5", |b| b.load_cell.counts_per_newton[1] *= 0.5),
        Board("load cell normal gain x2", |b| b.load_cell.counts_per_newton[1] *= 2.0),
        Board("load cell tangential gain x0.5", |b| b.load_cell.counts_per_newton[0] *= 0.5),
        Board("load cell tangential gain x2", |b| b.load_cell.counts_per_newton[0] *= 2.0),
        Entry("theta1 encoder stuck", "kind = \"stuck_sensor\"\nsignal = \"theta1\""),
        Entry("elbow encoder stuck", "kind = \"stuck_sensor\"\nsignal = \"elbow\""),
        Entry("theta1 encoder drops out", "kind = \"spi_error\"\nsignal = \"theta1\""),
        Entry("load cell normal axis stuck", "kind = \"stuck_sensor\"\nsignal = \"f_n\""),
        Entry("load cell tangential axis stuck", "kind = \"stuck_sensor\"\nsignal = \"f_t\""),
        Entry("belt speed sensor stuck", "kind = \"stuck_sensor\"\nsignal = \"belt\""),
        Entry("DMA transfer error", "kind = \"dma_transfer_error\""),
    ]
}

fn twin_run(s: &Scenario) -> (Vec<rig::record::PeriodRecord>, Option<RunError>) {
    let setup = rig::RunSetup::new(s.clone()).unwrap();
    let mut link = board_link::twin_link::TwinLink::new(&setup).unwrap();
    rig::run_loop(&setup, &mut link, &mut ())
}

#[test]
#[ignore = "a measurement (minutes): cargo test --release -p board-link --test board -- fmea --ignored --nocapture"]
fn the_fmea_measured_over_random_scenarios_of_the_envelope() {
    let n: u64 = std::env::var("PAINLEVE_FMEA_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(40);
    for kind in ["hybrid", "pid"] {
        // Healthy runs that complete (a stopped healthy run has no path to compare).
        let healthy: Vec<(Scenario, Vec<rig::record::PeriodRecord>)> = (0..n * 3)
            .filter_map(|i| {
                let (s, _) = random_envelope(20_000 + i, kind, 1.0);
                let (r, e) = twin_run(&s);
                e.is_none().then_some((s, r))
            })
            .take(n as usize)
            .collect();
        for class in classes() {
            let mut name = String::new();
            let (mut stops, mut worst_t, mut worst_stray, mut beyond) = (0, 0.0f64, 0.0f64, 0);
            for (s, h) in &healthy {
                let mut f = s.clone();
                let from_s = match &class {
                    Class::Board(n, change) => {
                        name = (*n).to_string();
                        change(&mut f.board);
                        0.0
                    }
                    Class::Entry(n, entry) => {
                        name = (*n).to_string();
                        let fault: rig::faults::Fault = toml::from_str(&format!("{entry}\nat_s = {AT_S}\nduration_s = 5.0\n")).unwrap();
                        f.faults.push(fault);
                        AT_S
                    }
                };
                let (r, e) = twin_run(&f);
                let stop = match e {
                    Some(RunError::SafeState { t, .. }) => Some(t),
                    _ => None,
                };
                let upto = r.len().min(h.len());
                let stray = r[..upto].iter().zip(h).map(|(a, b)| (a.z_t - b.z_t).hypot(a.z_n - b.z_n)).fold(0.0, f64::max);
                worst_stray = worst_stray.max(stray);
                if let Some(t) = stop {
                    stops += 1;
                    worst_t = worst_t.max(t - from_s);
                }
                let late = stop.is_some_and(|t| t - from_s > 0.1);
                if stray >= 0.030 || late {
                    beyond += 1;
                }
            }
            println!(
                "{kind:6} | {name:32} | stopped {stops:3} of {} | worst {:6.0} ms after | worst stray {:6.1} mm | beyond 0.1 s or 30 mm: {beyond}",
                healthy.len(),
                worst_t * 1e3,
                worst_stray * 1e3
            );
        }
    }
}
