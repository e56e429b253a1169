//! The `sil-host` command line, built inside the end-to-end test crate so that its
//! tests can run it as a real process (and it can spawn itself as the firmware
//! process of the SIL rig). Same code as `sil-host/src/main.rs`.

fn main() {
    std::process::exit(sil_host::run(std::env::args_os()));
}
