//! Every cargo alias of `.cargo/config.toml` (issue 44: `cargo qemu-arm` did not
//! parse, and nothing ran it): each one that needs no board is run as a user runs
//! it, `cargo ALIAS`, and must succeed; the four that flash a board (`arm`, `pil`,
//! and the template's law's `law-arm`, `law-pil`)
//! are run with probe-rs missing and must stop with the runner's advice (how to
//! install probe-rs, what runs without a board), exit 127, not cargo's "could not
//! execute process". An alias this test does not know fails it: add its check.
//! `cargo qemu-arm`'s log must carry the defmt timestamps (`mcu::log_time`).
//!
//! The builds go to the workspace's `target/` (`common::target_dir`), where
//! scripts/test.sh built the images already: the aliases' builds are then cargo's
//! freshness checks, and the runs use those images. Needs `qemu-system-arm`
//! and flip-link (scripts/test.sh installs both).

use crate::common;

use std::process::{Command, Output};

/// The aliases this test runs, and how.
const KNOWN: [&str; 7] = ["arm", "pil", "law-arm", "law-pil", "qemu-arm", "build-arm", "build-pil"];

/// `cargo ALIAS` from the workspace's `docs/` folder (an alias must not depend
/// on the folder it is typed in), the builds in `target/` ([`common::target_dir`]).
fn cargo(alias: &str) -> Output {
    let root = common::workspace();
    Command::new(env!("CARGO"))
        .arg(alias)
        .current_dir(root.join("docs"))
        .env("CARGO_TARGET_DIR", common::target_dir())
        // A probe-rs that is not there, whatever this machine has installed.
        .env("PAINLEVE_PROBE_RS", "probe-rs-absent-for-the-alias-test")
        .env_remove("CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUNNER")
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!("exit {}\n{}", o.status, String::from_utf8_lossy(&o.stderr))
}

#[test]
fn every_alias_runs_and_the_board_ones_say_how_to_get_probe_rs() {
    let config: toml::Table = std::fs::read_to_string(common::workspace().join(".cargo/config.toml")).unwrap().parse().unwrap();
    let aliases = config["alias"].as_table().expect("an [alias] table");
    for name in aliases.keys() {
        assert!(KNOWN.contains(&name.as_str()), "alias `{name}` is not run by tests/e2e/aliases.rs: add its check");
    }
    assert_eq!(aliases.len(), KNOWN.len(), "{aliases:?}");
    let target = common::target_dir().join("thumbv7em-none-eabihf");

    // The builds: each image where the tools look for it.
    for (alias, elf) in [("build-pil", "qemu/pil"), ("build-arm", "mcu/arm")] {
        let o = cargo(alias);
        assert!(o.status.success(), "cargo {alias}: {}", text(&o));
        assert!(target.join(elf).is_file(), "cargo {alias} made no {elf}");
    }

    // The arm image in QEMU: 3000 periods of virtual time, exit 0, its log
    // timestamped with the control tick's time.
    let o = cargo("qemu-arm");
    assert!(o.status.success(), "cargo qemu-arm: {}", text(&o));
    let log = common::decode_defmt_stamped(&target.join("qemu/arm"), &o.stdout);
    let all: Vec<String> = log.iter().map(|(t, l)| format!("{t:?} {l}")).collect();
    let all = all.join("\n");
    assert!(all.contains("qemu run over: 3000 periods"), "{all}");
    let mut windows = 0;
    for (stamp, line) in &log {
        let stamp = stamp.as_deref().unwrap_or_else(|| panic!("a line without a timestamp: {line}"));
        // `period K: ...` is logged in period K's tick: stamped K ms.
        if let Some(rest) = line.split("] period ").nth(1) {
            let k: u64 = rest.split(':').next().unwrap().parse().unwrap();
            assert_eq!(stamp, format!("{}.{:06}", k / 1000, (k % 1000) * 1000), "{line}");
            windows += usize::from(line.contains("step ticks median"));
        }
    }
    assert_eq!(windows, 3, "{all}");
    // The end, in the idle loop after the last tick (period 2999).
    assert_eq!(log.last().unwrap().0.as_deref(), Some("2.999000"), "{all}");

    // The board aliases without probe-rs: the runner's advice, not cargo's error.
    for alias in ["arm", "pil", "law-arm", "law-pil"] {
        let o = cargo(alias);
        let err = text(&o);
        assert_eq!(o.status.code(), Some(127), "cargo {alias}: {err}");
        assert!(err.contains("probe-rs is not installed") && err.contains("cargo install probe-rs-tools"), "cargo {alias}: {err}");
        assert!(err.contains("cargo qemu-arm"), "cargo {alias}: what runs without a board: {err}");
        assert!(!err.contains("could not execute process"), "cargo {alias}: {err}");
    }
}
