//! Processor in the loop: the `pil` image (thumbv7em-none-eabihf, the one that
//! would be flashed) in QEMU's netduinoplus2 closes the loop with the plant over
//! the emulated USART. Checks: the default scenario gives the SIL outcome (no
//! lift-off, tracking error within 1 % of the in-process run); the worst step of
//! each controller is within the 8400-instruction budget (HARDWARE.md: 5 % of a
//! 1 kHz period at 168 MHz); the image fits its flash and RAM budgets; a dead
//! QEMU or a missing image ends a run with a clear error, never a hang.
//!
//! Needs `qemu-system-arm` (Debian's package; `.ci/run` installs it). The image
//! is built here if needed, in its own target folder (the outer `cargo test`
//! holds the workspace's).

use std::{
    path::{Path, PathBuf},
    process::Command,
    sync::OnceLock,
};

use sil_host::{
    commands::run::rms_tracking_error,
    sil::{
        in_process,
        pil_link::{PilLink, PilOptions, STEP_BUDGET_INSTRUCTIONS, Spread},
        record::{RunError, lift_off_stats},
        rig::{FirmwareLink, run_loop},
        scenario::Scenario,
    },
};

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Builds the PIL image once per test binary; its path.
fn image() -> &'static Path {
    static IMAGE: OnceLock<PathBuf> = OnceLock::new();
    IMAGE.get_or_init(|| {
        assert!(
            Command::new("qemu-system-arm").arg("--version").output().is_ok(),
            "qemu-system-arm is missing: apt-get install -y qemu-system-arm (CI installs it)"
        );
        let root = workspace();
        let target_dir = root.join("target/mcu-test");
        let build = Command::new(env!("CARGO"))
            .args(["build", "-p", "firmware", "--profile", "mcu", "--target", "thumbv7em-none-eabihf", "--bin", "pil"])
            .env("CARGO_TARGET_DIR", &target_dir)
            .current_dir(&root)
            .output()
            .unwrap();
        assert!(build.status.success(), "building the PIL image failed:\n{}", String::from_utf8_lossy(&build.stderr));
        target_dir.join("thumbv7em-none-eabihf/mcu/pil")
    })
}

fn scenario(controller: &str, duration_s: f64) -> Scenario {
    let mut s = Scenario::default_scenario();
    s.controller.kind = controller.into();
    s.timing.duration_s = duration_s;
    s
}

#[test]
fn the_pil_image_fits_its_flash_and_ram_budgets() {
    let out = Command::new("python3").arg(workspace().join("scripts/budgets.py")).arg(image()).arg("--json").output().unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("budgets.py prints JSON");
    assert!(out.status.success() && report["ok"] == true, "over budget:\n{report:#}");
    assert!(report["flash_bytes"].as_u64().unwrap() <= 64 * 1024);
    assert!(report["static_ram_bytes"].as_u64().unwrap() <= 16 * 1024);
    assert_eq!(report["heap_allocator_symbols"].as_array().unwrap().len(), 0);
}

#[test]
fn default_scenario_in_pil_gives_the_sil_outcome_within_the_step_budget() {
    // 4 s: the 2 s move and the hold after it (the default runs 10 s).
    let s = scenario("hybrid", 4.0);
    let (sil, err) = in_process::run(&s, |_, _| {});
    assert!(err.is_none(), "{err:?}");

    let mut link = PilLink::start(&s, &PilOptions::new(image()), None).unwrap();
    let (pil, err) = run_loop(&s, &mut link, |_, _| true, |_| {});
    assert!(err.is_none(), "{err:?}");
    assert_eq!(pil.len(), sil.len());
    for (name, records) in [("SIL", &sil), ("PIL", &pil)] {
        let st = lift_off_stats(records);
        assert_eq!((st.lift_offs, st.false_alarms), (0, 0), "{name}: {st:?}");
        assert!(records.iter().all(|r| !r.deadline_miss), "{name}: no deadline miss");
    }
    let (rms_sil, rms_pil) = (rms_tracking_error(&sil), rms_tracking_error(&pil));
    assert!((rms_pil - rms_sil).abs() <= 0.01 * rms_sil, "tracking error: PIL {rms_pil:e} m vs SIL {rms_sil:e} m");
    assert!((pil.last().unwrap().z_t - 0.10).abs() < 1e-3);

    // The image measured every step (SysTick under -icount shift=0).
    let c = &link.counts;
    assert_eq!(c.step_ticks.len(), pil.len());
    assert_eq!(c.ticks_per_second, 168_000_000);
    let step = Spread::of(&c.step_ticks, c.instructions_per_tick());
    let frame = Spread::of(&c.frame_ticks, c.instructions_per_tick());
    assert!(step.worst <= STEP_BUDGET_INSTRUCTIONS, "hybrid: worst step {} instructions > {STEP_BUDGET_INSTRUCTIONS}", step.worst);
    assert!(step.median > 500.0, "a hybrid step is not free: {step:?}");
    assert!(frame.median > step.median, "the frame includes the step: {frame:?} vs {step:?}");

    // The image's defmt log, decoded here, tells the same story.
    link.finish(pil.len() as u32);
    assert!(link.exit_status().is_some_and(|e| e.success()), "the image ended QEMU cleanly: {:?}", link.exit_status());
    let log = link.log();
    assert!(log.iter().any(|l| l.message.starts_with("configured: hybrid")), "{log:?}");
    let end = log.iter().find(|l| l.message.starts_with("end of run")).expect("the image logged its end");
    assert!(end.message.contains(&format!("{} frames", pil.len())), "{}", end.message);
}

#[test]
fn pid_through_the_cli_reports_its_instruction_counts_within_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pid");
    let code = sil_host::run([
        "sil-host",
        "pil",
        "--controller",
        "pid",
        "--duration",
        "2.5",
        "--image",
        image().to_str().unwrap(),
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["transport"], "pil-qemu");
    assert_eq!(summary["controller"], "pid");
    assert_eq!(summary["periods"], 2500);
    let pil = &summary["pil"];
    let worst = pil["step_instructions"]["worst"].as_f64().unwrap();
    assert!(worst <= STEP_BUDGET_INSTRUCTIONS && pil["within_budget"] == true, "pid: worst step {worst} instructions");
    assert!(pil["step_instructions"]["median"].as_f64().unwrap() > 300.0);
    assert_eq!(pil["qemu_icount_shift"], 0);
    let log = std::fs::read_to_string(out.join("defmt.log")).unwrap();
    assert!(log.contains("configured: pid") && log.contains("end of run: 2500 frames"), "{log}");
    for f in ["trace.csv", "trace.svg", "instructions.svg"] {
        assert!(out.join(f).is_file(), "{f} written");
    }
}

#[test]
fn a_killed_qemu_or_a_missing_image_ends_the_run_with_a_clear_error() {
    // QEMU killed at 0.3 s (the kill_firmware fault): every period before is kept.
    let mut s = scenario("hybrid", 1.0);
    s.faults =
        Scenario::from_toml(&format!("{}\n[[faults]]\nkind = \"kill_firmware\"\nat_s = 0.3\n", sil_host::sil::scenario::DEFAULT_TOML))
            .unwrap()
            .faults;
    let mut link = PilLink::start(&s, &PilOptions::new(image()), None).unwrap();
    let (records, err) = run_loop(&s, &mut link, |_, _| true, |_| {});
    match err {
        Some(RunError::FirmwareLost { k, what, .. }) => {
            assert_eq!(k, 300);
            assert!(what.contains("QEMU"), "{what}");
        }
        other => panic!("expected FirmwareLost, got {other:?}"),
    }
    assert_eq!(records.len(), 300);

    // No image: exit 2 and a hint on how to build it; a missing QEMU: exit 1.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("none");
    let code = sil_host::run(["sil-host", "pil", "--image", "/nonexistent/pil", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 2);
    let err =
        PilLink::start(&s, &PilOptions { qemu: "/nonexistent/qemu-system-arm".into(), ..PilOptions::new(image()) }, None).unwrap_err();
    assert!(err.to_string().contains("cannot start /nonexistent/qemu-system-arm"), "{err}");
}
