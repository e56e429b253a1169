//! The device models against the drivers that talk to them on the board (the
//! drivers' own tests hold them to transaction lists from the datasheets; here
//! the models are held to the drivers, and to the datasheets' numbers).

use std::sync::{Arc, Mutex};

use board_twin::{
    BoardDescription,
    adc::adc_count,
    as5047p::As5047pModel,
    bench::{Bench, Shared, lock},
    counter::CounterModel,
    motor_stage::{PinModel, PwmModel, Wire, joint_torques},
};
use drivers::{
    As5047p, BeltEncoder, Motor, MotorStage,
    as5047p::{Error, read_command},
};
use embedded_hal::spi::SpiDevice;
use proptest::prelude::*;

fn bench() -> Shared {
    Arc::new(Mutex::new(Bench::default()))
}

#[test]
fn the_encoder_answers_in_the_next_frame_with_even_parity() {
    let b = bench();
    lock(&b).magnet_counts[0] = 1234.4;
    let mut spi = As5047pModel::new(b.clone(), 0);
    let mut w = [read_command(0x3FFF)];
    spi.transfer_in_place(&mut w).unwrap();
    assert_eq!(w[0], 0, "power-up: the pipeline holds NOP's answer");
    let mut w = [read_command(0x0000)];
    spi.transfer_in_place(&mut w).unwrap();
    assert_eq!(w[0] & 0x3FFF, 1234, "the angle, in the frame after its command");
    assert!(w[0].count_ones().is_multiple_of(2), "{:#06x}: even parity", w[0]);
}

proptest! {
    /// The driver reads the magnet's angle rounded to the nearest of 2^14 counts,
    /// wrapped, for any angle and any number of turns.
    #[test]
    fn the_driver_reads_the_quantised_angle(counts in -1e6f64..1e6) {
        let b = bench();
        lock(&b).magnet_counts[1] = counts;
        let mut enc = As5047p::new(As5047pModel::new(b, 1));
        prop_assert!(enc.check_ready().is_ok());
        let want = (counts.round().rem_euclid(16384.0)) as u16;
        prop_assert_eq!(enc.sample().unwrap(), want);
    }
}

#[test]
fn bus_faults_reach_the_driver_as_its_errors_and_clear_when_they_end() {
    let b = bench();
    lock(&b).magnet_counts[0] = 100.0;
    let mut enc = As5047p::new(As5047pModel::new(b.clone(), 0));
    enc.check_ready().unwrap();
    lock(&b).encoder_faults[0].spi_error = true;
    assert!(matches!(enc.sample(), Err(Error::Bus(_))));
    lock(&b).encoder_faults[0].spi_error = false;
    lock(&b).encoder_faults[0].parity_error = true;
    assert!(matches!(enc.sample(), Err(Error::Parity { .. })));
    lock(&b).encoder_faults[0].parity_error = false;
    lock(&b).encoder_faults[0].magnet_lost = true;
    assert_eq!(enc.sample(), Err(Error::Magnet { too_strong: false, too_weak: true }));
    lock(&b).encoder_faults[0].magnet_lost = false;
    assert_eq!(enc.sample(), Ok(100), "the next sample after the faults is good");
    // A command of odd parity latches PARERR; the next answer carries EF and the
    // driver reads (and so clears) ERRFL.
    let mut raw = As5047pModel::new(b.clone(), 0);
    raw.transfer_in_place(&mut [read_command(0x3FFF) ^ 1]).unwrap();
    let mut enc = As5047p::new(raw);
    assert_eq!(enc.angle(), Err(Error::ErrorFlag { errfl: 1 << 2 }));
    assert_eq!(enc.angle(), Ok(100), "ERRFL was cleared by reading it");
}

#[test]
fn a_stuck_encoder_repeats_its_angle() {
    let b = bench();
    lock(&b).magnet_counts[0] = 500.0;
    let mut enc = As5047p::new(As5047pModel::new(b.clone(), 0));
    assert_eq!(enc.sample(), Ok(500));
    lock(&b).encoder_faults[0].stuck = true;
    lock(&b).magnet_counts[0] = 900.0;
    assert_eq!(enc.sample(), Ok(500));
    lock(&b).encoder_faults[0].stuck = false;
    assert_eq!(enc.sample(), Ok(900));
}

#[test]
fn the_adc_saturates_at_its_rails_and_the_counter_wraps_at_16_bits() {
    assert_eq!(adc_count(2048.0, 81.92, 0.0), 2048);
    assert_eq!(adc_count(2048.0, 81.92, 25.0), 4095, "+25 N is 2048 counts above mid-scale: the rail");
    assert_eq!(adc_count(2048.0, 81.92, -30.0), 0);
    assert_eq!(adc_count(2048.0, 81.92, f64::NAN), 0);
    assert_eq!(drivers::belt::count_at(0.0, 1e6), 0);
    assert_eq!(drivers::belt::count_at(-1e-6, 1e6), 0xFFFF, "one count back from 0 wraps");
    assert_eq!(drivers::belt::count_at(0.065536, 1e6), 0, "2^16 counts is a full wrap");
    // The driver's speed across the wrap: 400 counts in one 1 ms period is 400 mm/s.
    let b = bench();
    lock(&b).belt_count = 0xFF00;
    let mut enc = BeltEncoder::new(CounterModel::new(b.clone()), 1e-6, 1e-3).unwrap();
    lock(&b).belt_count = 0xFF00u16.wrapping_add(400);
    assert_eq!(enc.speed_mm_s(), Ok(400));
}

#[test]
fn the_motor_stage_makes_signed_torque_only_when_enabled_and_healthy() {
    let b = bench();
    let board = BoardDescription::default();
    let m1 = Motor::new(PwmModel::new(b.clone(), 0, board.pwm_max_duty), PinModel::new(b.clone(), Wire::Dir1));
    let m2 = Motor::new(PwmModel::new(b.clone(), 1, board.pwm_max_duty), PinModel::new(b.clone(), Wire::Dir2));
    let mut stage = MotorStage::new(m1, m2, PinModel::new(b.clone(), Wire::Enable), PinModel::new(b.clone(), Wire::Fault)).unwrap();
    stage.apply([1024, -2048]).unwrap();
    assert_eq!(joint_torques(&b, &board), [0.0, 0.0], "disabled: no torque");
    stage.enable().unwrap();
    stage.apply([1024, -2048]).unwrap();
    assert_eq!(joint_torques(&b, &board), [2.5, -5.0], "half and full scale, signed by the direction pin");
    let reversed = BoardDescription { motor2: board_twin::MotorWiring { reversed: true, ..board.motor2 }, ..board };
    assert_eq!(joint_torques(&b, &reversed), [2.5, 5.0], "a motor wired the other way");
    lock(&b).driver_fault = true;
    assert_eq!(joint_torques(&b, &board), [0.0, 0.0], "nFAULT: the drivers make nothing");
    assert!(stage.fault_asserted().unwrap());
    stage.disable().unwrap();
    assert!(stage.enable().is_err(), "the stage will not enable on a fault");
}
