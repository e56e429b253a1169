//! The control handler's worst case over random scenarios (issue 56), on the
//! bytes that are flashed: the unmodified `arm` ELF on the emulated board in
//! the counted mode (every instruction of TIM2's handler costed, the flash's
//! wait states behind the ART included), against the board twin.
//!
//! The issue states the bound for named cases: at most 5 000 cycles at 1 kHz
//! (the four paper scenarios, `emulator.rs`) and at most 50 % of the period,
//! 8 400 cycles, at 10 kHz (the default scenario). The project's standard is
//! that such a bound holds for every case of its kind. The handler's work per
//! period does not depend on the rate (the same acquisition, step and checks;
//! only their constants change), so the bound asserted here is the tighter of
//! the two at every rate: [`HANDLER_CYCLES_CEILING`] (5 000 cycles), and never
//! more than half the period (which 5 000 cycles is from 100 us on).
//!
//! The sample, seeded (the same cases on every run): random admissible
//! scenarios (`board_link::random_scenarios`) under both laws, the hybrid
//! law with each of its five friction terms in turn, at random periods of the
//! image's whole range (`arm_app::rate`: 100 to 4 000 us, drawn log-uniform so
//! that each decade is as likely), the command's delay within the period
//! (`random_scenarios::delay_within`), the belt within the counted mode's
//! speed (`random_scenarios::COUNTED_BELT_SPEED_MAX`, a limit of the emulated
//! board's counted mode; the belt's speed changes no path of the handler). A quarter of the cases carry a wiring fault of
//! issue 52, a quarter a bus fault (SPI error, parity, lost magnet, missing
//! conversion, driver fault) at a random time: both end in the safe state, the
//! period that latches it and the one that disables the drivers in the sample.
//! One case in eight, without a fault, runs past 1 000 periods (the step's
//! statistics window closes, `arm_app::step_stats::WINDOW`); the laws
//! alternate within each kind of case. Named cases add the hybrid law's
//! lift-off (`mu` = 1: the base motor saturates, the tip bounces and the
//! firmware's tracking or lift-off check stops the arm) and two cases an
//! earlier sample found ([`named_cases`]). Every run counts from period 0,
//! where the enable button's firmware reset lands, and the handler's runs
//! before it (the boot's tick and the button's held ticks) are bounded too.
//!
//! Per case: the image's trace and outcome are the twin's bit for bit, no
//! deadline missed (plant side and the firmware's own count), one handler run
//! per period, the worst handler within the bound, its instructions and the
//! stack within their ceilings. `PAINLEVE_BOUND_CASES` (default
//! [`CASES`]) and `PAINLEVE_BOUND_FIRST` run another sample of the same
//! generator (e.g. a larger one before a release); `PAINLEVE_BOUND_REPORT`
//! names a file for the table of figures (markdown).

use board_emulator::core_clock::Mode;
use board_link::{
    emulator_link::{EmulatorLink, HANDLER_CYCLES_CEILING, HANDLER_INSTRUCTIONS_CEILING, ImageTiming, STACK_CEILING_BYTES, default_image},
    twin_link::TwinLink,
};
use firmware::{ControllerKind, SafeReason, config::FrictionCompensation};
use rig::{faults::Fault, record::RunError, run_loop, scenario::Scenario};

use board_link::random_scenarios::{FRICTIONS, Uniform, at_period, counted_admissible as admissible, friction_name, log_uniform_period_us};

use crate::wiring_cases::{WIRING_FAULTS, unused_by};

/// Cases in CI's sample: with the named ones, 38 s of one core in release
/// (73 s of wall time on a 2-core machine under a load of 12), the worst
/// handler 4 759 cycles. The first 400 cases (350 s of one core): 4 769 at
/// most (PID, the elbow encoder reversed, at 1 072 and 443 us), 4 525 after
/// period 0.
const CASES: u64 = 48;

/// The sample's seed.
const SEED: u64 = 0x5eed_0056;

/// The bus faults the emulated board injects (`rig::faults::LinkKind::Emulator`),
/// as a scenario's `[[faults]]` entry without its time.
const BUS_FAULTS: [&str; 5] = [
    "kind = \"spi_error\"\nsignal = \"theta1\"",
    "kind = \"parity_error\"\nsignal = \"elbow\"",
    "kind = \"magnet_lost\"\nsignal = \"theta1\"",
    "kind = \"missing_conversion\"",
    "kind = \"driver_fault\"",
];

/// How a case is expected to end.
#[derive(Debug, Clone, Copy)]
enum Ending {
    /// No fault injected: the run's end; under the hybrid law the firmware's
    /// tracking or lift-off check may stop it (see [`Ending::NoFault`]'s use in [`check`]).
    NoFault,
    /// A wiring fault of issue 52: the safe state, unless the law uses nothing it touches.
    Wiring(&'static str),
    /// A bus fault held past the firmware's limit: `BadFrames`.
    Bus(&'static str),
    /// The hybrid law's lift-off at `mu` = 1: `Tracking`, `LiftOff`, `Runaway` or `Overload`.
    LiftOff,
}

/// One case of the sample.
struct Case {
    name: String,
    scenario: Scenario,
    ending: Ending,
}

/// The law of `kind` and `friction`, for a case's name.
fn law(kind: &str, friction: FrictionCompensation) -> String {
    if kind == "pid" { "pid".to_string() } else { format!("hybrid/{}", friction_name(friction)) }
}

/// Random case `i` of the sample (see the module's documentation). In each
/// eight, by `i % 8`: 0, 1, 4 and 5 without a fault (hybrid, PID, PID,
/// hybrid; 0 past a window's close for even `i / 8`, 1 for odd), 2 and 6 a
/// wiring fault (hybrid, PID), 3 and 7 a bus fault (PID, hybrid); the hybrid
/// cases take the friction terms in turn.
fn random_case(i: u64) -> Case {
    let mut r = Uniform::new(SEED ^ (i + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let kind = if (i / 4 + i).is_multiple_of(2) { "hybrid" } else { "pid" };
    let friction = FRICTIONS[((i / 2) % 5) as usize];
    // Periods up to 1 ms for the cases past a window's close (the slowest
    // rates would cost the test minutes for the same path).
    let long = matches!(i % 16, 0 | 9);
    let us = if long { log_uniform_period_us(&mut r, 100, 1000) } else { log_uniform_period_us(&mut r, 100, 4000) };
    let periods = if long { 1000 + (100.0 * r.draw()) as u64 } else { 100 + (300.0 * r.draw()) as u64 };
    let ending = match i % 4 {
        2 => Ending::Wiring(WIRING_FAULTS[(r.draw() * WIRING_FAULTS.len() as f64) as usize].0),
        3 => Ending::Bus(BUS_FAULTS[(r.draw() * BUS_FAULTS.len() as f64) as usize]),
        _ => Ending::NoFault,
    };
    let mut duration_s = periods as f64 * us as f64 * 1e-6;
    if let Ending::Wiring(_) = ending {
        // The wiring checks confirm in seconds: 0.15 s stops every fault (`emulator.rs`).
        duration_s = duration_s.max(0.15);
    }
    let mut s = admissible(30_000 + i, kind, friction, us, duration_s);
    match ending {
        Ending::Wiring(fault) => {
            let wire = WIRING_FAULTS.iter().find(|(f, _)| *f == fault).unwrap().1;
            wire(&mut s.board);
        }
        Ending::Bus(fault) => {
            // From a random period of the run's first 80 %, held 0.1 s: the
            // firmware's limit of bad frames in a row is reached within it.
            let at_s = (0.8 * r.draw() * periods as f64).floor() * us as f64 * 1e-6;
            let f: Fault = toml::from_str(&format!("{fault}\nat_s = {at_s}\nduration_s = 0.1")).unwrap();
            s.faults.push(f);
        }
        Ending::NoFault | Ending::LiftOff => {}
    }
    let what = match ending {
        Ending::NoFault => String::new(),
        Ending::Wiring(f) => format!(", {f}"),
        Ending::Bus(f) => format!(", {}", f.lines().next().unwrap().trim_start_matches("kind = ").trim_matches('"')),
        Ending::LiftOff => ", lift-off".into(),
    };
    Case { name: format!("case {i} ({} at {us} us{what})", law(kind, friction)), scenario: s, ending }
}

/// Random cases of this generator kept by index ([`named_cases`]): ones that
/// failed once (the 400-case sample's, the test then expecting `BadFrames`).
const KEPT_CASES: [u64; 1] = [375];

/// The named cases. The hybrid law's lift-off at `mu` = 1 (the default
/// scenario's arm, `tests/e2e/closed_loop_friction.rs`), at 1 kHz and
/// at 2 kHz, run until the firmware stops the arm. And two cases of the first
/// sample (its generator since changed) kept: no fault, the test expecting
/// their end, the firmware stopped them, the twin alike (where the paper's
/// hybrid gains are not stable when sampled, see [`check`]): `Tracking` at
/// period 14 and `LiftOff` at period 37, the two checks' safe states at the
/// slowest rates (since issue 66 both `Unstable`: the paper's gains are
/// outside their envelope there).
fn named_cases() -> Vec<Case> {
    let lift_off = [(1000u64, 1.0), (500, 1.0)].into_iter().map(|(us, duration_s)| {
        let mut s = Scenario::from_toml(rig::scenario::DEFAULT_TOML).unwrap();
        s.plant.mu = 1.0;
        s.controller.mu_hat = 1.0;
        at_period(&mut s, us, duration_s);
        Case { name: format!("lift-off (hybrid/commanded at {us} us, mu 1)"), scenario: s, ending: Ending::LiftOff }
    });
    let kept = [(16u64, FrictionCompensation::ModelMeasuredNormal, 3255u64), (144, FrictionCompensation::Measured, 2233)].into_iter().map(
        |(i, friction, us)| Case {
            name: format!("kept {i} ({} at {us} us)", law("hybrid", friction)),
            scenario: admissible(30_000 + i, "hybrid", friction, us, 300.0 * us as f64 * 1e-6),
            ending: Ending::NoFault,
        },
    );
    // Kept by their index in this sample's generator ([`random_case`]): a bus
    // fault's case under the hybrid law at 3 579 us that the tracking check
    // stopped (period 8) before the parity errors reached `BadFrames`.
    lift_off.chain(kept).chain(KEPT_CASES.map(random_case)).collect()
}

/// One case's figures.
struct Row {
    name: String,
    us: u64,
    periods: usize,
    outcome: String,
    timing: ImageTiming,
    /// The worst handler before period 0 (boot and the enable button's ticks), cycles with wait states.
    start_worst: u64,
}

/// Runs `case` on the twin and on the counted image and checks it (see the
/// module's documentation): its figures, or what failed.
fn check(case: &Case) -> Result<Row, String> {
    let Case { name, scenario: s, ending } = case;
    s.validate().map_err(|e| format!("{name}: {e}"))?;
    let us = s.timing.period().as_us();
    let setup = rig::RunSetup::new(s.clone()).unwrap();
    let mut twin = TwinLink::new(&setup).unwrap();
    let (twin_records, twin_err) = run_loop(&setup, &mut twin, &mut ());
    let image = default_image();
    assert!(image.exists(), "{} is missing: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let mut link = EmulatorLink::with_mode(&setup, &image, Mode::Counted).map_err(|e| format!("{name}: {e}"))?;
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    // The same run, bit for bit: the outcome, then every record.
    let outcome = format!("{err:?}");
    if outcome != format!("{twin_err:?}") {
        return Err(format!("{name}: the image ends {outcome}, the twin {twin_err:?}"));
    }
    if records.len() != twin_records.len() {
        return Err(format!("{name}: {} records, the twin {}", records.len(), twin_records.len()));
    }
    if let Some(k) = records.iter().zip(&twin_records).position(|(a, b)| format!("{a:?}") != format!("{b:?}")) {
        return Err(format!("{name}: period {k} differs from the twin's:\n{:?}\n{:?}", records[k], twin_records[k]));
    }
    // The ending the case was built for. Where the paper's hybrid gains are
    // not stable when sampled (periods from about 1.6 ms: the default scenario
    // ends in `Tracking` or `Overload` on the twin from 1 600 us on, not at
    // 1 500) or its friction term leaves the tip behind its reference (`none`:
    // `Tracking` at 1 kHz as at 762 us), the firmware's tracking, lift-off or
    // runaway checks stop the arm (since issue 66 named `Unstable` where the
    // gains are outside their envelope at the rate, `Saturated` where the law
    // saturated), with or without a fault, a bus fault's
    // `BadFrames` not yet reached: a safe state, the twin's, the handler
    // bounded in it as in any period.
    let hybrid = s.controller.kind == ControllerKind::Hybrid;
    let checks_stop = matches!(
        err,
        Some(RunError::SafeState {
            reason: SafeReason::Tracking
                | SafeReason::LiftOff
                | SafeReason::Runaway
                | SafeReason::Overload
                | SafeReason::Saturated
                | SafeReason::Unstable,
            ..
        })
    );
    let ended = match (ending, &err) {
        (Ending::NoFault, None) => true,
        (Ending::NoFault | Ending::Bus(_), _) if hybrid && checks_stop => true,
        (Ending::Wiring(f), None) => unused_by(if hybrid { "hybrid" } else { "pid" }, f),
        (Ending::Wiring(_), Some(RunError::SafeState { .. })) => true,
        (Ending::Bus(_), Some(RunError::SafeState { reason: SafeReason::BadFrames, .. })) => true,
        (Ending::LiftOff, _) => checks_stop,
        _ => false,
    };
    if !ended {
        return Err(format!("{name}: ends {outcome}, not as a {ending:?} case should"));
    }
    if let Some(k) = records.iter().position(|p| p.deadline_miss || p.firmware_deadline_miss || p.overruns != 0) {
        return Err(format!("{name}: a deadline missed at period {k}: {:?}", records[k]));
    }
    let timing = link.timing().ok_or_else(|| format!("{name}: no handler counted"))?;
    let start_worst = link.start_handlers.iter().map(|r| r.cycles + r.wait_cycles).max().unwrap_or(0);
    let row = Row { name: name.clone(), us, periods: records.len(), outcome: short(&err), timing, start_worst };
    if timing.runs != records.len() {
        return Err(format!("{name}: {} handler runs in {} periods", timing.runs, records.len()));
    }
    // The boot's tick(s) and the button's held ticks (20 ms: 20 at 1 kHz, 200
    // at 10 kHz), one or two more.
    if link.start_handlers.len() < usize::from(arm_app::button_periods(us)) {
        return Err(format!("{name}: {} handler runs before period 0", link.start_handlers.len()));
    }
    // The bound: the 1 kHz ceiling at every rate, and half the period.
    let half_period = u64::from(timing.core_hz) / 1_000_000 * us / 2;
    let bound = HANDLER_CYCLES_CEILING.min(half_period);
    let worst = timing.flash_cycles[1].max(start_worst);
    if worst > bound {
        return Err(format!(
            "{name}: the handler's worst {} cycles (before period 0: {start_worst}) past {bound}: {timing:?}",
            timing.flash_cycles[1]
        ));
    }
    if timing.instructions[1] > HANDLER_INSTRUCTIONS_CEILING || timing.stack_high_water_bytes > STACK_CEILING_BYTES {
        return Err(format!("{name}: instructions or stack past their ceilings: {timing:?}"));
    }
    Ok(row)
}

fn short(err: &Option<RunError>) -> String {
    match err {
        None => "end".into(),
        Some(RunError::SafeState { k, reason, .. }) => format!("{reason:?} at {k}"),
        Some(e) => e.to_string(),
    }
}

/// The rate classes of the report.
fn class(us: u64) -> &'static str {
    match us {
        0..=249 => "4 to 10 kHz",
        250..=999 => "1 to 4 kHz",
        _ => "250 Hz to 1 kHz",
    }
}

#[test]
fn the_control_handlers_worst_case_stays_within_the_bound_on_random_scenarios_at_random_rates() {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let first = env("PAINLEVE_BOUND_FIRST").unwrap_or(0);
    let n = env("PAINLEVE_BOUND_CASES").unwrap_or(CASES);
    let mut cases = named_cases();
    cases.extend((first..first + n).map(random_case));
    let started = std::time::Instant::now();
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for case in &cases {
        let t = std::time::Instant::now();
        match check(case) {
            Ok(row) => {
                eprintln!(
                    "{}: {} periods, {}; handler cycles median {} worst {} (after period 0: {}; before: {}), instructions worst {} [{:.1} s]",
                    row.name,
                    row.periods,
                    row.outcome,
                    row.timing.flash_cycles[0],
                    row.timing.flash_cycles[1],
                    row.timing.steady_flash_cycles,
                    row.start_worst,
                    row.timing.instructions[1],
                    t.elapsed().as_secs_f64()
                );
                rows.push(row);
            }
            Err(e) => {
                eprintln!("FAILED {e}");
                failures.push(e);
            }
        }
    }
    let wall = started.elapsed().as_secs_f64();
    let mut report = String::from(
        "| case | period (us) | periods | outcome | median cycles | worst cycles | worst after period 0 | worst before period 0 | worst instructions |\n|---|---:|---:|---|---:|---:|---:|---:|---:|\n",
    );
    for r in &rows {
        report += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.name,
            r.us,
            r.periods,
            r.outcome,
            r.timing.flash_cycles[0],
            r.timing.flash_cycles[1],
            r.timing.steady_flash_cycles,
            r.start_worst,
            r.timing.instructions[1]
        );
    }
    report += "\n| rate class | cases | max worst cycles | its case | max worst after period 0 | max median cycles |\n|---|---:|---:|---|---:|---:|\n";
    for c in ["250 Hz to 1 kHz", "1 to 4 kHz", "4 to 10 kHz"] {
        let of: Vec<&Row> = rows.iter().filter(|r| class(r.us) == c).collect();
        if let Some(w) = of.iter().max_by_key(|r| r.timing.flash_cycles[1].max(r.start_worst)) {
            let median = of.iter().map(|r| r.timing.flash_cycles[0]).max().unwrap_or(0);
            let steady = of.iter().map(|r| r.timing.steady_flash_cycles).max().unwrap_or(0);
            report +=
                &format!("| {c} | {} | {} | {} | {steady} | {median} |\n", of.len(), w.timing.flash_cycles[1].max(w.start_worst), w.name);
        }
    }
    report += &format!("\n{} cases, {} failed, {wall:.1} s\n", cases.len(), failures.len());
    eprintln!("{report}");
    if let Ok(path) = std::env::var("PAINLEVE_BOUND_REPORT") {
        std::fs::write(&path, &report).unwrap();
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n{}", failures.len(), cases.len(), failures.join("\n"));
}
