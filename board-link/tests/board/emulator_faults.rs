//! Faults at the register level on the flashed image (issue 38): each injected
//! into the emulated board under the unmodified `arm` ELF, each seen where the
//! firmware sees it (the tick's status word in the image's monitor block) and
//! said in its defmt log (the RTT buffer, decoded with the image's own table).

use super::ask;
use arm_app::{
    Settings,
    bringup::{CalibrationRecord, Refusal, Reply, Request},
    record::{RecordFault, Stored},
};
use board_emulator::{EmuError, EmulatedBoard, RegisterFault, SpiFaults};
use board_link::{emulator_link::default_image, free_arm::FreeArm};
use board_twin::{BusFaults, EncoderFaults, FlashModel};
use rig::{
    pil_link::decode_log,
    scenario::{DEFAULT_TOML, Scenario},
    setup::firmware_config,
};
use shared::wire::status;

/// The arm hanging free on the emulated board, its record saved, a few ticks in.
fn bench() -> FreeArm<EmulatedBoard> {
    let s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    let stored = Stored { calibration: CalibrationRecord::brought_up(&s.calibration.arm_calibration()), config: firmware_config(&s) };
    bench_with(&FlashModel::saved(&stored).unwrap())
}

fn bench_with(flash: &FlashModel) -> FreeArm<EmulatedBoard> {
    let s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    let image = default_image();
    assert!(image.exists(), "{}: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let mut arm = FreeArm::emulated(&s, s.board, flash, &image).unwrap();
    arm.ticks(5).unwrap();
    arm
}

fn status_now(arm: &FreeArm<EmulatedBoard>) -> u32 {
    arm.board().monitor().expect("the image ticks").command.status
}

fn log(arm: &mut FreeArm<EmulatedBoard>) -> String {
    let bytes = arm.board_mut().take_rtt();
    decode_log(&default_image(), &bytes).unwrap().iter().map(|l| format!("[{}] {}\n", l.level, l.message)).collect()
}

/// Runs one tick with `inject` applied first; returns the tick's status word and the log since.
fn one_tick(arm: &mut FreeArm<EmulatedBoard>, inject: impl FnOnce(&mut FreeArm<EmulatedBoard>)) -> (u32, String) {
    let _ = log(arm);
    assert_eq!(status_now(arm) & status::BAD_FRAME, 0, "a clean frame before the fault");
    inject(arm);
    arm.tick().unwrap();
    (status_now(arm), log(arm))
}

#[test]
fn an_spi_overrun_makes_the_encoders_reading_invalid_for_that_frame() {
    let mut arm = bench();
    let (st, log) = one_tick(&mut arm, |a| a.board_mut().set_spi_faults(SpiFaults { overrun: true, mode_fault: false }));
    assert_ne!(st & status::BAD_FRAME, 0, "{st:#x}");
    assert!(log.contains("invalid readings") && log.contains("theta1 true"), "{log}");
    arm.ticks(2).unwrap();
    assert_eq!(status_now(&arm) & status::BAD_FRAME, 0, "the next frames are good again");
}

#[test]
fn a_mode_fault_disables_spi1_and_every_frame_after_is_invalid() {
    // MODF clears SPE and MSTR (RM0090 28.4.8) and the image's driver does not
    // re-enable SPI1: every frame after is invalid (the firmware holds its safe
    // state; a board then needs a reset).
    let mut arm = bench();
    let (st, log) = one_tick(&mut arm, |a| a.board_mut().set_spi_faults(SpiFaults { overrun: false, mode_fault: true }));
    assert_ne!(st & status::BAD_FRAME, 0, "{st:#x}");
    assert!(log.contains("theta1 true, elbow true"), "{log}");
    for _ in 0..5 {
        arm.tick().unwrap();
        assert_ne!(status_now(&arm) & status::BAD_FRAME, 0, "SPI1 stays off");
    }
}

#[test]
fn a_missing_end_of_conversion_makes_the_load_cells_readings_invalid() {
    let mut arm = bench();
    let (st, log) = one_tick(&mut arm, |a| a.set_faults(BusFaults { missing_conversion: true, ..BusFaults::default() }));
    assert_ne!(st & status::BAD_FRAME, 0, "{st:#x}");
    assert!(log.contains("f_t true, f_n true"), "{log}");
}

#[test]
fn the_drivers_fault_line_reaches_the_frame() {
    let mut arm = bench();
    let (st, log) = one_tick(&mut arm, |a| a.set_faults(BusFaults { driver_fault: true, ..BusFaults::default() }));
    assert_ne!(st & status::BAD_FRAME, 0, "{st:#x}");
    assert!(log.contains("driver fault true"), "{log}");
}

#[test]
fn a_magnet_lost_frame_makes_that_encoder_invalid() {
    let mut arm = bench();
    let lost = EncoderFaults { magnet_lost: true, ..EncoderFaults::default() };
    let (st, log) = one_tick(&mut arm, |a| a.set_faults(BusFaults { encoders: [EncoderFaults::default(), lost], ..BusFaults::default() }));
    assert_ne!(st & status::BAD_FRAME, 0, "{st:#x}");
    assert!(log.contains("elbow true"), "{log}");
}

#[test]
fn a_stalled_loop_is_reset_by_the_watchdog_and_comes_back_locked_until_the_button() {
    let mut arm = bench();
    let _ = log(&mut arm);
    arm.board_mut().inject(RegisterFault::TickLost);
    // The tick interrupt is gone: no feed; the IWDG's 5 ms (5 periods) run out.
    let e = arm.ticks(200).unwrap_err().to_string();
    assert!(e.contains("watchdog"), "{e}");
    // The image boots again, says why, and keeps the drivers off.
    let back = arm.board_mut().run_for(20_000_000).unwrap();
    let l = log(&mut arm);
    let m = arm.board().machine();
    let pk = |a| board_emulator::checks::peek(m, a);
    assert!(
        back,
        "the image ticks again after its reset: pc {:#x}, log {l}, error {e}, CSR {:#x} DIER {:#x} monitor {:?} t {} ms",
        arm.board().core().cpu.pc(),
        pk(0x4002_3874),
        pk(0x4000_000C),
        arm.board().monitor().map(|m| m.ticks),
        arm.board().now_ns() / 1_000_000
    );
    arm.ticks(3).unwrap();
    let log = l + &log(&mut arm);
    assert!(log.contains("reset by the watchdog"), "{log}");
    assert!(log.contains("settings: loaded from flash"), "the record comes back from the emulated flash: {log}");
    assert_eq!(arm.board().monitor().unwrap().drivers_enabled, 0, "drivers disabled until the enable button");
}

#[test]
fn a_watchdog_reset_is_an_error_naming_it_not_a_silent_restart() {
    let mut arm = bench();
    arm.board_mut().inject(RegisterFault::TickLost);
    let mut err = None;
    for _ in 0..200 {
        if let Err(e) = arm.tick() {
            err = Some(e.to_string());
            break;
        }
    }
    let e = err.expect("the reset is reported");
    assert!(e.contains(&EmuError::WatchdogReset { period: 0 }.to_string()[..40]), "{e}");
}

#[test]
fn a_record_the_image_saves_comes_back_from_the_emulated_flash_after_a_reset() {
    // A board fresh from the factory: nothing in flash.
    let mut arm = bench_with(&FlashModel::erased());
    let Reply::Status(st) = ask(&mut arm, Request::Status) else { panic!() };
    assert_eq!(st.settings, Settings::Missing);
    let s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    let cal = CalibrationRecord::brought_up(&s.calibration.arm_calibration());
    assert_eq!(ask(&mut arm, Request::SetCalibration(cal)), Reply::Calibration(cal));
    assert_eq!(ask(&mut arm, Request::Save), Reply::Done, "the image erases sector 4 and programs the record");
    // A reset (the watchdog's): the image loads what it wrote.
    arm.board_mut().inject(RegisterFault::TickLost);
    assert!(arm.ticks(200).unwrap_err().to_string().contains("watchdog"));
    assert!(arm.board_mut().run_for(20_000_000).unwrap());
    let _ = log(&mut arm);
    let Reply::Status(st) = ask(&mut arm, Request::Status) else { panic!() };
    assert_eq!(st.settings, Settings::Saved, "{st:?}");
    assert_eq!(ask(&mut arm, Request::GetCalibration), Reply::Calibration(cal));
}

#[test]
fn a_corrupt_record_keeps_the_emulated_images_drivers_locked_out() {
    let s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    let stored = Stored { calibration: CalibrationRecord::brought_up(&s.calibration.arm_calibration()), config: firmware_config(&s) };
    let flash = FlashModel::saved(&stored).unwrap();
    flash.bytes().borrow_mut()[12] ^= 0x10;
    let mut arm = bench_with(&flash);
    let log = log(&mut arm);
    assert!(log.contains("CRC-32C mismatch"), "{log}");
    assert_eq!(ask(&mut arm, Request::Enable), Reply::Refused(Refusal::LockedOut(Settings::Corrupt(RecordFault::Crc))));
}

/// The encoders by DMA (issue 56): each of the acquisition's faults, injected
/// on DMA2 under the unmodified image (a TEIF on the TX stream, seen at the
/// deadline; an FEIF or a DMEIF on the RX stream, seen in its interrupt; a
/// stalled transfer, stopped at the deadline), makes both encoders' readings
/// of that period invalid and is logged by name; a clean period after one
/// fault reads again; three periods in a row latch the safe state with the
/// acquisition's own reason (13).
#[test]
fn every_dma_fault_is_named_and_makes_that_periods_encoders_invalid() {
    use arm_app::AcquisitionFault as F;
    for fault in [F::TransferError, F::FifoError, F::DirectModeError, F::Timeout] {
        // On the raised, stopped belt, reset there: hanging over the lowered
        // belt the consistency check latches its SensorFault within 3 periods
        // of a start, faults or not (`dma_faults.rs`).
        let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
        s.plant.v_belt = 0.0;
        let stored = Stored { calibration: CalibrationRecord::brought_up(&s.calibration.arm_calibration()), config: firmware_config(&s) };
        let mut arm = FreeArm::emulated(&s, s.board, &FlashModel::saved(&stored).unwrap(), &default_image()).unwrap();
        arm.move_belt(true).unwrap();
        arm.reset().unwrap();
        arm.ticks(5).unwrap();
        assert_eq!(status_now(&arm) & (status::SAFE_STATE | status::BAD_FRAME), 0, "{fault:?}: clean on the belt");
        let faulty = BusFaults { acquisition: Some(fault), ..BusFaults::default() };
        let (st, log) = one_tick(&mut arm, |a| a.set_faults(faulty));
        assert_ne!(st & status::BAD_FRAME, 0, "{fault:?}: {st:#x}");
        assert!(log.contains(fault.describe()) && log.contains("theta1 true, elbow true"), "{fault:?}: {log}");
        arm.set_faults(BusFaults::default());
        arm.ticks(2).unwrap();
        assert_eq!(status_now(&arm) & status::BAD_FRAME, 0, "{fault:?}: the next frames are good again");
        arm.set_faults(faulty);
        arm.ticks(3).unwrap();
        let st = status_now(&arm);
        assert_ne!(st & status::SAFE_STATE, 0, "{fault:?}: {st:#x}");
        // Three faulted periods in a row: the acquisition's own reason, before
        // the bad-frame rule and the consistency check (which the held
        // encoders trip on the hanging arm) can name another.
        let reason = firmware::SafeReason::from_status(st);
        assert_eq!(reason, Some(firmware::SafeReason::Acquisition), "{fault:?}: {st:#x}");
    }
}
