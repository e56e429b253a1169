//! The board's checks of the peripherals rsemu models (`board_emulator::checks`)
//! on the unmodified `arm` image: each passes on the image as built, and each
//! misconfiguration of the list, written into a register of the booted
//! machine by a bus master (as a stray store of the image would), is caught
//! naming the register and its value.

use arm_app::{bringup::CalibrationRecord, record::Stored};
use board_emulator::{ArmImage, EmulatedBoard, checks, core_clock::Mode};
use board_twin::{ArmState, BoardDescription, FlashModel};
use rsemu::core::{space::MemAttrs, value::Width};

fn booted() -> EmulatedBoard {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/thumbv7em-none-eabihf/mcu/arm");
    let image = ArmImage::load(&path).unwrap_or_else(|e| panic!("{e}: build it with `cargo build-arm`"));
    let cal = arm_app::ArmCalibration {
        encoders: drivers::frame::FrameCalibration::default(),
        load_cell: drivers::load_cell::Calibration::default(),
        belt_metres_per_count: 1e-6,
    };
    let flash =
        FlashModel::saved(&Stored { calibration: CalibrationRecord::brought_up(&cal), config: firmware::Config::default() }).unwrap();
    let sector = flash.bytes().borrow().clone();
    let mut b = EmulatedBoard::new(image, BoardDescription::default(), &sector, 1_000_000, 1, 0.0, Mode::Functional).unwrap();
    b.boot(&ArmState { x: [0.3, 0.0, 1.2, 0.0], f: [0.0, 0.0], belt_travel_m: 0.0 }).unwrap();
    b
}

fn write(b: &EmulatedBoard, addr: u32, value: u32) {
    let space = b.machine().space("mem").unwrap();
    space.write(u64::from(addr), Width::U32, u64::from(value), MemAttrs::default()).unwrap();
}

fn all(b: &EmulatedBoard) -> Result<(), board_emulator::BoardError> {
    let m = b.machine();
    checks::clock_tree(m).and_then(|()| checks::pins(m)).and_then(|()| checks::timers(m, 1000.0)).and_then(|()| checks::watchdog(m, 1e-3))
}

#[test]
fn the_image_as_built_passes_every_check() {
    let b = booted();
    all(&b).unwrap();
}

#[test]
fn each_misconfiguration_is_caught_naming_the_register() {
    let peek = |b: &EmulatedBoard, a| checks::peek(b.machine(), a);
    // (what, register to change, how, the register the error must name, words of its reason)
    type Case = (&'static str, u32, fn(u32) -> u32, &'static str, &'static str);
    let cases: [Case; 9] = [
        ("PA5 not SPI1's alternate function", 0x4002_0020, |v| (v & !(0xF << 20)) | (6 << 20), "GPIOA_AFRL", "AF5"),
        ("PB15 (nFAULT) without its pull-up", 0x4002_040C, |v| v & !(0b11 << 30), "GPIOB_PUPDR", "pulled up"),
        ("PB14 (enable) not an output", 0x4002_0400, |v| v & !(0b11 << 28), "GPIOB_MODER", "an output"),
        ("the PWM at 10 kHz", 0x4000_042C, |v| 2 * (v + 1) - 1, "TIM3_ARR", "20 kHz"),
        ("channel 2's PWM active low", 0x4000_0420, |v| v | (1 << 5), "TIM3_CCER", "active low"),
        ("the belt's counter in encoder mode 1", 0x4000_0808, |v| (v & !0b111) | 0b001, "TIM4_SMCR", "encoder mode 3"),
        ("TRGO not on update", 0x4000_0004, |v| v & !(0b111 << 4), "TIM2_CR2", "TRGO"),
        ("APB2 undivided", 0x4002_3808, |v| v & !(0b111 << 13), "RCC_CFGR", "APB2 /2"),
        ("flash at 2 wait states", 0x4002_3C00, |v| (v & !0xF) | 2, "FLASH_ACR", "5"),
    ];
    for (what, addr, change, register, why) in cases {
        let b = booted();
        write(&b, addr, change(peek(&b, addr)));
        let e = all(&b).expect_err(what);
        assert!(e.register.starts_with(register) && e.why.contains(why), "{what}: {e}");
    }
}

#[test]
fn a_watchdog_shorter_than_two_periods_at_the_lsis_fastest_is_caught() {
    // RLR 15 with PR 0: 4 x 16 / 47 kHz = 1.4 ms, under two 1 ms periods.
    let b = booted();
    write(&b, 0x4000_3000, 0x5555);
    write(&b, 0x4000_3004, 0);
    write(&b, 0x4000_3008, 15);
    let e = checks::watchdog(b.machine(), 1e-3).unwrap_err();
    assert!(e.register.starts_with("IWDG_RLR") && e.why.contains("would be reset"), "{e}");
}

fn read(b: &EmulatedBoard, addr: u32) -> u32 {
    let space = b.machine().space("mem").unwrap();
    space.read(u64::from(addr), Width::U32, MemAttrs::default()).unwrap() as u32
}

const KEYR: u32 = 0x4002_3C04;
const SR: u32 = 0x4002_3C0C;
const CR: u32 = 0x4002_3C10;
/// PSIZE x32, SER, SNB = `sector`.
fn erase(sector: u32) -> u32 {
    (0b10 << 8) | (sector << 3) | 0b10
}

#[test]
fn the_record_sectors_erase_and_program_in_the_right_sequence_raise_no_error() {
    let mut b = booted();
    write(&b, KEYR, 0x4567_0123);
    write(&b, KEYR, 0xCDEF_89AB);
    write(&b, CR, erase(4));
    write(&b, CR, erase(4) | (1 << 16));
    while read(&b, SR) & (1 << 16) != 0 {
        b.run_for(100_000).unwrap();
    }
    assert_eq!(read(&b, 0x0801_0000), 0xFFFF_FFFF, "sector 4 erased");
    write(&b, CR, (0b10 << 8) | 1);
    write(&b, 0x0801_0000, 0x1234_5678);
    while read(&b, SR) & (1 << 16) != 0 {
        b.run_for(10_000).unwrap();
    }
    assert_eq!(read(&b, SR) & 0xF2, 0);
    assert_eq!(read(&b, 0x0801_0000), 0x1234_5678);
    write(&b, CR, 1 << 31);
    assert_eq!(b.board_errors(), vec![]);
}

#[test]
fn each_wrong_flash_sequence_is_caught_naming_the_register() {
    // (what, the writes after booting, the register the error must name, words of its reason)
    type Case = (&'static str, &'static [(u32, u32)], &'static str, &'static str);
    let unlock: [(u32, u32); 2] = [(KEYR, 0x4567_0123), (KEYR, 0xCDEF_89AB)];
    let cases: [Case; 7] = [
        ("FLASH_CR written while locked", &[(CR, 0x202)], "FLASH_CR", "while locked"),
        ("a wrong second key", &[(KEYR, 0x4567_0123), (KEYR, 0x1234_5678)], "FLASH_KEYR", "KEY2"),
        ("a key while unlocked", &[(KEYR, 0x4567_0123), (KEYR, 0xCDEF_89AB), (KEYR, 0x4567_0123)], "FLASH_KEYR", "unlocked"),
        ("an erase of the image's sector 2", &[(CR, 0x212), (CR, 0x1_0212)], "FLASH_CR", "erases sector 2"),
        ("a mass erase", &[(CR, 0x204), (CR, 0x1_0204)], "FLASH_CR", "mass erase"),
        ("an erase at x64 parallelism", &[(CR, 0x322), (CR, 0x1_0322)], "FLASH_CR", "VPP"),
        // A program without PG: the part sets PGSERR, which the image reads.
        ("a write into the array without PG", &[(0x0801_0000, 0), (SR, 0)], "FLASH_SR", "PGSERR"),
    ];
    for (i, (what, writes, register, why)) in cases.into_iter().enumerate() {
        let b = booted();
        let writes: Vec<(u32, u32)> = if i >= 3 { unlock.iter().chain(writes).copied().collect() } else { writes.to_vec() };
        for (addr, value) in writes {
            if addr == SR {
                read(&b, SR);
            } else {
                let space = b.machine().space("mem").unwrap();
                let _ = space.write(u64::from(addr), Width::U32, u64::from(value), MemAttrs::default());
            }
        }
        let errors = b.board_errors();
        let e = errors.first().unwrap_or_else(|| panic!("{what}: no error"));
        assert!(e.register.starts_with(register) && e.why.contains(why), "{what}: {e}");
    }
}

#[test]
fn the_timers_the_image_does_not_use_are_not_on_the_bus() {
    // TIM5 (0x4000_0C00) and TIM1 (0x4001_0000) are left out of the machine
    // (board_emulator::machine::LEFT_OUT); TIM2 to TIM4 answer.
    let b = booted();
    let space = b.machine().space("mem").unwrap();
    for addr in [0x4000_0C00u64, 0x4001_0000] {
        assert!(space.read(addr, Width::U32, MemAttrs::default()).is_err(), "{addr:#x}");
    }
    for addr in [0x4000_0000u64, 0x4000_0400, 0x4000_0800] {
        assert!(space.read(addr, Width::U32, MemAttrs::default()).is_ok(), "{addr:#x}");
    }
}
