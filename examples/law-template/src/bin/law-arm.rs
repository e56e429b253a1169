//! The arm image of [`law_template::Impedance`]: the reference board's `arm`
//! image (`board_stm32f405::images::arm`: acquisition by DMA, the watchdog,
//! the enable button, the bring-up over USART1, the settings record) with
//! this crate's law. `sil-host run --link emulator --elf` runs it on the
//! emulated board; `cargo run` flashes it with probe-rs (README.md).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "`law-arm` is the Cortex-M4F arm image of the impedance law: cargo run -p law-template --profile mcu --target thumbv7em-none-eabihf --bin law-arm (README.md)"
    );
}

#[cfg(target_os = "none")]
board_stm32f405::arm_image!(law_template::Impedance);
