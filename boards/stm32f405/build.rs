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
    }
}
