//! A board never runs without its runaway limits and wiring checks (issue 52):
//! the host's own check of a configuration before it reaches a board (a
//! scenario on `--link twin`/`emulator`, `board configure`, a backup for
//! `board restore`), in the words the board's refusal uses
//! (`Refusal::ProtectionOff`, `RecordFault::ProtectionOff`; docs/board.md
//! "Runaway limits").

/// Why a board refuses the runaway limits off (`Refusal::ProtectionOff`,
/// `RecordFault::ProtectionOff`, and the host's own checks of a scenario or a
/// backup before it reaches a board).
pub const PROTECTION_OFF: &str = "the runaway limits cannot be turned off on a board; the studies that need them off run without \
                                  a board: `sil-host run --in-process`, or `sil-host run` (the firmware process over iceoryx2)";

/// [`PROTECTION_OFF`] for a configuration that turns them off, the key named:
/// `Err` when `config.runaway_limits` is false.
///
/// # Errors
/// `"{key} = false: {PROTECTION_OFF}"`.
pub fn check_protection(config: &firmware::Config, key: &str) -> Result<(), String> {
    if config.runaway_limits { Ok(()) } else { Err(format!("{key} = false: {PROTECTION_OFF}")) }
}
