//! The SIL rig's firmware process running [`law_template::Impedance`]: the
//! same command as `sil-host firmware` (`law-firmware firmware --rig NAME
//! --scenario FILE`), for `sil-host run --attach NAME` (README.md). A host
//! program: the MCU images are `law-pil` and `law-arm`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() -> std::process::ExitCode {
    experiments::firmware_process::main::<law_template::Impedance>()
}
