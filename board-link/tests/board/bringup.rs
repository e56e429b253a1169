//! Bring-up on the board twin (issue 23; docs/board.md "Bring-up"): the `arm`
//! application's bring-up requests, served between ticks while the simulated
//! arm moves under the torques it makes. As the procedure asks, the belt is
//! lowered below the hanging tip (here the base 0.4199 m above it: the arm at
//! rest, its elbow bent by the spring, clears it by a few millimetres, and a jog
//! lifts the tip) and the arm hangs at rest; the test knows the pose's joint
//! counts from the plant's state, as the calibration jig's drawing gives them.

use arm_app::{
    Joint, Notice, Settings,
    bringup::{CalibrationRecord, JogFault, Missing, Refusal, Reply, Request, SpanStep},
    record::RecordFault,
};
use board_link::free_arm::FreeArm;
use board_twin::{BoardDescription, FlashModel, MotorWiring};
use rig::{
    calibration::CalibrationSection,
    scenario::{DEFAULT_TOML, Scenario},
};

/// The default scenario on a stopped belt.
fn scenario() -> Scenario {
    let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    s.plant.v_belt = 0.0;
    s
}

/// The arm hanging free on `board` (its flash holding the scenario's settings).
fn bench(board: BoardDescription) -> FreeArm {
    FreeArm::new(&scenario(), board, &CalibrationSection::default()).unwrap()
}

/// Jogs `joint` and runs the ticks until its result is there.
fn jog(b: &mut FreeArm, joint: Joint, code: i16) -> Reply {
    assert_eq!(b.twin_mut().serve(Request::Jog { joint, code, periods: 100 }), Reply::Done);
    for _ in 0..200 {
        b.tick().unwrap();
        match b.twin_mut().serve(Request::JogResult) {
            Reply::Refused(Refusal::Busy) => {}
            other => return other,
        }
    }
    panic!("the jog never ended")
}

/// A board mounted some way, zeroed at the jig, then each joint jogged both ways.
fn calibrate(board: BoardDescription) -> (FreeArm, [Reply; 4]) {
    let mut b = bench(board);
    b.ticks(5).unwrap();
    let pose = b.pose_counts();
    assert!(matches!(b.twin_mut().serve(Request::SetZeros { pose_counts: pose }), Reply::Calibration(_)));
    b.ticks(2).unwrap();
    let jogs = [(Joint::Theta1, 41), (Joint::Theta1, -41), (Joint::Elbow, 41), (Joint::Elbow, -41)].map(|(j, c)| {
        let r = jog(&mut b, j, c);
        b.ticks(300).unwrap();
        r
    });
    (b, jogs)
}

#[test]
fn on_a_board_wired_as_documented_every_jog_moves_its_joint_its_torques_way() {
    // The encoders' magnets glued anywhere: the zeros come from the jig.
    let board = BoardDescription {
        theta1_encoder: board_twin::EncoderMounting { zero_count: 5000.4, reversed: false },
        elbow_encoder: board_twin::EncoderMounting { zero_count: 12000.0, reversed: false },
        ..BoardDescription::default()
    };
    let (mut b, jogs) = calibrate(board);
    for r in jogs {
        match r {
            Reply::Jogged(j) => assert_eq!(j.verdict, Ok(()), "{j:?}"),
            other => panic!("{other:?}"),
        }
    }
    assert!(!b.twin().drivers_enabled(), "every jog ends with the drivers disabled");
    match b.twin_mut().serve(Request::Status) {
        Reply::Status(s) => assert!(s.zeros_set && s.directions_checked && s.torque_limit_codes == 410, "{s:?}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(b.twin_mut().serve(Request::LiftTorqueLimit), Reply::Done);
    // New zeros are not in flash yet: the drivers stay locked out until saved.
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Refused(Refusal::LockedOut(Settings::Unsaved)));
    assert_eq!(b.twin_mut().serve(Request::Save), Reply::Done);
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Done);
}

#[test]
fn a_saved_calibration_survives_a_power_cycle_and_a_damaged_or_missing_one_locks_the_drivers_out() {
    let s = scenario();
    let board = BoardDescription {
        theta1_encoder: board_twin::EncoderMounting { zero_count: 700.0, reversed: false },
        ..BoardDescription::default()
    };
    // A board fresh from the factory: nothing in flash.
    let flash = FlashModel::erased();
    let mut b = FreeArm::with_flash(&s, board, &CalibrationSection::default(), flash.clone()).unwrap();
    let notices = b.twin_mut().take_notices();
    assert_eq!(notices.first(), Some(&Notice::Settings(Settings::Missing)), "{notices:?}");
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Refused(Refusal::LockedOut(Settings::Missing)));
    assert_eq!(
        b.twin_mut().serve(Request::Jog { joint: Joint::Theta1, code: 41, periods: 10 }),
        Reply::Refused(Refusal::ZerosNotSet),
        "the fallback's zeros are not this arm's"
    );
    let pose = b.pose_counts();
    let Reply::Calibration(cal) = b.twin_mut().serve(Request::SetZeros { pose_counts: pose }) else { panic!() };
    // Zeros alone are no calibration: the save names every step still missing.
    assert_eq!(
        b.twin_mut().serve(Request::Save),
        Reply::Refused(Refusal::Incomplete(Missing(Missing::DIRECTIONS | Missing::TARE | Missing::SPAN_T | Missing::SPAN_N)))
    );
    // The rest restored from a record (the encoders' zeros unchanged, so the
    // direction checks it claims are kept).
    let cal = CalibrationRecord { directions_checked: true, tared: true, span: [SpanStep::Measured, SpanStep::Skipped], ..cal };
    assert_eq!(b.twin_mut().serve(Request::SetCalibration(cal)), Reply::Calibration(cal));
    assert_eq!(b.twin_mut().serve(Request::Save), Reply::Done);
    match b.twin_mut().serve(Request::Status) {
        Reply::Status(st) => assert_eq!(st.settings, Settings::Saved),
        other => panic!("{other:?}"),
    }
    // Power cycle: the same flash, the record loaded.
    let mut b = FreeArm::with_flash(&s, board, &CalibrationSection::default(), flash.clone()).unwrap();
    assert_eq!(b.twin_mut().take_notices().first(), Some(&Notice::Settings(Settings::Saved)));
    assert_eq!(b.twin_mut().serve(Request::GetCalibration), Reply::Calibration(cal));
    // A damaged record (one bit of its payload): refused, the drivers locked out,
    // the enable button ignored with the reason.
    flash.bytes().borrow_mut()[12] ^= 0x10;
    let mut b = FreeArm::with_flash(&s, board, &CalibrationSection::default(), flash).unwrap();
    let corrupt = Settings::Corrupt(RecordFault::Crc);
    assert_eq!(b.twin_mut().take_notices().first(), Some(&Notice::Settings(corrupt)));
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Refused(Refusal::LockedOut(corrupt)));
    b.twin_mut().press_button(true);
    b.ticks(30).unwrap();
    b.twin_mut().press_button(false);
    assert!(!b.twin().drivers_enabled());
    assert!(b.twin_mut().take_notices().contains(&Notice::LockedOut(corrupt)));
}

#[test]
fn a_reversed_encoder_or_motor_is_refused_by_the_jog_before_any_closed_loop() {
    let reversed_encoder =
        BoardDescription { elbow_encoder: board_twin::EncoderMounting { zero_count: 0.0, reversed: true }, ..BoardDescription::default() };
    let reversed_motor =
        BoardDescription { motor1: MotorWiring { reversed: true, ..MotorWiring::default() }, ..BoardDescription::default() };
    for (board, bad) in [(reversed_encoder, Joint::Elbow), (reversed_motor, Joint::Theta1)] {
        let (mut b, jogs) = calibrate(board);
        for r in jogs {
            let Reply::Jogged(j) = r else { panic!("{r:?}") };
            let want = if j.joint == bad { Err(JogFault::WrongDirection) } else { Ok(()) };
            assert_eq!(j.verdict, want, "{j:?}");
        }
        assert_eq!(b.twin_mut().serve(Request::LiftTorqueLimit), Reply::Refused(Refusal::DirectionsNotChecked));
    }
}

#[test]
fn bring_up_requests_refuse_what_is_unsafe_or_out_of_range() {
    let mut b = bench(BoardDescription::default());
    b.ticks(3).unwrap();
    assert_eq!(b.twin_mut().serve(Request::Jog { joint: Joint::Theta1, code: 2000, periods: 10 }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin_mut().serve(Request::Jog { joint: Joint::Theta1, code: 40, periods: 0 }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin_mut().serve(Request::Span { axis: 2, newtons: 5.0 }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin_mut().serve(Request::SetZeros { pose_counts: [20000, 0] }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin_mut().serve(Request::JogResult), Reply::Refused(Refusal::NoJog));
    // Running: every calibration request is refused until the drivers are disabled.
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Done);
    b.ticks(2).unwrap();
    assert!(b.twin().drivers_enabled());
    assert_eq!(b.twin_mut().serve(Request::Tare), Reply::Refused(Refusal::DriversEnabled));
    assert_eq!(b.twin_mut().serve(Request::Jog { joint: Joint::Elbow, code: 40, periods: 10 }), Reply::Refused(Refusal::DriversEnabled));
    assert_eq!(b.twin_mut().serve(Request::Disable), Reply::Done);
    assert!(!b.twin().drivers_enabled());
    // Tare with the tip on the belt reads the contact force as zero: the span then
    // sees none of the same force.
    assert!(matches!(b.twin_mut().serve(Request::Tare), Reply::Calibration(_)));
    assert_eq!(b.twin_mut().serve(Request::Span { axis: 1, newtons: 5.0 }), Reply::Refused(Refusal::NoSpan));
}

/// Issue 44: `Restore` (a backup file's settings, `sil-host board restore`) is
/// checked by the firmware itself, with its flash record's check, and taken
/// whole or not at all: a refused one (each value out of range, another rate,
/// the drivers on) leaves the calibration, the configuration, the settings and
/// the torque limit as they were; an accepted one puts both in force, its
/// direction checks as recorded, unsaved until `Save`.
#[test]
fn a_restore_is_checked_by_the_firmware_and_taken_whole_or_not_at_all() {
    use arm_app::record::Stored;
    let mut b = bench(BoardDescription::default());
    b.ticks(3).unwrap();
    let state = |b: &mut FreeArm| {
        let Reply::Calibration(cal) = b.twin_mut().serve(Request::GetCalibration) else { panic!() };
        let Reply::Config(config) = b.twin_mut().serve(Request::GetConfig) else { panic!() };
        let Reply::Status(st) = b.twin_mut().serve(Request::Status) else { panic!() };
        (Stored { calibration: cal, config }, st.settings, st.torque_limit_codes, st.directions_checked)
    };
    let before = state(&mut b);
    assert_eq!(before.1, Settings::Saved, "the bench's flash holds the scenario's settings");
    let good = before.0;
    let mut bad: Vec<(&str, Stored, Refusal)> = Vec::new();
    let mut s = good;
    s.config.torque_limit = 50.0;
    bad.push(("torque limit 50 N m", s, Refusal::InvalidConfig));
    let mut s = good;
    s.config.observer_bandwidth = f32::NAN;
    bad.push(("a NaN gain", s, Refusal::InvalidConfig));
    let mut s = good;
    s.config.period = shared::time::Period::from_us(5000).unwrap();
    bad.push(("a rate the image does not run (200 Hz)", s, Refusal::Rate));
    let mut s = good;
    s.config.period = shared::time::Period::from_us(99).unwrap();
    bad.push(("a rate the image does not run (10.1 kHz)", s, Refusal::Rate));
    let mut s = good;
    s.calibration.zero_counts[0] = 1 << 14;
    bad.push(("a 15-bit zero", s, Refusal::OutOfRange));
    let mut s = good;
    s.calibration.load_newtons_per_count[1] = 0.0;
    bad.push(("a zero gain", s, Refusal::OutOfRange));
    let mut s = good;
    s.calibration.load_zero_counts[0] = 5000.0;
    bad.push(("a load-cell zero beyond 12 bits", s, Refusal::OutOfRange));
    let mut s = good;
    s.calibration.belt_metres_per_count = f32::INFINITY;
    bad.push(("an infinite belt scale", s, Refusal::OutOfRange));
    // Issue 52: what the scenario path refused, a restore took.
    let mut s = good;
    s.config.runaway_limits = false;
    bad.push(("the runaway limits off", s, Refusal::ProtectionOff));
    let mut s = good;
    s.config.f_n_ref = 100.0;
    bad.push(("f_n* of 100 N, four times the load cell's range", s, Refusal::InvalidConfig));
    let mut s = good;
    s.calibration.load_newtons_per_count[1] = 1e-45;
    bad.push(("a load-cell gain of 1e-45 N per count (a blind force loop)", s, Refusal::OutOfRange));
    let mut s = good;
    s.calibration.load_newtons_per_count[0] = -25.0 / 2048.0;
    bad.push(("a negative load-cell gain", s, Refusal::OutOfRange));
    let mut s = good;
    s.calibration.belt_metres_per_count = 1e-3;
    bad.push(("a belt scale of 1 mm per count (1 m/s a count)", s, Refusal::OutOfRange));
    for (what, s, why) in bad {
        assert_eq!(b.twin_mut().serve(Request::Restore(s)), Reply::Refused(why), "{what}");
        assert_eq!(state(&mut b), before, "{what}: the board unchanged");
    }
    // The same settings: nothing changes, the record stays in force.
    assert_eq!(b.twin_mut().serve(Request::Restore(good)), Reply::Done);
    assert_eq!(state(&mut b), before);
    // Other settings: both in force, unsaved, the reduced torque limit.
    let mut other = good;
    other.calibration.zero_counts = [1234, 4321];
    other.calibration.belt_metres_per_count *= 2.0;
    other.config.torque_limit = 3.0;
    assert_eq!(b.twin_mut().serve(Request::Restore(other)), Reply::Done);
    let after = state(&mut b);
    assert_eq!(after.0, other);
    assert_eq!((after.1, after.2), (Settings::Unsaved, arm_app::bringup::REDUCED_TORQUE_CODES));
    assert_eq!(after.3, good.calibration.directions_checked, "the steps as recorded");
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Refused(Refusal::LockedOut(Settings::Unsaved)));
    // Back to the first, then saved: as before, but for the limit (lifted by the operator).
    assert_eq!(b.twin_mut().serve(Request::Restore(good)), Reply::Done);
    assert_eq!(b.twin_mut().serve(Request::Save), Reply::Done);
    assert_eq!(b.twin_mut().serve(Request::LiftTorqueLimit), Reply::Done);
    assert_eq!(state(&mut b), before);
    // Running: refused.
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Done);
    b.ticks(2).unwrap();
    assert!(b.twin().drivers_enabled());
    assert_eq!(b.twin_mut().serve(Request::Restore(other)), Reply::Refused(Refusal::DriversEnabled));
    assert_eq!(b.twin_mut().serve(Request::Disable), Reply::Done);
    assert_eq!(state(&mut b).0, good);
}

/// Issue 52 (1): a board never runs without its runaway limits. `Configure`
/// refuses them off, naming why (`Refusal::ProtectionOff`), the configuration
/// in force unchanged; a flash record holding them off is refused at reset,
/// the drivers locked out saying why; and an application whose compiled-in
/// configuration has them off does not start.
#[test]
fn the_runaway_limits_cannot_be_turned_off_on_a_board() {
    let mut b = bench(BoardDescription::default());
    b.ticks(3).unwrap();
    let Reply::Config(before) = b.twin_mut().serve(Request::GetConfig) else { panic!() };
    assert!(before.runaway_limits);
    let off = firmware::Config { runaway_limits: false, ..before };
    assert_eq!(b.twin_mut().serve(Request::Configure(off)), Reply::Refused(Refusal::ProtectionOff));
    assert_eq!(b.twin_mut().serve(Request::GetConfig), Reply::Config(before), "the configuration in force unchanged");
    let Reply::Status(st) = b.twin_mut().serve(Request::Status) else { panic!() };
    assert_eq!(st.settings, Settings::Saved);
    // Off, and otherwise invalid: the protection is named first.
    let worse = firmware::Config { f_n_ref: 100.0, ..off };
    assert_eq!(b.twin_mut().serve(Request::Configure(worse)), Reply::Refused(Refusal::ProtectionOff));
    assert_eq!(
        b.twin_mut().serve(Request::Configure(firmware::Config { f_n_ref: 100.0, ..before })),
        Reply::Refused(Refusal::InvalidConfig)
    );

    // A record saved with them off (by an earlier image, or written by hand):
    // refused at reset, the drivers locked out, the button ignored with the reason.
    let s = scenario();
    let cal = CalibrationSection::default();
    let flash = FlashModel::brought_up(&cal.arm_calibration(), off).unwrap();
    let mut b = FreeArm::with_flash(&s, BoardDescription::default(), &cal, flash).unwrap();
    let refused = Settings::Corrupt(RecordFault::ProtectionOff);
    assert_eq!(b.twin_mut().take_notices().first(), Some(&Notice::Settings(refused)));
    assert_eq!(b.twin_mut().serve(Request::Enable), Reply::Refused(Refusal::LockedOut(refused)));
    assert!(refused.describe().contains("runaway limits off"), "{}", refused.describe());
    let Reply::Config(fallback) = b.twin_mut().serve(Request::GetConfig) else { panic!() };
    assert!(fallback.runaway_limits, "the compiled-in fallback is in force, its limits on");

    // A compiled-in configuration with them off: the application does not start.
    let twin = board_twin::BoardTwin::with_flash(BoardDescription::default(), FlashModel::erased(), off, &cal.arm_calibration(), 1, 0.0);
    assert!(matches!(twin, Err(board_twin::TwinError::Start(arm_app::StartError::ProtectionOff))), "{:?}", twin.err());
}

/// Issue 52 (3): `save` said "done" after a reset had discarded the `Configure`
/// before it (the reset reloads the flash record): with the record in force
/// there is nothing to save, and `Save` says so (`Refusal::NothingToSave`).
#[test]
fn a_save_after_a_reset_that_discarded_the_change_says_nothing_was_saved() {
    let mut b = bench(BoardDescription::default());
    b.ticks(3).unwrap();
    let Reply::Config(saved) = b.twin_mut().serve(Request::GetConfig) else { panic!() };
    let changed = firmware::Config { f_n_ref: 7.0, ..saved };
    assert_eq!(b.twin_mut().serve(Request::Configure(changed)), Reply::Done);
    let Reply::Status(st) = b.twin_mut().serve(Request::Status) else { panic!() };
    assert_eq!(st.settings, Settings::Unsaved);
    // The reset button: the record reloaded, the change gone.
    b.reset().unwrap();
    b.ticks(3).unwrap();
    assert_eq!(b.twin_mut().serve(Request::GetConfig), Reply::Config(saved));
    assert_eq!(b.twin_mut().serve(Request::Save), Reply::Refused(Refusal::NothingToSave));
    // Sent again, it saves, and survives the next reset.
    assert_eq!(b.twin_mut().serve(Request::Configure(changed)), Reply::Done);
    assert_eq!(b.twin_mut().serve(Request::Save), Reply::Done);
    b.reset().unwrap();
    b.ticks(3).unwrap();
    assert_eq!(b.twin_mut().serve(Request::GetConfig), Reply::Config(changed));
}
