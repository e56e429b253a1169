//! The processor-in-the-loop image with the paper's laws: its body is
//! `board_stm32f405::images::pil` (docs/board.md); a law of one's own builds
//! the same image from its crate with `board_stm32f405::pil_image!(ItsLaw)`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("`pil` is the Cortex-M4F PIL image: build it with --target thumbv7em-none-eabihf (docs/board.md)");
}

#[cfg(target_os = "none")]
board_stm32f405::pil_image!(firmware::PaperLaws);
