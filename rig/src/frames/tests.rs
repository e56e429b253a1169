//! The frames table's rows: a frame, its truth and its answer back bit for bit.

use super::*;

fn answered() -> (SensorFrame, Exchange) {
    let frame = SensorFrame {
        t_us: 1_234_000,
        seq: 1234,
        theta1_count: 16383,
        elbow_count: 7,
        f_t_code: -2048,
        f_n_code: 2047,
        belt_count: -400,
        flags: 0x20,
    };
    let command = ActuatorCommand {
        t_sent_us: 1_234_050,
        seq: 1234,
        u1_code: -3,
        u2_code: 2047,
        status: 0x11,
        step_ticks: 99,
        overruns: 2,
        reserved: 0,
    };
    let telemetry = FirmwareTelemetry {
        seq: 1234,
        status: 0x11,
        z_t_ref: 0.1,
        f_n_ref: -3.5e-8,
        q: [1.0e-30, -2.0],
        qd: [f32::MAX, f32::MIN_POSITIVE],
        f: [0.3, 7.0],
        u_raw: [f32::from_bits(1), -0.0],
    };
    (frame, Exchange::Answered { command, telemetry, at_stamp: false })
}

fn truth() -> GroundTruth {
    GroundTruth { t: 1.234, seq: 1234, x: [0.1, -2.5, 1e-300, f64::MIN_POSITIVE], f: [-0.0, 9.75], ..GroundTruth::default() }
}

#[test]
fn the_frame_comes_back_bit_for_bit() {
    let (frame, exchange) = answered();
    let row = FrameRow::of(&frame, &truth(), &exchange);
    assert_eq!(row.frame(), frame);
    let t = row.truth();
    assert_eq!(
        (t.t.to_bits(), t.seq, t.x.map(f64::to_bits), t.f.map(f64::to_bits)),
        (truth().t.to_bits(), 1234, truth().x.map(f64::to_bits), truth().f.map(f64::to_bits))
    );
    assert_eq!(row.first_difference(&row), None);
    // Every f32 of the telemetry survives f64 exactly, -0.0 and a subnormal included.
    assert_eq!((row.u1_raw as f32).to_bits(), 1);
    assert_eq!((row.u2_raw as f32).to_bits(), (-0.0f32).to_bits());
}

#[test]
fn a_difference_in_the_last_bit_of_any_signal_is_found() {
    let (frame, exchange) = answered();
    let row = FrameRow::of(&frame, &truth(), &exchange);
    let names: Vec<_> = row.signals().iter().map(|(n, _)| *n).collect();
    for (i, name) in names.iter().enumerate() {
        let mut other = row;
        match *name {
            "answer" => other.answer = Answer::Dropped,
            "u1_code" => other.u1_code ^= 1,
            "u2_code" => other.u2_code ^= 1,
            "status" => other.status ^= 1,
            "overruns" => other.overruns ^= 1,
            _ => {
                let field = match *name {
                    "z_t_ref" => &mut other.z_t_ref,
                    "f_n_ref" => &mut other.f_n_ref,
                    "q1" => &mut other.q1,
                    "q2" => &mut other.q2,
                    "qd1" => &mut other.qd1,
                    "qd2" => &mut other.qd2,
                    "f_t_meas" => &mut other.f_t_meas,
                    "f_n_meas" => &mut other.f_n_meas,
                    "u1_raw" => &mut other.u1_raw,
                    _ => &mut other.u2_raw,
                };
                *field = f64::from(f32::from_bits((*field as f32).to_bits() ^ 1));
            }
        }
        let (found, _, _) = row.first_difference(&other).unwrap_or_else(|| panic!("{name}: not found"));
        assert_eq!(found, names[i]);
    }
}

#[test]
fn no_answer_and_a_lost_one_are_told_apart() {
    let (frame, exchange) = answered();
    let Exchange::Answered { command, telemetry, .. } = exchange else { unreachable!() };
    let dropped = FrameRow::of(&frame, &truth(), &Exchange::Dropped { command, telemetry });
    let none = FrameRow::of(&frame, &truth(), &Exchange::NoAnswer);
    assert_eq!(dropped.answer, Answer::Dropped);
    assert_eq!((none.answer, none.u1_code, none.u1_raw), (Answer::None, 0, 0.0));
    assert_eq!(FrameRow::of(&frame, &truth(), &exchange).first_difference(&dropped).map(|d| d.0), Some("answer"));
}
