//! The arm image with the paper's laws: its body is
//! `board_stm32f405::images::arm` (docs/board.md); a law of one's own builds
//! the same image from its crate with `board_stm32f405::arm_image!(ItsLaw)`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "`arm` is the Cortex-M4F image for the arm: `cargo arm` (= cargo run -p board-stm32f405 --profile mcu --target thumbv7em-none-eabihf --bin arm) (docs/board.md)"
    );
}

#[cfg(target_os = "none")]
board_stm32f405::arm_image!(firmware::PaperLaws);
