//! The arm image (`boards/stm32f405`, bin `arm`) in QEMU's netduinoplus2 under
//! `-icount shift=0`: it starts, its control interrupt runs at the configured
//! rate of the emulated core clock, and the sensors QEMU does not model end in
//! the safe state with the drivers disabled and clear log lines; never a hang
//! or a panic. Needs `qemu-system-arm`.

mod common;

use std::process::Command;

#[test]
fn arm_image_in_qemu_ticks_at_its_rate_and_goes_safe_without_sensors() {
    let elf = common::qemu_image("arm");
    let run = Command::new("bash").arg(common::workspace().join("scripts/qemu-run.sh")).arg(&elf).args(["-icount", "shift=0,sleep=off"]).output().unwrap();
    let log = common::decode_defmt(&elf, &run.stdout);
    let text = log.join("\n");
    eprintln!("{text}");
    assert!(run.status.success(), "QEMU exit {} (101 = panic): {}", run.status, String::from_utf8_lossy(&run.stderr));
    assert!(text.contains("arm image up: 1000 Hz control tick"), "{text}");
}
