//! The harnesses in the test suite: a few thousand cases of each (sizes fixed, the
//! same in debug and release), and tests that each property can fail: a wrong
//! command, a decoder that ignores trailing bytes or its CRC, a scenario out of its
//! bounds are caught; a failure is shrunk and replays from its seed and case.

use firmware::{
    Config, Firmware, SafeReason,
    board::FrozenClock,
    pil::{Downlink, Uplink, WireError},
};
use painleve_fuzz::{
    Failure, Target, case_seed,
    firmware_step::{self, Clock, Coverage, ModelState, Observed},
    on_harness_thread,
    pil_decode::{self, Case as PilCase, Decoders, Msg},
    run_strategy,
    scenario::{self, check_accepted, error_names_its_place, violations},
};
use proptest::{
    collection::vec,
    strategy::{Strategy, ValueTree},
    test_runner::{RngAlgorithm, TestRng, TestRunner},
};
use rig::scenario::Scenario;
use shared::wire::{ActuatorCommand, SensorFrame, status};

/// A change that breaks a command.
type Breaks<'a> = &'a dyn Fn(&mut ActuatorCommand);

/// The seed of the suite's runs (issue 15).
const SEED: u64 = 15;

fn passes(target: Target, cases: u64) {
    let report = on_harness_thread(move || target.run(SEED, 0, cases, &mut |_| {}));
    assert_eq!(report.cases, cases);
    if let Some(Failure { case, message, input, .. }) = report.failure {
        panic!("{} case {case} (seed {SEED}) failed: {message}\n{input}", target.name());
    }
}

#[test]
fn firmware_step_holds_on_3000_cases() {
    passes(Target::FirmwareStep, 3000);
}

#[test]
fn pil_decode_holds_on_5000_cases() {
    passes(Target::PilDecode, 5000);
}

#[test]
fn scenario_holds_on_3000_cases() {
    passes(Target::Scenario, 3000);
}

/// The values of cases `0..n` of `strategy` under seed [`SEED`].
fn cases<S: Strategy>(strategy: &S, n: u64) -> Vec<S::Value> {
    let mut runner = TestRunner::deterministic();
    (0..n)
        .map(|k| {
            *runner.rng() = TestRng::from_seed(RngAlgorithm::ChaCha, &case_seed(SEED, k));
            strategy.new_tree(&mut runner).expect("generate").current()
        })
        .collect()
}

/// The generator reaches every status bit and every safe-state reason, and
/// commands with torque: the properties are exercised on all of them.
#[test]
fn firmware_cases_reach_every_status_bit_and_safe_reason() {
    let mut cov = Coverage::default();
    for c in cases(&firmware_step::strategy(), 400) {
        firmware_step::check_covering(&c, &mut cov).unwrap();
    }
    assert!(cov.bits.iter().all(|&n| n > 0), "{cov:?}");
    // Every reason of the step but `LiftOff` (12): it needs lift-off declared for 2 ms
    // (firmware::tracking::LIFT_OFF_S) under the hybrid law with no other check tripping
    // first, which a random script does not hold; the twin's wiring tests reach it (a
    // reversed load cell, board-link/tests/board/twin.rs) and firmware::tracking's unit tests pin
    // its rule. The tracking check's trips are `Tracking` (11) with the gains inside
    // their envelope at the script's rate and `Unstable` (15) outside it (issue 66:
    // the paper's gains from 1.1 ms on), which most of the scripts' random periods are:
    // one of the two. `Acquisition` (13) is the board's, `Saturated` (14) needs a
    // saturated law whose error creeps past its bound (firmware::tracking's tests).
    assert!(cov.reasons[1..11].iter().all(|&n| n > 0), "{cov:?}");
    assert!(cov.reasons[11] + cov.reasons[15] > 0, "{cov:?}");
    assert!(cov.torque > cov.steps / 20, "{cov:?}");
}

/// A frame of the arm near the belt (x0d), trusted by the default configuration,
/// pressing with 10 N (with no force read, the hybrid law's lift-off check stops it
/// after 2 ms: `firmware::tracking::LIFT_OFF_S`).
fn good_frame(seq: u32) -> SensorFrame {
    SensorFrame {
        t_us: u64::from(seq) * 1000,
        seq,
        theta1_count: 15_860,
        elbow_count: 15_290,
        f_n_code: shared::wire::encode_force(10.0),
        ..SensorFrame::default()
    }
}

/// Each property of `firmware-step` fails on a command that breaks it.
#[test]
fn a_wrong_command_fails_the_firmware_property() {
    let cfg = Config::default();
    let run = |cmd_change: Breaks<'_>, safe: Option<SafeReason>| {
        let mut fw = Firmware::new(cfg).unwrap();
        let mut model = ModelState::default();
        let mut result = Ok(());
        for k in 0..3 {
            let frame = good_frame(k);
            let now_us = frame.t_us + 100;
            let mut cmd = fw.step(shared::time::Instant::from_us(now_us), &frame, &FrozenClock);
            let seen_clock = Clock { start: 0, elapsed: 0, tps: 1_000_000 };
            if k == 2 {
                cmd_change(&mut cmd);
            }
            let seen = Observed {
                frame: &frame,
                now_us,
                clock: &seen_clock,
                cmd: &cmd,
                fw_safe: safe.or(fw.safe_state()),
                fw_overruns: cmd.overruns,
            };
            result = result.and(firmware_step::check_step(&cfg, &mut model, &seen));
        }
        result
    };
    run(&|_| {}, None).expect("the firmware's own commands pass");
    let wrong: [(&str, Breaks<'_>); 8] = [
        ("seq", &|c| c.seq += 1),
        ("u1_code", &|c| c.u1_code = 2048),
        ("undefined status", &|c| c.status |= 1 << 12),
        ("BAD_FRAME", &|c| c.status |= status::BAD_FRAME),
        ("DEADLINE_MISS", &|c| c.status |= status::DEADLINE_MISS),
        ("overruns", &|c| c.overruns = 7),
        ("t_sent_us", &|c| c.t_sent_us += 1),
        ("SAFE_STATE without reason", &|c| c.status |= status::SAFE_STATE),
    ];
    for (what, change) in wrong {
        assert!(run(change, None).is_err(), "{what} not caught");
    }
    // The safe state with torque, or latched without a cause.
    let latched = |c: &mut ActuatorCommand| c.status |= status::SAFE_STATE | (2 << status::REASON_SHIFT);
    assert!(run(&latched, Some(SafeReason::BadFrames)).is_err(), "a safe state without bad frames");
    // Beyond the torque limit: a limit of 1 N m and a code of 2 N m.
    let low = Config { torque_limit: 1.0, ..cfg };
    let mut model = ModelState::default();
    let frame = good_frame(0);
    let mut cmd = Firmware::new(low).unwrap().step(frame.sampled_at(), &frame, &FrozenClock);
    cmd.u2_code = 820;
    let seen = Observed {
        frame: &frame,
        now_us: frame.t_us,
        clock: &Clock { start: 0, elapsed: 0, tps: 1 },
        cmd: &cmd,
        fw_safe: None,
        fw_overruns: 0,
    };
    let e = firmware_step::check_step(&low, &mut model, &seen).unwrap_err();
    assert!(e.contains("torque_limit"), "{e}");
}

fn cobs_payload(frame: &mut [u8]) -> Result<&[u8], WireError> {
    let n = cobs::decode_in_place(frame).map_err(|_| WireError::Cobs)?;
    Ok(&frame[..n])
}

const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);

/// The firmware's decoder before issue 15: bytes after the CRC ignored.
fn lenient<T: serde::de::DeserializeOwned>(frame: &mut [u8]) -> Result<T, WireError> {
    let raw = cobs_payload(frame)?;
    postcard::take_from_bytes_crc32(raw, CRC.digest()).map(|(m, _rest)| m).map_err(|_| WireError::Message)
}

/// A decoder that reads the message and skips its CRC.
fn crc_blind<T: serde::de::DeserializeOwned>(frame: &mut [u8]) -> Result<T, WireError> {
    let raw = cobs_payload(frame)?;
    match postcard::take_from_bytes::<T>(raw) {
        Ok((m, rest)) if rest.len() == 4 => Ok(m),
        _ => Err(WireError::Message),
    }
}

#[test]
fn a_decoder_that_ignores_trailing_bytes_fails_the_pil_property() {
    let lax = Decoders { down: lenient::<Downlink>, up: lenient::<Uplink> };
    let case = PilCase::Trailing { msg: Msg::Down(Downlink::End), junk: vec![1] };
    assert_eq!(pil_decode::check(&case), Ok(()));
    let e = pil_decode::check_with(&case, &lax).unwrap_err();
    assert!(e.contains("expected Err(Message)"), "{e}");
    // Found by the harness's own cases, too.
    let found = cases(&pil_decode::strategy(), 300).iter().filter(|c| pil_decode::check_with(c, &lax).is_err()).count();
    assert!(found > 10, "{found} of 300 cases catch the lenient decoder");
}

#[test]
fn a_decoder_without_its_crc_fails_the_pil_property() {
    let blind = Decoders { down: crc_blind::<Downlink>, up: crc_blind::<Uplink> };
    let found = cases(&pil_decode::strategy(), 300).iter().filter(|c| pil_decode::check_with(c, &blind).is_err()).count();
    assert!(found > 10, "{found} of 300 cases catch a decoder without CRC");
}

/// The scenario's checks flag what breaks documented bounds, an error message
/// without a place, and an accepted scenario the firmware would refuse.
#[test]
fn the_scenario_properties_catch_out_of_bounds_scenarios_and_placeless_errors() {
    let ok = Scenario::default_scenario();
    assert_eq!(violations(&ok), Vec::<String>::new());
    check_accepted(&ok).unwrap();
    let mut bad = ok.clone();
    bad.plant.mu = 11.0;
    bad.timing.delta_s = 0.001;
    bad.rig.realtime_cpu = "1024".into();
    let v = violations(&bad);
    // The delay breaks two rules: within one period, and 0.4 ms with the protection on.
    assert_eq!(v.len(), 4, "{v:?}");
    assert!(check_accepted(&bad).is_err());
    let mut f32_gain = ok.clone();
    f32_gain.controller.hybrid.kp = 1e39;
    let e = check_accepted(&f32_gain).unwrap_err();
    assert!(e.contains("breaks documented bounds"), "{e}");
    let mut unused_nan = ok.clone();
    unused_nan.faults =
        vec![rig::faults::Fault { delay_s: f64::NAN, ..rig::faults::Fault::new(rig::faults::FaultKind::DropCommand, 1.0, 0.0) }];
    let e = check_accepted(&unused_nan).unwrap_err();
    assert!(e.contains("delay_s"), "{e}");
    let mut blank = ok;
    blank.name = String::new();
    assert!(check_accepted(&blank).is_err());
    for msg in ["", "  ", "recursion limit", "invalid type: integer, expected a string", "the scenario is not valid TOML: "] {
        assert!(!error_names_its_place(msg), "{msg:?}");
    }
    for msg in [
        "scenario key `plant.m` = -1 is out of range: expected a finite value > 0",
        "TOML parse error at line 3, column 7\n  |\n3 | mu = \n  |       ^\nstring values must be quoted",
        "--set plant.m: the key is given twice",
        "the scenario is not valid TOML: keys, tables or arrays nested 80 levels deep or more",
    ] {
        assert!(error_names_its_place(msg), "{msg:?}");
    }
}

/// The runner shrinks a failure to a minimal input, reports its case, and the
/// case alone replays it (inputs depend on the seed and the case index only).
#[test]
fn a_failure_is_shrunk_and_replays_from_its_seed_and_case() {
    let strategy = vec(0u32..1000, 0..20);
    let check = |v: &Vec<u32>| if v.iter().sum::<u32>() < 1500 { Ok(()) } else { Err(format!("sum {}", v.iter().sum::<u32>())) };
    let report = run_strategy("sum", &strategy, &check, 3, 0, 1000, &mut |_| {});
    let f = report.failure.expect("some vector sums to 1500 or more");
    assert_eq!(report.cases, f.case + 1, "stops at the failing case");
    let shrunk: Vec<u32> = f.input.split(|c: char| !c.is_ascii_digit()).filter(|s| !s.is_empty()).map(|s| s.parse().unwrap()).collect();
    let sum: u32 = shrunk.iter().sum();
    assert!(sum >= 1500 && shrunk.len() >= 2, "shrunk to {shrunk:?}");
    assert!(shrunk.iter().all(|&x| sum - x < 1500), "every element is needed: {shrunk:?}");
    assert_eq!(f.message, format!("sum {sum}"));
    let again = run_strategy("sum", &strategy, &check, 3, f.case, 1, &mut |_| {});
    assert_eq!(again.failure.map(|g| (g.case, g.input)), Some((f.case, f.input.clone())), "the case alone replays");
    assert!(run_strategy("sum", &strategy, &check, 3, 0, f.case, &mut |_| {}).failure.is_none(), "the cases before it pass");
    assert_eq!(Target::Scenario.show(3, 7), Target::Scenario.show(3, 7));
    assert_ne!(Target::Scenario.show(3, 7), Target::Scenario.show(4, 7));
}

/// The scenario cases reach both outcomes often: accepted scenarios (where the
/// bounds, firmware and round-trip properties act) and refused ones.
#[test]
fn scenario_cases_are_often_accepted_and_often_refused() {
    let all = cases(&scenario::strategy(), 400);
    let accepted = all.iter().filter(|c| Scenario::from_toml(&scenario::text(&c.source)).is_ok()).count();
    assert!((40..360).contains(&accepted), "{accepted} of 400 accepted");
}
