//! The control rate set by configuration, not by a rebuild (issue 56;
//! docs/board.md "The control rate"): `Configure` (and `Restore`) of any period
//! the image runs (`arm_app::rate`: 100 to 4000 us, 10 kHz to 250 Hz) puts it
//! in force and the board's tick follows at once, on the board twin and on the
//! unmodified `arm` ELF (TIM2's prescaler and reload, the watchdog, read back
//! from the emulated registers); `Status` reports the period the tick runs; a
//! period outside the range is refused with `Refusal::Rate`, the board
//! unchanged; a saved rate comes back at reset.

use super::ask;
use arm_app::{
    bringup::{CalibrationRecord, Refusal, Reply, Request},
    rate,
    record::Stored,
};
use board_emulator::{EmulatedBoard, checks};
use board_link::{
    board_backup::{BACKUP_FORMAT, Backup},
    emulator_link::default_image,
    free_arm::FreeArm,
};
use board_twin::{ArmState, BoardDescription, BoardTwin, BusFaults, FlashModel};
use proptest::prelude::*;
use rig::{
    calibration::CalibrationSection,
    scenario::{DEFAULT_TOML, Scenario, TimingSection},
    setup::firmware_config,
};
use shared::time::Period;

/// The rates tested on both boards, Hz, and their periods, us: both ends of
/// the range, the default, and 4 kHz.
const RATES: [(f64, u64); 4] = [(250.0, 4000), (4000.0, 250), (10_000.0, 100), (1000.0, 1000)];

/// The default scenario on a stopped belt.
fn scenario() -> Scenario {
    let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    s.plant.v_belt = 0.0;
    s
}

/// The firmware configuration `sil-host board configure --set timing.rate_hz=RATE`
/// sends (the sampling delay within the period, as the scenario requires).
fn config_at(rate_hz: f64) -> firmware::Config {
    let mut s = scenario();
    s.timing.rate_hz = rate_hz;
    s.timing.delta_s = s.timing.delta_s.min(0.5 / rate_hz);
    s.validate().unwrap();
    firmware_config(&s)
}

/// The default scenario's configuration at `us` (any period, for refusals).
fn config_with_period(us: u64) -> firmware::Config {
    firmware::Config { period: Period::from_us(u32::try_from(us).unwrap()).unwrap(), ..config_at(1000.0) }
}

fn status(reply: Reply) -> arm_app::bringup::Status {
    match reply {
        Reply::Status(s) => s,
        other => panic!("not a status: {other:?}"),
    }
}

#[test]
fn the_scenarios_rates_are_the_periods_the_image_runs() {
    // The rig's range (scenario files, `timing.rate_hz`) and the image's are one:
    // every rate of the one gives a period of the other, and their ends meet.
    let (lo, hi) = TimingSection::RATE_RANGE_HZ;
    assert_eq!(Period::from_rate_hz(lo).unwrap().as_us(), rate::MAX_PERIOD_US);
    assert_eq!(Period::from_rate_hz(hi).unwrap().as_us(), rate::MIN_PERIOD_US);
    for k in 0..=1000 {
        let r = lo + (hi - lo) * f64::from(k) / 1000.0;
        assert!(rate::supported(Period::from_rate_hz(r).unwrap()), "{r} Hz");
    }
}

/// The twin: each rate configured in turn, the tick runs it (the bench advances
/// the arm by the board's period), `Status` reports it, the drivers enable at
/// it once saved; a period outside the range and a restore of one are refused,
/// nothing changed; a restore of another rate in the range retimes the tick.
#[test]
fn the_twin_runs_the_rate_configure_sends_and_refuses_one_it_does_not_run() {
    let mut b = FreeArm::new(&scenario(), BoardDescription::default(), &CalibrationSection::default()).unwrap();
    b.ticks(3).unwrap();
    assert_eq!(status(b.twin_mut().serve(Request::Status)).period_us, 1000);
    for (rate_hz, us) in RATES {
        let config = config_at(rate_hz);
        assert_eq!(config.period.as_us(), us);
        assert_eq!(b.twin_mut().serve(Request::Configure(config)), Reply::Done, "{rate_hz} Hz");
        let st = status(b.twin_mut().serve(Request::Status));
        assert_eq!(u64::from(st.period_us), us, "{rate_hz} Hz: the tick's period reported");
        assert_eq!(b.twin().period_us(), us);
        assert_eq!(b.period_s(), us as f64 * 1e-6, "the arm moves by the board's period");
        assert_eq!(b.twin_mut().serve(Request::GetConfig), Reply::Config(config));
        b.ticks(20).unwrap();
        assert_eq!(status(b.twin_mut().serve(Request::Status)).periods, st.periods + 20);
        // Outside the range: refused, the tick and the configuration unchanged.
        for bad in [99, 4001, 5000] {
            assert_eq!(b.twin_mut().serve(Request::Configure(config_with_period(bad))), Reply::Refused(Refusal::Rate), "{bad} us");
            assert_eq!(b.twin().period_us(), us, "{bad} us");
            assert_eq!(b.twin_mut().serve(Request::GetConfig), Reply::Config(config), "{bad} us");
        }
    }
    // 4 kHz saved: with the belt raised to the tip (the procedure's step 7) the
    // drivers enable at it and the closed loop runs 0.5 s (2 000 periods of
    // 250 us) without a safe state.
    let config = config_at(4000.0);
    assert_eq!(b.twin_mut().serve(Request::Configure(config)), Reply::Done);
    assert_eq!(b.twin_mut().serve(Request::Save), Reply::Done);
    b.move_belt(true).unwrap();
    b.ticks(3).unwrap();
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Done);
    b.ticks(2000).unwrap();
    let st = status(b.twin_mut().serve(Request::Status));
    assert!(b.twin().drivers_enabled() && st.status & shared::wire::status::SAFE_STATE == 0, "{st:?}");
    assert_eq!(b.twin_mut().serve(Request::Disable), Reply::Done);
    b.move_belt(false).unwrap();
    // Restore: a period outside refused whole; another rate in the range taken, the tick with it.
    let Reply::Calibration(calibration) = b.twin_mut().serve(Request::GetCalibration) else { panic!() };
    let bad = Stored { calibration, config: config_with_period(4001) };
    assert_eq!(b.twin_mut().serve(Request::Restore(bad)), Reply::Refused(Refusal::Rate));
    assert_eq!(b.twin().period_us(), 250);
    let other = Stored { calibration, config: config_at(10_000.0) };
    assert_eq!(b.twin_mut().serve(Request::Restore(other)), Reply::Done);
    assert_eq!(b.twin().period_us(), 100);
    assert_eq!(status(b.twin_mut().serve(Request::Status)).period_us, 100);
}

/// A twin without the arm's dynamics (the devices held at one state): enough
/// for the protocol's answers.
fn still_twin() -> (BoardTwin, ArmState) {
    let s = scenario();
    let cal = s.calibration.arm_calibration();
    let twin = BoardTwin::new(BoardDescription::default(), firmware_config(&s), &cal, 7, 0.0).unwrap();
    let arm = ArmState { x: [0.0, 0.0, 0.3, 0.0], f: [0.0; 2], belt_travel_m: 0.0 };
    (twin, arm)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random periods in and out of the range, one after the other on one
    /// board: taken exactly when the image runs them (`Configure` and `Restore`
    /// alike, the host's backup check agreeing), the tick then at it; refused
    /// with `Rate` otherwise, the tick and the configuration as they were.
    #[test]
    fn a_period_is_taken_exactly_when_the_image_runs_it(
        periods in proptest::collection::vec(prop_oneof![1u64..=20_000, 90u64..=110, 3990u64..=4010], 1..8),
        restore in proptest::collection::vec(any::<bool>(), 8),
    ) {
        let (mut twin, arm) = still_twin();
        let Reply::Calibration(calibration) = twin.serve(Request::GetCalibration) else { panic!() };
        for (i, us) in periods.into_iter().enumerate() {
            let before = (twin.period_us(), twin.serve(Request::GetConfig));
            let config = config_with_period(us);
            let runs = (rate::MIN_PERIOD_US..=rate::MAX_PERIOD_US).contains(&us);
            prop_assert_eq!(rate::supported(config.period), runs);
            let host = board_link::board_backup::validate(&Backup {
                format: BACKUP_FORMAT,
                protocol: arm_app::bringup::BRINGUP_PROTOCOL,
                calibration,
                config,
            });
            prop_assert_eq!(host.is_ok(), runs, "{} us: {:?}", us, host);
            let request = if restore[i] { Request::Restore(Stored { calibration, config }) } else { Request::Configure(config) };
            let reply = twin.serve(request);
            if runs {
                prop_assert_eq!(reply, Reply::Done, "{} us", us);
                prop_assert_eq!(twin.period_us(), us);
                prop_assert_eq!(status(twin.serve(Request::Status)).period_us, us as u32);
            } else {
                prop_assert_eq!(reply, Reply::Refused(Refusal::Rate), "{} us", us);
                prop_assert_eq!((twin.period_us(), twin.serve(Request::GetConfig)), before);
            }
            twin.tick(&arm, &BusFaults::default(), false);
        }
    }
}

/// The tick the emulated board runs, checked at the registers: TIM2 updates at
/// `us`'s rate with its interrupt on, the watchdog longer than two periods, one
/// image tick a board tick.
fn assert_ticks_at(arm: &mut FreeArm<EmulatedBoard>, us: u64) {
    assert_eq!(arm.board().period_ns(), us * 1000, "the board runs TIM2's period");
    let m = arm.board().machine();
    checks::timers(m, 1e6 / us as f64).unwrap_or_else(|e| panic!("{us} us: {e}"));
    checks::watchdog(m, us as f64 * 1e-6).unwrap_or_else(|e| panic!("{us} us: {e}"));
    let ticks = |a: &FreeArm<EmulatedBoard>| a.board().monitor().expect("the image ticks").ticks;
    let before = ticks(arm);
    arm.ticks(10).unwrap();
    assert_eq!(ticks(arm), before + 10, "{us} us: one image tick a period");
}

/// The flashed image: each rate configured over its own USART1, TIM2 and the
/// watchdog reprogrammed at once (read back from the registers), `Status`
/// reporting it; a frame with a period outside the range refused by the image
/// (`Refusal::Rate`), TIM2 untouched; a rate saved comes back from the
/// emulated flash at the reset.
#[test]
fn the_flashed_image_retimes_its_tick_to_the_rate_configure_sends_and_keeps_a_saved_one_through_a_reset() {
    let s = scenario();
    let stored = Stored { calibration: CalibrationRecord::brought_up(&s.calibration.arm_calibration()), config: firmware_config(&s) };
    let image = default_image();
    assert!(image.exists(), "{}: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let mut arm = FreeArm::emulated(&s, s.board, &FlashModel::saved(&stored).unwrap(), &image).unwrap();
    arm.ticks(5).unwrap();
    assert_ticks_at(&mut arm, 1000);
    for (rate_hz, us) in RATES {
        assert_eq!(ask(&mut arm, Request::Configure(config_at(rate_hz))), Reply::Done, "{rate_hz} Hz");
        assert_eq!(u64::from(status(ask(&mut arm, Request::Status)).period_us), us, "{rate_hz} Hz");
        assert_ticks_at(&mut arm, us);
        for bad in [99, 4001] {
            assert_eq!(ask(&mut arm, Request::Configure(config_with_period(bad))), Reply::Refused(Refusal::Rate), "{bad} us");
            assert_eq!(u64::from(status(ask(&mut arm, Request::Status)).period_us), us);
        }
        let bad = Stored { calibration: stored.calibration, config: config_with_period(5000) };
        assert_eq!(ask(&mut arm, Request::Restore(bad)), Reply::Refused(Refusal::Rate));
        assert_eq!(arm.board().period_ns(), us * 1000, "TIM2 untouched");
    }
    // 4 kHz saved, then the reset button: the image boots into it from its record.
    assert_eq!(ask(&mut arm, Request::Configure(config_at(4000.0))), Reply::Done);
    assert_eq!(ask(&mut arm, Request::Save), Reply::Done);
    arm.reset().unwrap();
    arm.ticks(5).unwrap();
    assert_eq!(u64::from(status(ask(&mut arm, Request::Status)).period_us), 250);
    assert_ticks_at(&mut arm, 250);
}
