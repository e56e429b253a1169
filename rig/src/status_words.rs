//! Status words and frame flags in words (docs/wire.md, "Status word" and
//! "Frame flags"): what `sil-host board`, the twin's log and run summaries print
//! next to the hexadecimal word, so that nobody decodes `0x7000001` by hand.

use firmware::SafeReason;
use shared::wire::{frame_flags, status};

/// The words of a command's status word (`shared::wire::status`): the safe
/// state with its reason first, then each flag set; `"running, no flag"` for 0.
///
/// Example: `0x7000001` gives "safe state: the encoders and the load cell
/// disagree about the tip (...)".
pub fn describe_status(word: u32) -> String {
    let mut parts = Vec::new();
    if word & status::SAFE_STATE != 0 {
        let code = word >> status::REASON_SHIFT;
        parts.push(match SafeReason::from_status(word) {
            Some(r) => format!("safe state: {}", r.describe()),
            None => format!("safe state: unknown reason {code}"),
        });
    }
    for (bit, name) in [
        (status::BAD_FRAME, "bad frame"),
        (status::STALE_FRAME, "stale frame"),
        (status::SEQUENCE_GAP, "sequence gap"),
        (status::LIFT_OFF, "lift-off detected"),
        (status::SATURATED_U1, "u1 saturated"),
        (status::SATURATED_U2, "u2 saturated"),
        (status::DEADLINE_MISS, "deadline miss"),
        (status::LOAD_CLIPPED, "load cell clipped"),
        (status::REFERENCE_MOVING, "reference moving"),
    ] {
        if word & bit != 0 {
            parts.push(name.to_string());
        }
    }
    let known = 0x3FF | (0xFF << status::REASON_SHIFT);
    if word & !known != 0 {
        parts.push(format!("unknown bits {:#x}", word & !known));
    }
    if parts.is_empty() { "running, no flag".into() } else { parts.join("; ") }
}

/// The words of a sensor frame's flags (`shared::wire::frame_flags`): each
/// invalid reading and the driver fault; `"every reading valid"` for none.
pub fn describe_frame_flags(flags: u16) -> String {
    let parts: Vec<&str> = [
        (frame_flags::THETA1_INVALID, "theta1 encoder invalid"),
        (frame_flags::ELBOW_INVALID, "elbow encoder invalid"),
        (frame_flags::F_T_INVALID, "f_t invalid"),
        (frame_flags::F_N_INVALID, "f_n invalid"),
        (frame_flags::BELT_INVALID, "belt invalid"),
        (frame_flags::DRIVER_FAULT, "driver fault line asserted"),
        (frame_flags::HELLO, "hello"),
        (frame_flags::END_OF_RUN, "end of run"),
    ]
    .into_iter()
    .filter(|(bit, _)| flags & bit != 0)
    .map(|(_, name)| name)
    .collect();
    if parts.is_empty() { "every reading valid".into() } else { parts.join(", ") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_audits_word_reads_as_a_sensor_fault() {
        // The word `board status` showed after `enable` on a twin with its fault line.
        let s = describe_status(0x700_0001);
        assert!(s.starts_with("safe state: the encoders and the load cell disagree"), "{s}");
        assert_eq!(describe_status(0), "running, no flag");
        assert_eq!(describe_status(status::LIFT_OFF | status::SATURATED_U2), "lift-off detected; u2 saturated");
        assert_eq!(describe_status(status::SAFE_STATE | (16 << status::REASON_SHIFT)), "safe state: unknown reason 16");
        assert_eq!(describe_status(1 << 12), "unknown bits 0x1000");
    }

    #[test]
    fn every_reason_has_its_own_words() {
        let words: Vec<String> = (1..=15u32).map(|r| describe_status(status::SAFE_STATE | (r << status::REASON_SHIFT))).collect();
        for (i, w) in words.iter().enumerate() {
            assert!(!w.contains("unknown"), "{w}");
            assert!(words[i + 1..].iter().all(|o| o != w), "{w} twice");
        }
    }

    #[test]
    fn frame_flags_name_each_reading() {
        assert_eq!(describe_frame_flags(0), "every reading valid");
        assert_eq!(
            describe_frame_flags(frame_flags::ELBOW_INVALID | frame_flags::DRIVER_FAULT),
            "elbow encoder invalid, driver fault line asserted"
        );
    }
}
