//! Puts the workspace root's `memory.x` (the STM32F405's memory map) on the
//! linker path for the images (cortex-m-rt's `link.x` includes it). Host
//! builds need nothing.

use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=../../memory.x");
    if env::var("TARGET").unwrap_or_default().starts_with("thumb") {
        let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
        fs::copy("../../memory.x", out.join("memory.x")).expect("../../memory.x is readable");
        println!("cargo:rustc-link-search={}", out.display());
        // The images are sized and timed for the `mcu` profile (opt-level "s",
        // fat LTO): a dev build is about 250 KiB (over the 64 KiB budget) and too
        // slow for the control rate; a plain --release one (opt-level 3, no LTO)
        // fits (about 42 KiB, docs/board.md "Budgets") but is not the timed build.
        let opt = env::var("OPT_LEVEL").unwrap_or_default();
        if opt != "s" && opt != "z" {
            println!(
                "cargo:warning=board image built at opt-level {opt}: not the sized and timed build{}; \
                 build with --profile mcu (`cargo arm`, `cargo pil`) or --profile qemu (docs/board.md)",
                if opt == "0" { ", and over the 64 KiB flash budget" } else { "" }
            );
        }
    }
}
