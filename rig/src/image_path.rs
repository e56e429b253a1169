//! Where an MCU image is found by default: the `thumbv7em-none-eabihf` target
//! folder next to this executable's (a `sil-host` built in the workspace), else
//! the workspace this crate was built from.

use std::path::{Path, PathBuf};

/// `target/<rel>` next to the running executable's target folder if it exists
/// there, else in the workspace this crate was built from (`rel`: e.g.
/// `thumbv7em-none-eabihf/mcu/arm`).
pub fn beside_this_executable(rel: &Path) -> PathBuf {
    if let Ok(exe) = std::env::current_exe()
        && let Some(target) = exe.parent().and_then(Path::parent)
    {
        let p = target.join(rel);
        if p.exists() {
            return p;
        }
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target").join(rel)
}
