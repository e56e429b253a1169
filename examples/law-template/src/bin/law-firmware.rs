//! The SIL rig's firmware process running [`law_template::Impedance`]: the
//! same command as `sil-host firmware` (`law-firmware firmware --rig NAME
//! --scenario FILE`), for `sil-host run --attach NAME` (README.md).

fn main() -> std::process::ExitCode {
    experiments::firmware_process::main::<law_template::Impedance>()
}
