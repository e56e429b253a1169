//! The reset button (NRST) pressed at any instant of a period, at any rate the
//! image runs: the unmodified `arm` ELF restarts from its flash into the saved
//! configuration and ticks again at its rate (issue 56). Found by the e2e test
//! of `sil-host board reset` after `configure` at 4 kHz: the image came back
//! from a reset with the NVIC and the system control block as it had left
//! them (rsemu's warm reset restarts the core alone), took its interrupts
//! before `main` set them up and bus-faulted; on the part, a system reset
//! returns that block to its reset values (RM0090 section 6.1.2), as the
//! emulated board now does (`board_emulator::core_clock::Core`).

use super::ask;
use arm_app::{
    Settings,
    bringup::{CalibrationRecord, Reply, Request},
    record::Stored,
};
use board_emulator::EmulatedBoard;
use board_link::{emulator_link::default_image, free_arm::FreeArm};
use board_twin::FlashModel;
use rig::{
    scenario::{DEFAULT_TOML, Scenario},
    setup::firmware_config,
};

/// The default scenario at `rate_hz`, the sampling delay within the period.
fn scenario_at(rate_hz: f64) -> Scenario {
    let mut s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    s.plant.v_belt = 0.0;
    s.timing.rate_hz = rate_hz;
    s.timing.delta_s = s.timing.delta_s.min(0.5 / rate_hz);
    s.validate().unwrap();
    s
}

/// A seeded sample of instants within a period, as fractions of it: spread
/// over the acquisition's frames, the control interrupt and the idle loop
/// (xorshift64, so the sample is the same on every run).
fn instants(seed: u64, n: usize) -> Vec<f64> {
    let mut x = seed | 1;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// The board at `rate_hz`, its configuration saved (`Settings::Saved`), ticking.
fn board_at(rate_hz: f64) -> FreeArm<EmulatedBoard> {
    let image = default_image();
    assert!(image.exists(), "{}: {}", image.display(), board_link::emulator_link::BUILD_HINT);
    let s = scenario_at(rate_hz);
    let stored = Stored { calibration: CalibrationRecord::brought_up(&s.calibration.arm_calibration()), config: firmware_config(&s) };
    let mut arm = FreeArm::emulated(&s, s.board, &FlashModel::saved(&stored).unwrap(), &image).unwrap();
    arm.ticks(3).unwrap();
    arm
}

/// Presses the reset button now (the machine where the last step left it),
/// then checks that the image is back: TIM2 at the saved period `us`, one
/// image tick a board tick, `Status` saying so from the saved record.
fn reset_and_check(arm: &mut FreeArm<EmulatedBoard>, us: u64, what: &str) {
    arm.reset().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(arm.board().period_ns(), us * 1000, "{what}: the saved rate");
    let ticks = |a: &FreeArm<EmulatedBoard>| a.board().monitor().expect("the image ticks").ticks;
    let before = ticks(arm);
    arm.ticks(5).unwrap_or_else(|e| panic!("{what}, after the reset: {e}"));
    assert_eq!(ticks(arm), before + 5, "{what}, after the reset: one image tick a period");
    match ask(arm, Request::Status) {
        Reply::Status(st) => {
            assert_eq!(u64::from(st.period_us), us, "{what}, after the reset");
            assert_eq!(st.settings, Settings::Saved, "{what}, after the reset");
        }
        other => panic!("{what}, after the reset: {other:?}"),
    }
}

/// The rates tested, Hz, and their periods, us: both ends of the range, the
/// default and 4 kHz.
const RATES: [(f64, u64); 4] = [(4000.0, 250), (10_000.0, 100), (1000.0, 1000), (250.0, 4000)];

#[test]
fn the_reset_button_at_any_instant_of_a_period_restarts_the_image_into_its_saved_rate() {
    // Eight seeded instants of a period per rate, the board running between
    // resets: in the acquisition's frames, the control interrupt, the idle loop.
    for (rate_hz, us) in RATES {
        let mut arm = board_at(rate_hz);
        for (i, at) in instants(us, 8).into_iter().enumerate() {
            arm.ticks(3).unwrap_or_else(|e| panic!("{rate_hz} Hz, before reset {i}: {e}"));
            let to = arm.board().now_ns() + (at * arm.board().period_ns() as f64) as u64;
            arm.board_mut().step_to(to).unwrap();
            reset_and_check(&mut arm, us, &format!("{rate_hz} Hz, reset {i} at {at:.3} of a period"));
        }
    }
}

#[test]
fn the_reset_button_while_an_interrupt_holds_a_lazily_preserved_fp_frame_restarts_the_image() {
    // The instant the e2e test met by chance: an interrupt (TIM2, DMA2) has
    // preempted thread-mode code that used the FPU, so a floating-point frame
    // is reserved on the old stack and not yet written (FPCCR.LSPACT, FPCAR:
    // ARMv7-M B1.5.7). A system reset forgets it; if the emulated board kept
    // it, the restarted image's first floating-point instruction wrote the
    // old S0-S15 over its new stack (the bus fault at 0x3df1d8d8, a float,
    // loaded as a pointer). Found by stepping 0.5 us at a time (a few per
    // cent of the instants at 4 kHz), four times per rate.
    for (rate_hz, us) in RATES {
        let mut arm = board_at(rate_hz);
        for i in 0..4 {
            arm.ticks(2).unwrap_or_else(|e| panic!("{rate_hz} Hz, before reset {i}: {e}"));
            let (t0, limit) = (arm.board().now_ns(), 4 * arm.board().period_ns());
            let mut dt = 0;
            loop {
                dt += 500;
                assert!(dt <= limit, "{rate_hz} Hz, reset {i}: no pending lazy FP frame within four periods");
                arm.board_mut().step_to(t0 + dt).unwrap();
                let cpu = &arm.board().core().cpu;
                if cpu.with_sys(|s| s.fpccr & FPCCR_LSPACT != 0) && cpu.current_exception().0 != 0 {
                    break;
                }
            }
            reset_and_check(&mut arm, us, &format!("{rate_hz} Hz, reset {i} with a lazy FP frame pending"));
        }
    }
}

/// FPCCR.LSPACT: lazy floating-point state preservation is active (a frame is
/// reserved and not written; ARMv7-M ARM DDI 0403E B3.2.22).
const FPCCR_LSPACT: u32 = 1;
