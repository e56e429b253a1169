//! The encoders' acquisition faults over random sequences (issue 56), on both
//! boards: the board twin (the application compiled for the host, its
//! acquisition at bus level) and the unmodified `arm` image on the emulated
//! board (DMA2 at register level, the faults injected on its streams).
//!
//! Each case is a sequence of periods, each clean or with one fault, on the
//! arm whose record is saved, stood on the raised (stopped) belt, its board
//! reset there and its drivers enabled: the closed loop (hanging over the
//! lowered belt, the consistency check latches `SensorFault` within 3 periods
//! of a start, the encoders putting the tip below the belt line the firmware
//! is configured with; held on the belt with the drivers off, the wiring check
//! can latch `Miswired` a few periods after a fault, the observer having
//! predicted a motion under torques that were never applied). Checked against a model of the rule
//! (docs/board.md "The encoders by DMA"), period by period: a faulted period's
//! frame is bad (`BAD_FRAME`), a clean one is not; `bad_frame_limit` (3)
//! faulted periods in a row latch the safe state with the acquisition's own
//! reason (13, `SafeReason::Acquisition`), and nothing else does; the safe
//! state then holds. The twin and the image give the same status bits.
//!
//! From a scenario (issue 66): each acquisition fault as a `[[faults]]` entry
//! (`dma_transfer_error`, `dma_fifo_error`, `dma_direct_mode_error`,
//! `dma_late_transfer`, `stuck_chip_select` of either encoder), run in closed
//! loop with the plant on `--link twin` and `--link emulator`: one faulted
//! period is held and the run goes on, three latch `Acquisition` in the third,
//! the same period and the same trace, bit for bit, on both boards.

use arm_app::{
    AcquisitionFault as F,
    bringup::{Reply, Request},
    record::Stored,
};
use board_emulator::EmulatedBoard;
use board_link::{
    emulator_link::{EmulatorLink, default_image},
    free_arm::{ArmBoard, FreeArm},
    twin_link::TwinLink,
};
use board_twin::{BusFaults, FlashModel};
use firmware::{
    SafeReason,
    pil::{MAX_FRAME, decode, encode},
};
use proptest::{collection::vec, option, prelude::*};
use rig::{
    calibration::CalibrationSection,
    record::{PeriodRecord, RunError},
    run_loop,
    scenario::{DEFAULT_TOML, Scenario},
    setup::firmware_config,
};
use shared::wire::status;

/// The faults the emulated DMA2 makes, and a stuck chip select (theta1's PA4
/// reads low in GPIOA's IDR: `board_emulator::widen::StuckLow`).
const EMULATED: [F; 5] = [F::TransferError, F::FifoError, F::DirectModeError, F::Timeout, F::StuckChipSelect];
/// Every fault the twin makes.
const TWIN: [F; 5] = [F::TransferError, F::FifoError, F::DirectModeError, F::Timeout, F::StuckChipSelect];

/// The status bits the rule decides: the safe state, its reason, the bad frame.
const RULED: u32 = status::SAFE_STATE | status::BAD_FRAME | (0xFF << status::REASON_SHIFT);

fn scenario() -> (Scenario, FlashModel) {
    let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    s.plant.v_belt = 0.0;
    let stored = Stored {
        calibration: arm_app::bringup::CalibrationRecord::brought_up(&s.calibration.arm_calibration()),
        config: firmware_config(&s),
    };
    let flash = FlashModel::saved(&stored).unwrap();
    (s, flash)
}

/// The status bits the rule expects after each period of `faults`.
fn expected(faults: &[Option<F>]) -> Vec<u32> {
    let limit = u32::from(firmware::Config::default().bad_frame_limit);
    let mut run = 0;
    let mut safe = false;
    faults
        .iter()
        .map(|f| {
            run = if f.is_some() { run + 1 } else { 0 };
            safe |= run >= limit;
            if safe {
                status::SAFE_STATE
                    | ((SafeReason::Acquisition as u32) << status::REASON_SHIFT)
                    | if f.is_some() { status::BAD_FRAME } else { 0 }
            } else if f.is_some() {
                status::BAD_FRAME
            } else {
                0
            }
        })
        .collect()
}

/// Stands the arm on the raised (stopped) belt, resets its board there,
/// enables the drivers (the bring-up protocol's `Enable`, on the line) and
/// runs the closed loop a few periods.
fn on_the_belt<B: ArmBoard>(arm: &mut FreeArm<B>) {
    arm.move_belt(true).unwrap();
    arm.reset().unwrap();
    arm.ticks(5).unwrap();
    let mut buf = [0u8; MAX_FRAME];
    let frame = encode(&Request::Enable, &mut buf).unwrap().to_vec();
    let mut got = arm.line(&frame);
    for _ in 0..50 {
        if let Some(end) = got.iter().position(|&b| b == 0) {
            assert_eq!(decode::<Reply>(&mut got[..end]).unwrap(), Reply::Done, "enable");
            arm.ticks(20).unwrap();
            assert!(arm.board().drivers_enabled(), "the drivers enabled");
            return;
        }
        arm.tick().unwrap();
        got.extend(arm.line(&[]));
    }
    panic!("no reply to enable")
}

/// The ruled status bits of each period of `faults` on the twin.
fn on_the_twin(faults: &[Option<F>]) -> Vec<u32> {
    let (s, flash) = scenario();
    let mut arm = FreeArm::with_flash(&s, s.board, &CalibrationSection::default(), flash).unwrap();
    on_the_belt(&mut arm);
    faults
        .iter()
        .map(|f| {
            arm.set_faults(BusFaults { acquisition: *f, ..BusFaults::default() });
            arm.tick().unwrap();
            arm.twin().app().last_command().expect("the twin ticks").status & RULED
        })
        .collect()
}

/// The ruled status bits of each period of `faults` on the emulated image.
fn on_the_image(faults: &[Option<F>]) -> Vec<u32> {
    let (s, flash) = scenario();
    let image = default_image();
    assert!(image.exists(), "{}: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let mut arm: FreeArm<EmulatedBoard> = FreeArm::emulated(&s, s.board, &flash, &image).unwrap();
    on_the_belt(&mut arm);
    faults
        .iter()
        .map(|f| {
            arm.set_faults(BusFaults { acquisition: *f, ..BusFaults::default() });
            arm.tick().unwrap();
            arm.board().monitor().expect("the image ticks").command.status & RULED
        })
        .collect()
}

#[test]
fn on_the_belt_both_boards_run_clean_and_a_fault_run_latches_the_acquisitions_reason() {
    // The cases' start: no reason latched, no bad frame, on either board.
    let clean = [None; 6];
    assert_eq!(on_the_twin(&clean), vec![0; 6]);
    assert_eq!(on_the_image(&clean), vec![0; 6]);
    // One fault run each, against the model written out.
    let safe = status::SAFE_STATE | ((SafeReason::Acquisition as u32) << status::REASON_SHIFT);
    let faults = [None, Some(F::Timeout), None, Some(F::FifoError), Some(F::TransferError), Some(F::DirectModeError), None];
    let want = vec![0, status::BAD_FRAME, 0, status::BAD_FRAME, status::BAD_FRAME, safe | status::BAD_FRAME, safe];
    assert_eq!(expected(&faults), want);
    assert_eq!(on_the_twin(&faults), want);
    assert_eq!(on_the_image(&faults), want);
}

proptest! {
    // Each case boots the image on the emulated board (about 0.1 s of the host's time).
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_dma_faults_follow_the_rule_on_the_twin_and_the_image_alike(
        faults in vec(option::weighted(0.45, 0..EMULATED.len()), 4..24)
    ) {
        let faults: Vec<Option<F>> = faults.iter().map(|f| f.map(|i| EMULATED[i])).collect();
        let want = expected(&faults);
        let twin = on_the_twin(&faults);
        prop_assert_eq!(&twin, &want, "the twin, faults {:?}", faults);
        let image = on_the_image(&faults);
        prop_assert_eq!(&image, &twin, "the image against the twin, faults {:?}", faults);
    }

    #[test]
    fn random_acquisition_faults_follow_the_rule_on_the_twin(
        faults in vec(option::weighted(0.5, 0..TWIN.len()), 4..40)
    ) {
        let faults: Vec<Option<F>> = faults.iter().map(|f| f.map(|i| TWIN[i])).collect();
        prop_assert_eq!(on_the_twin(&faults), expected(&faults), "faults {:?}", faults);
    }
}

// ------------------------------------------------------------- from a scenario

/// Each acquisition fault as a scenario's `[[faults]]` entry (without its time),
/// the name the log gives it (`AcquisitionFault::describe`).
const SCENARIO_FAULTS: [(&str, F); 6] = [
    ("kind = \"dma_transfer_error\"", F::TransferError),
    ("kind = \"dma_fifo_error\"", F::FifoError),
    ("kind = \"dma_direct_mode_error\"", F::DirectModeError),
    ("kind = \"dma_late_transfer\"", F::Timeout),
    ("kind = \"stuck_chip_select\"\nsignal = \"theta1\"", F::StuckChipSelect),
    ("kind = \"stuck_chip_select\"\nsignal = \"elbow\"", F::StuckChipSelect),
];

/// Where the fault starts, s: mid-move (the default scenario's 2 s move), and
/// the run's length past it.
const AT_S: f64 = 0.5;
const RUN_S: f64 = 0.52;

/// The default scenario, `RUN_S` long, with `fault` from `AT_S` for `duration_s`.
fn with_fault(fault: &str, duration_s: f64) -> Scenario {
    let text = format!("{DEFAULT_TOML}\n[[faults]]\n{fault}\nat_s = {AT_S}\nduration_s = {duration_s}\n");
    let mut s = Scenario::from_toml(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    s.timing.duration_s = RUN_S;
    s.validate().unwrap_or_else(|e| panic!("{e}"));
    s
}

type Run = (Vec<PeriodRecord>, Option<RunError>);

/// The twin's run and the emulated image's of `s`.
fn both(s: &Scenario) -> (Run, Run) {
    let setup = rig::RunSetup::new(s.clone()).unwrap();
    let mut twin = TwinLink::new(&setup).unwrap();
    let t = run_loop(&setup, &mut twin, &mut ());
    let image = default_image();
    assert!(image.exists(), "{}: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let mut emu = EmulatorLink::new(&setup, &image).unwrap_or_else(|e| panic!("{e}"));
    let e = run_loop(&setup, &mut emu, &mut ());
    (t, e)
}

/// The two runs are the same, bit for bit, outcome included.
fn same(what: &str, (twin, emu): &(Run, Run)) {
    assert_eq!(format!("{:?}", emu.1), format!("{:?}", twin.1), "{what}: the same outcome on both boards");
    assert_eq!(emu.0.len(), twin.0.len(), "{what}");
    for (k, (e, t)) in emu.0.iter().zip(&twin.0).enumerate() {
        assert_eq!(format!("{e:?}"), format!("{t:?}"), "{what}: period {k} differs");
    }
}

#[test]
fn each_acquisition_fault_from_a_scenario_is_held_then_latches_its_reason_alike_on_both_boards() {
    let ts = 1e-3;
    let k0 = (AT_S / ts).round() as usize;
    let limit = usize::from(firmware::Config::default().bad_frame_limit);
    for (fault, kind) in SCENARIO_FAULTS {
        // One period: held (BAD_FRAME, the previous command), the run goes on to its end.
        let one = both(&with_fault(fault, ts));
        same(fault, &one);
        let (records, err) = &one.0;
        assert!(err.is_none(), "{fault}: {err:?}");
        assert_eq!(records.len(), (RUN_S / ts).round() as usize, "{fault}");
        let bad: Vec<usize> = records.iter().enumerate().filter(|(_, r)| r.status & status::BAD_FRAME != 0).map(|(k, _)| k).collect();
        assert_eq!(bad, vec![k0], "{fault}: the one faulted period's frame is bad");
        assert_eq!((records[k0].u1_cmd, records[k0].u2_cmd), (records[k0 - 1].u1_cmd, records[k0 - 1].u2_cmd), "{fault}: held");
        // Longer: `bad_frame_limit` faulted periods latch the acquisition's own
        // reason in the last of them, on both boards.
        let long = both(&with_fault(fault, 10.0 * ts));
        same(fault, &long);
        match &long.0.1 {
            Some(RunError::SafeState { k, reason: SafeReason::Acquisition, .. }) => assert_eq!(*k, k0 + limit - 1, "{fault}"),
            other => panic!("{fault} ({kind:?}): {other:?}"),
        }
        let last = long.0.0.last().unwrap();
        assert_eq!(last.status >> status::REASON_SHIFT, SafeReason::Acquisition as u32, "{fault}");
        assert_eq!((last.u1_cmd, last.u2_cmd), (0.0, 0.0), "{fault}: zero torque");
    }
}
