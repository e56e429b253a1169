//! Logs and the end of an image: defmt over RTT on a board (a probe reads it),
//! over semihosting under QEMU (feature `qemu`); `panic-probe` prints a panic
//! through defmt and traps; under QEMU the trap's hard fault exits with 101.

#[cfg(all(feature = "qemu", feature = "rtt"))]
compile_error!("features `qemu` and `rtt` exclude each other: build QEMU images with --no-default-features --features qemu");
#[cfg(not(any(feature = "qemu", feature = "rtt")))]
compile_error!("enable one log transport: `rtt` (the default, boards) or `qemu`");

#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "qemu")]
use defmt_semihosting as _;
use panic_probe as _;

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
