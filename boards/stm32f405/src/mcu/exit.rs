//! Logs and the end of an image: defmt over RTT on a board (a probe reads it),
//! over semihosting under QEMU (feature `qemu`); the panic handler below logs a
//! panic through defmt and traps; under QEMU the trap's hard fault exits with 101.

#[cfg(all(feature = "qemu", feature = "rtt"))]
compile_error!("features `qemu` and `rtt` exclude each other: build QEMU images with --no-default-features --features qemu");
#[cfg(not(any(feature = "qemu", feature = "rtt")))]
compile_error!("enable one log transport: `rtt` (the default, boards) or `qemu`");

#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "qemu")]
use defmt_semihosting as _;

/// Ends the image with `code`: QEMU exits with it; a board sleeps (its probe
/// session ends with the log).
pub fn exit(code: i32) -> ! {
    #[cfg(feature = "qemu")]
    semihosting::process::exit(code);
    #[cfg(not(feature = "qemu"))]
    {
        let _ = code;
        loop {
            cortex_m::asm::wfi();
        }
    }
}

/// Whether this build runs under QEMU (feature `qemu`).
pub const UNDER_QEMU: bool = cfg!(feature = "qemu");

#[cfg(feature = "qemu")]
#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    defmt::error!("hard fault (a panic traps here): exiting");
    exit(101)
}

/// The images' panic handler: the motor drivers disabled at once (the enable
/// line low), then (in place of `panic-probe`'s `print-defmt`, which
/// formats the message with `core::fmt`: with its float formatting about 16 KiB
/// of flash, docs/measurements.md "Speed and scale"). Logs once, as defmt's
/// `error`, `panicked at FILE:LINE:COLUMN` and the message when it is a literal
/// (`PanicMessage::as_str`; a formatted message is logged as `<formatted>`:
/// FILE:LINE names it), then traps like `panic-probe`: `udf` with the usage fault
/// disabled, so it escalates to a hard fault (probe-rs reports it; under QEMU the
/// `HardFault` handler exits with 101). Interrupts stay masked from here on.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    use core::sync::atomic::{AtomicBool, Ordering};
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    // The drivers off first (PB14 low through BSRR: one register write, no
    // state read): a panic (a law's of one's own among them, issue 70) stops the
    // torques at once, not at the watchdog's reset 5 periods later. Harmless in
    // the PIL image, which drives no motor.
    crate::mcu::gpio::write(&crate::pins::DRIVER_ENABLE, false);
    // A panic while logging one (the log transport itself) must not recurse.
    if !PANICKED.swap(true, Ordering::Relaxed) {
        let msg = info.message().as_str().unwrap_or("<formatted>");
        match info.location() {
            Some(l) => defmt::error!("panicked at {=str}:{=u32}:{=u32}: {=str}", l.file(), l.line(), l.column(), msg),
            None => defmt::error!("panicked: {=str}", msg),
        }
    }
    hard_fault()
}

/// Traps through a hard fault (as `panic_probe::hard_fault`): clears SHCSR's
/// USGFAULTENA so the undefined instruction escalates to `HardFault`.
fn hard_fault() -> ! {
    const SHCSR: *mut u32 = 0xE000_ED24 as *mut u32;
    const USGFAULTENA: u32 = 1 << 18;
    // SAFETY: SHCSR is the System Handler Control and State Register of every
    // Cortex-M4 (ARMv7-M ARM B3.2.13); a read-modify-write of one enable bit.
    unsafe { SHCSR.write_volatile(SHCSR.read_volatile() & !USGFAULTENA) };
    cortex_m::asm::udf()
}
