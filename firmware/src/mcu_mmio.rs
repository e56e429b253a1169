//! Volatile access to the STM32F405's memory-mapped registers for the MCU
//! images (`src/bin/mcu.rs`, `src/bin/pil.rs` include this file): the library
//! forbids `unsafe`, so its register sequences (`firmware::clock_tree`) take
//! this through the `Registers` trait.

/// The chip's own registers.
pub struct Mmio;

impl firmware::clock_tree::Registers for Mmio {
    fn read(&mut self, addr: u32) -> u32 {
        // SAFETY: callers pass aligned addresses of memory-mapped registers of
        // the STM32F405 (RM0090 2.3); a read has no side effect on those used.
        unsafe { core::ptr::read_volatile(addr as *const u32) }
    }
    fn write(&mut self, addr: u32, value: u32) {
        // SAFETY: as `read`; the clocks are brought up once, before anything else
        // touches the RCC.
        unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
    }
}
