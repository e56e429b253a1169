//! End-to-end: a law of one's own (`examples/law-template`, the impedance law;
//! issue 70) where the paper's laws run, through `sil-host`'s own commands:
//! its firmware process over iceoryx2 (`run --attach`), its PIL image in QEMU
//! (`pil --image`) with the same trace and frames bit for bit, and its `arm`
//! image on the emulated board answering every recorded frame identically
//! (`replay --link emulator --elf`); the scenario's `[law]` table checked
//! against the law's declaration on each link. The first test runs on every law
//! crate the house finds (`common::laws`: a copy made with scripts/new-law.py
//! too); the others on the template's impedance law.

use std::{
    path::Path,
    process::{Child, Command, Stdio},
};

use crate::common;

/// The template's law (examples/law-template: the impedance law).
fn template() -> common::Law {
    common::laws().into_iter().find(|l| l.package == "law-template").expect("the template is a law crate")
}

/// `law`'s firmware process serving rig `rig` with `args` after its scenario.
fn law_firmware(law: &common::Law, rig: &str, args: &[&str]) -> Child {
    Command::new(common::law_firmware(law))
        .args(["firmware", "--rig", rig, "--scenario"])
        .arg(&law.scenario)
        .args(args)
        .stdout(Stdio::null())
        .spawn()
        .unwrap()
}

fn text(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every law crate (the template's and any copy): its firmware process over
/// iceoryx2 and its PIL image give the same trace and frames bit for bit, the
/// runs name the law its firmware announced, and its `arm` image on the
/// emulated board and its PIL image answer every recorded frame identically.
#[test]
fn every_law_runs_over_iceoryx2_in_pil_and_on_the_emulated_board_bit_for_bit() {
    for law in common::laws() {
        let (pil, arm) = common::law_images(&law);
        let scenario = law.scenario.to_str().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let (ipc, qemu) = (dir.path().join("ipc"), dir.path().join("pil"));
        let rig = format!("e2e-law-{}", std::process::id());
        let mut fw = law_firmware(&law, &rig, &["--set", "timing.duration_s=2"]);
        let code =
            common::run(&["run", "--attach", &rig, "--scenario", scenario, "--duration", "2", "--no-page", "--out", ipc.to_str().unwrap()]);
        assert!(fw.wait().unwrap().success(), "{}", law.package);
        assert_eq!(code, 0, "{}", law.package);
        let code = common::run(&[
            "pil",
            "--image",
            pil.to_str().unwrap(),
            "--scenario",
            scenario,
            "--duration",
            "2",
            "--no-page",
            "--out",
            qemu.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{}", law.package);
        for table in ["trace.csv", "frames.csv"] {
            assert!(text(&ipc.join(table)) == text(&qemu.join(table)), "{}: {table}: iceoryx2 and PIL differ", law.package);
        }
        // The runs name the law the firmware announced.
        let s = common::summary_of(&ipc);
        let name = s["firmware_announcement"]["law"]["name"].as_str().unwrap().to_string();
        assert_eq!(s["controller"], name.as_str());
        assert_eq!(common::summary_of(&qemu)["controller"], name.as_str());
        if law.package == "law-template" {
            // The values the scenario's `[law]` table gave, in the declared order.
            assert_eq!(name, "impedance");
            let values = &s["firmware_announcement"]["config"]["law"]["values"];
            assert_eq!(values, &serde_json::json!([2000.0, 90.0, 1000.0, 60.0, 0.0, 0.0, 0.0, 0.0]));
        }
        // The PIL image says which law it was configured for, and its stack stays small.
        let log = text(&qemu.join("defmt.log"));
        assert!(log.contains(&format!("configured: law b\"{name}\", period 1000 us")), "{log}");
        let end = log.lines().find(|l| l.contains("stack high-water mark")).unwrap();
        assert!(common::numbers_after(end, "stack high-water mark")[0] < 16 * 1024, "{end}");
        // The `arm` image on the emulated board and the PIL image answer every
        // recorded frame of the iceoryx2 run bit for bit.
        for link in [["--link", "emulator", "--elf", arm.to_str().unwrap()], ["--link", "pil", "--image", pil.to_str().unwrap()]] {
            let mut args = vec!["replay", ipc.to_str().unwrap()];
            args.extend(link);
            assert_eq!(common::run(&args), 0, "{}: {link:?}", law.package);
        }
    }
}

#[test]
fn a_scenario_for_another_law_is_refused_on_every_link() {
    let template = template();
    let (pil, arm) = common::law_images(&template);
    let law = template.scenario.to_str().unwrap();
    let default = common::workspace().join("scenarios/default.toml");
    let default = default.to_str().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = |tag: &str| dir.path().join(tag).to_str().unwrap().to_string();
    // The paper's laws' firmware (in process, the board twin, the `arm` image,
    // the PIL image) refuses the impedance law's scenario: bad input.
    for (tag, args) in [
        ("in-process", vec!["run", "--in-process"]),
        ("twin", vec!["run", "--link", "twin"]),
        ("emulator", vec!["run", "--link", "emulator"]),
        ("pil", vec!["pil"]),
    ] {
        let o = out(tag);
        let mut full = args.clone();
        full.extend(["--scenario", law, "--duration", "0.1", "--out", o.as_str()]);
        assert_eq!(common::run(&full), 2, "{tag}");
    }
    // The law's images refuse the paper's scenario.
    let o = out("law-pil");
    assert_ne!(common::run(&["pil", "--image", pil.to_str().unwrap(), "--scenario", default, "--duration", "0.1", "--out", &o]), 0);
    let o = out("law-arm");
    assert_ne!(
        common::run(&[
            "run",
            "--link",
            "emulator",
            "--elf",
            arm.to_str().unwrap(),
            "--scenario",
            default,
            "--duration",
            "0.1",
            "--out",
            &o
        ]),
        0
    );
}

/// A law that panics on purpose (`examples/law-template/examples/panicking_arm.rs`:
/// the impedance law until period 500, then `panic!` in the control interrupt) on
/// the emulated board: the image's panic handler disables the motor drivers at
/// once (the enable line, PB14, low), the image stops ticking and the run stops
/// there with the reason; the torques it applied until then are the law's.
#[test]
fn a_law_that_panics_on_the_board_leaves_the_drivers_disabled() {
    use board_link::emulator_link::EmulatorLink;
    use rig::{law::LawTable, period_loop::run_loop, scenario::Scenario, setup::RunSetup};
    let image = common::panicking_law_image(&template());
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = 1.0;
    s.law = Some(LawTable { name: "panicking".into(), params: Default::default() });
    let setup = RunSetup::new(s).unwrap();
    let mut link = EmulatorLink::new(&setup, &image).unwrap();
    let gpiob_odr = |link: &EmulatorLink| board_emulator::checks::peek(link.board().machine(), 0x4002_0414);
    let (records, e) = run_loop(&setup, &mut link, &mut ());
    let e = e.expect("the run stops").to_string();
    assert!(e.contains("ran 0 ticks in one period"), "{e}");
    assert_eq!(records.len(), 500, "the law's 500 periods, then none");
    assert!(records.iter().all(|r| r.status & shared::wire::status::SAFE_STATE == 0), "no safe state before the panic");
    assert!(records[499].u1_applied != 0.0, "the law drove the arm until then");
    assert_eq!(gpiob_odr(&link) & (1 << 14), 0, "the drivers' enable line (PB14) is low after the panic");
}

/// Issue 70: `board configure --elf` binds the scenario's `[law]` table to
/// the law the flashed ELF declares, held to the digest the board's image
/// reports in its status: a law of one's own is configured on a board as on
/// every other link (its values reach the firmware in the declared order; a
/// value out of range or a table for another law is refused with the
/// declaration in the message), and an ELF that is not the board's, or none
/// for a law's image, is refused before anything is sent.
#[test]
fn board_configure_binds_a_law_table_to_the_law_the_board_runs() {
    let (_, arm) = common::law_images(&template());
    let paper = board_link::emulator_link::default_image();
    let dir = tempfile::tempdir().unwrap();
    let scenario = |law: &str| {
        let path = dir.path().join(format!("s{}.toml", law.len()));
        std::fs::write(&path, format!("{}\n{law}\n", rig::scenario::DEFAULT_TOML)).unwrap();
        path.to_str().unwrap().to_string()
    };
    let own = scenario("[law]\nname = \"impedance\"\nk_t = 1500.0\nd_n = 45.0");
    let (arm, paper_elf) = (arm.to_str().unwrap().to_string(), paper.to_str().unwrap().to_string());
    let t = common::BoardTwin::spawn(&["--emulated", "--elf", &arm]);
    let (code, out, err) = t.board(&["configure", "--scenario", &own, "--elf", &arm]);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = t.board(&["--json", "backup", dir.path().join("b.toml").to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let law = &v["backup"]["config"]["law"];
    assert_eq!(law["name"], "impedance", "{law}");
    // k_t, d_t (its default), k_n (its default), d_n, then zeros.
    let values: Vec<f64> = law["values"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert_eq!(values, [1500.0, 90.0, 1000.0, 45.0, 0.0, 0.0, 0.0, 0.0], "{law}");
    for (table, elf, says) in [
        ("[law]\nname = \"impedance\"\nk_t = 1e6", Some(&arm), "k_t"),
        ("[law]\nname = \"impedance\"\nstifness = 1.0", Some(&arm), "stifness"),
        ("[law]\nname = \"pd\"", Some(&arm), "impedance"),
        ("", Some(&arm), "impedance"),
        ("[law]\nname = \"impedance\"", None, "--elf"),
        ("[law]\nname = \"impedance\"", Some(&paper_elf), "not the one the board runs"),
    ] {
        let s = scenario(table);
        let mut args = vec!["configure", "--scenario", &s];
        if let Some(elf) = elf {
            args.extend(["--elf", elf.as_str()]);
        }
        let (code, _, err) = t.board(&args);
        assert_eq!(code, 2, "{table} {elf:?}: {err}");
        assert!(err.contains(says) && err.contains("configure"), "{table} {elf:?}: {err}");
    }
    drop(t);
    // The paper's image runs the paper's laws: a `[law]` table is refused, the
    // law's ELF too.
    let t = common::BoardTwin::spawn(&["--emulated", "--elf", &paper_elf]);
    let (code, _, err) = t.board(&["configure", "--scenario", &own]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("impedance") && err.contains("paper"), "{err}");
    let (code, _, err) = t.board(&["configure", "--scenario", &own, "--elf", &arm]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not the one the board runs"), "{err}");
}
