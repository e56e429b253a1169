//! The processor-in-the-loop image of [`law_template::Impedance`]: the
//! reference board's PIL image (`board_stm32f405::images::pil`) with this
//! crate's law. `sil-host pil --image` runs it under QEMU (README.md).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "`law-pil` is the Cortex-M4F PIL image of the impedance law: cargo build -p law-template --profile qemu --target thumbv7em-none-eabihf --no-default-features --features qemu --bin law-pil (README.md)"
    );
}

#[cfg(target_os = "none")]
board_stm32f405::pil_image!(law_template::Impedance);
