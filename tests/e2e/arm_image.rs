//! The arm image (`boards/stm32f405`, bin `arm`) in QEMU's netduinoplus2 under
//! `-icount shift=0,sleep=off` (virtual time follows retired instructions and
//! jumps to the next timer deadline when the core sleeps: deterministic). It
//! starts, its control interrupt runs at the configured rate of the emulated
//! core clock, and the sensors QEMU does not model end in the documented safe
//! state (the encoders' acquisition: QEMU has no DMA, so every period's frames
//! time out) with the drivers disabled and clear log lines; never a hang or a
//! panic. Needs `qemu-system-arm`.

use crate::common;

use std::process::Command;

/// Ticks of the emulated core clock (168 MHz) in one 1 kHz period.
const PERIOD_TICKS: u64 = 168_000;

#[test]
fn arm_image_in_qemu_ticks_at_its_rate_and_goes_safe_without_sensors() {
    let elf = common::qemu_image("arm");
    let run = Command::new("bash").arg(common::workspace().join("scripts/qemu-run.sh")).arg(&elf).output().unwrap();
    let log = common::decode_defmt(&elf, &run.stdout);
    let text = log.join("\n");
    eprintln!("{text}");
    assert!(run.status.success(), "QEMU exit {} (101 = panic): {}\n{text}", run.status, String::from_utf8_lossy(&run.stderr));
    assert!(!text.contains("panic") && !text.contains("hard fault"), "{text}");

    // Start-up: the clocks (QEMU has no RCC), the tick, the encoders' check.
    assert!(text.contains("no RCC model (emulator)"), "{text}");
    assert!(text.contains("arm image up: 1000 us control period"), "{text}");
    assert!(text.contains("drivers disabled until the enable button"), "{text}");
    assert!(text.contains("encoder theta1: not ready") && text.contains("encoder elbow: not ready"), "{text}");
    // QEMU's flash holds no settings record (sector 4 reads zeros, not erased
    // flash): refused, the drivers locked out, and said.
    assert!(text.contains("[error] settings: the settings sector holds something else"), "{text}");

    // No sensor reads: QEMU models no DMA, so each period's frames time out
    // (issue 56: named, both encoders invalid) and the frames are invalid from
    // the first period; bad_frame_limit = 3 such periods latch the
    // acquisition's own reason (13) at period 2, before the bad-frame rule's 2;
    // the drivers never enable (the button, unmodelled, never presses).
    let first = log.iter().find(|l| l.contains("invalid readings")).expect("the invalid readings are logged");
    assert!(first.starts_with("[warn] period 0:") && first.contains("theta1 true, elbow true, f_t true, f_n true"), "{first}");
    let timeout = log.iter().find(|l| l.contains("acquisition failed")).expect("the acquisition's fault is logged");
    assert!(timeout.starts_with("[warn] period 0:") && timeout.contains("did not complete in time"), "{timeout}");
    let safe: Vec<_> = log.iter().filter(|l| l.contains("safe state")).collect();
    assert_eq!(safe.len(), 1, "latched once: {safe:?}");
    assert!(safe[0].starts_with("[error] period 2: safe state, reason 13 (acquisition;"), "{}", safe[0]);
    // Every ERROR and WARN line is one docs/board.md "Under QEMU" explains, no more.
    let loud: Vec<_> = log.iter().filter(|l| l.starts_with("[error]") || l.starts_with("[warn]")).collect();
    assert_eq!(loud.len(), 6, "four errors and two warnings: {loud:#?}");
    let doc = std::fs::read_to_string(common::workspace().join("docs/board.md")).unwrap();
    for l in &loud {
        let words: String = l.split(": ").skip(1).collect::<Vec<_>>().join(": ");
        let key: String = words.chars().take(40).collect();
        assert!(doc.contains(&key), "docs/board.md explains `{l}` (looked for `{key}`)");
    }
    assert!(!text.contains("drivers enabled") && !text.contains("enable button: firmware reset"), "{text}");
    assert!(text.contains("qemu run over: 3000 periods, drivers disabled"), "{text}");

    // The rate: three windows of 1000 periods, every tick interval the same, one
    // period of the emulated core clock plus the timer model's fixed re-arm
    // latency (QEMU 10's stm32f2xx timer: about 24 500 ticks, docs/board.md).
    let windows: Vec<_> = log.iter().filter(|l| l.contains("step ticks median")).collect();
    assert_eq!(windows.len(), 3, "{text}");
    for w in &windows {
        assert!(common::numbers_after(w, "over")[0] == 1000, "{w}");
        let interval = common::numbers_after(w, "tick interval");
        // Under icount the intervals are one instruction count: every run of this
        // test alone measured 192 905..192 905 ticks. In one of three runs of the
        // whole suite on a loaded fresh clone (issue 69) one interval of the last
        // window was 50 ticks longer (192 905..192 955), cause not found (the
        // image's code is the same; QEMU 7.2's icount under host load). Held to
        // 0.1 % of the period, 168 ticks: a jitter of the firmware's own (a
        // handler that overran, a re-arm that drifted) is far larger.
        assert!(interval[1] - interval[0] <= PERIOD_TICKS / 1000, "jitter beyond the log's retries under icount: {w}");
        assert!((PERIOD_TICKS..PERIOD_TICKS * 6 / 5).contains(&interval[0]), "one 1 ms period of 168 MHz ticks: {w}");
        // The handler (sampling, step, outputs) is well inside the period.
        assert!(common::numbers_after(w, "handler worst")[0] < PERIOD_TICKS / 4, "{w}");
    }
    // The stack's high-water mark is measured and small.
    let stack = log.iter().rev().find(|l| l.contains("stack high-water mark")).unwrap();
    let bytes = common::numbers_after(stack, "stack high-water mark")[0];
    assert!((256..16 * 1024).contains(&bytes), "{stack}");
}
