//! Bring-up on the board twin (issue 23; docs/board.md "Bring-up"): the `arm`
//! application's bring-up requests, served between ticks while the simulated
//! arm moves under the torques it makes. As the procedure asks, the belt is
//! lowered below the hanging tip (here the base 0.4199 m above it: the arm at
//! rest, its elbow bent by the spring, clears it by a few millimetres, and a jog
//! lifts the tip) and the arm hangs at rest; the test knows the pose's joint
//! counts from the plant's state, as the calibration jig's drawing gives them.

use arm_app::{
    Joint,
    bringup::{JogFault, Refusal, Reply, Request},
};
use board_twin::{ArmState, BoardDescription, BoardTwin, BusFaults, MotorWiring};
use plant::{Hold, NoObserver, Plant, SimConfig};
use rig::{
    calibration::CalibrationSection,
    scenario::{DEFAULT_TOML, Scenario},
    setup::{firmware_config, plant_params},
};

/// The arm on a stopped belt, its board, and the twin on it.
struct Bench {
    plant: Plant,
    twin: BoardTwin,
    u: [f64; 2],
    ts: f64,
    /// The state the devices sensed at the last tick.
    sensed: [f64; 4],
}

impl Bench {
    fn new(board: BoardDescription) -> Self {
        let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
        s.plant.v_belt = 0.0;
        let params = shared::Params { h: 0.4199, ..plant_params(&s) };
        let plant = Plant::new(params, SimConfig::default(), [0.0, 0.0, 0.3, 0.0], 0.0, [0.0; 2]).unwrap();
        let twin = BoardTwin::new(board, firmware_config(&s), &CalibrationSection::default().arm_calibration(), 1, 0.02).unwrap();
        let mut b = Self { plant, twin, u: [0.0; 2], ts: s.timing.period().as_secs_f64(), sensed: [0.0; 4] };
        // Hanging from straight down, the spring between the links bends the elbow
        // to its rest: 40 s of light damping bring the arm to rest.
        b.ticks(40_000);
        b
    }

    /// One period: the devices sense the arm, the tick runs, the arm moves.
    fn tick(&mut self) {
        self.sensed = self.plant.state();
        let arm = ArmState { x: self.sensed, f: self.plant.contact_force(self.u), belt_travel_m: 0.0 };
        self.u = self.twin.tick(&arm, &BusFaults::default(), true);
        self.plant.advance(&Hold(self.u), self.ts, &mut NoObserver).unwrap();
    }

    fn ticks(&mut self, n: usize) {
        (0..n).for_each(|_| self.tick());
    }

    /// The pose's joint counts `[theta1, theta2 - theta1]` (the jig's drawing).
    fn pose_counts(&self) -> [u16; 2] {
        let x = self.sensed;
        [x[0], x[2] - x[0]].map(shared::wire::encode_angle)
    }

    /// Jogs `joint` and runs the ticks until its result is there.
    fn jog(&mut self, joint: Joint, code: i16) -> Reply {
        assert_eq!(self.twin.serve(Request::Jog { joint, code, periods: 100 }), Reply::Done);
        for _ in 0..200 {
            self.tick();
            match self.twin.serve(Request::JogResult) {
                Reply::Refused(Refusal::Busy) => {}
                other => return other,
            }
        }
        panic!("the jog never ended")
    }
}

/// A board mounted some way, zeroed at the jig, then each joint jogged both ways.
fn calibrate(board: BoardDescription) -> (Bench, [Reply; 4]) {
    let mut b = Bench::new(board);
    b.ticks(5);
    let pose = b.pose_counts();
    assert!(matches!(b.twin.serve(Request::SetZeros { pose_counts: pose }), Reply::Calibration(_)));
    b.ticks(2);
    let jogs = [(Joint::Theta1, 41), (Joint::Theta1, -41), (Joint::Elbow, 41), (Joint::Elbow, -41)].map(|(j, c)| {
        let r = b.jog(j, c);
        b.ticks(300);
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
    assert!(!b.twin.drivers_enabled(), "every jog ends with the drivers disabled");
    match b.twin.serve(Request::Status) {
        Reply::Status(s) => assert!(s.zeros_set && s.directions_checked && s.torque_limit_codes == 410, "{s:?}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(b.twin.serve(Request::LiftTorqueLimit), Reply::Done);
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
        assert_eq!(b.twin.serve(Request::LiftTorqueLimit), Reply::Refused(Refusal::DirectionsNotChecked));
    }
}

#[test]
fn bring_up_requests_refuse_what_is_unsafe_or_out_of_range() {
    let mut b = Bench::new(BoardDescription::default());
    b.ticks(3);
    assert_eq!(b.twin.serve(Request::Jog { joint: Joint::Theta1, code: 2000, periods: 10 }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin.serve(Request::Jog { joint: Joint::Theta1, code: 40, periods: 0 }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin.serve(Request::Span { axis: 2, newtons: 5.0 }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin.serve(Request::SetZeros { pose_counts: [20000, 0] }), Reply::Refused(Refusal::OutOfRange));
    assert_eq!(b.twin.serve(Request::JogResult), Reply::Refused(Refusal::NoJog));
    // Running: every calibration request is refused until the drivers are disabled.
    assert_eq!(b.twin.serve(Request::Enable), Reply::Done);
    b.ticks(2);
    assert!(b.twin.drivers_enabled());
    assert_eq!(b.twin.serve(Request::Tare), Reply::Refused(Refusal::DriversEnabled));
    assert_eq!(b.twin.serve(Request::Jog { joint: Joint::Elbow, code: 40, periods: 10 }), Reply::Refused(Refusal::DriversEnabled));
    assert_eq!(b.twin.serve(Request::Disable), Reply::Done);
    assert!(!b.twin.drivers_enabled());
    // Tare with the tip on the belt reads the contact force as zero: the span then
    // sees none of the same force.
    assert!(matches!(b.twin.serve(Request::Tare), Reply::Calibration(_)));
    assert_eq!(b.twin.serve(Request::Span { axis: 1, newtons: 5.0 }), Reply::Refused(Refusal::NoSpan));
}
