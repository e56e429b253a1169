//! `sil-host report`: every experiment runs and lands in one page.

use crate::figure_check;

use std::process::Command;

#[test]
fn the_quick_report_runs_every_experiment_and_links_every_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let results = dir.path().join("results.md");
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        // Two seeds for the sampled loop's cells (the report's default, 16, costs minutes more).
        .args(["report", "--json", "--seeds", "2", "--out"])
        .arg(&out)
        .arg("--results")
        .arg(&results)
        .output()
        .unwrap();
    if !o.status.success() {
        // Name the failed experiments and why (the folder goes with the test).
        let page = std::fs::read_to_string(out.join("report.md")).unwrap_or_default();
        let failed: Vec<&str> = page.lines().filter(|l| l.contains("**failed**") || l.starts_with("**Failed**")).collect();
        let why: Vec<&str> = page.split("**Failed**:").skip(1).map(|s| s.split("```").nth(1).unwrap_or("")).collect();
        panic!("{}\nfailed: {failed:#?}\nwhy: {why:#?}", String::from_utf8_lossy(&o.stderr));
    }
    let index: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(index["failed"], 0);
    let steps = index["steps"].as_array().unwrap();
    let ids: Vec<&str> = steps.iter().map(|s| s["id"].as_str().unwrap()).collect();
    for id in [
        "modes",
        "admissible",
        "sweep-open-loop",
        "sweep-hybrid",
        "sweep-hybrid-edge",
        "poincare",
        "zmax",
        "sensitivity",
        "pid-x0u",
        "hybrid-x0d",
    ] {
        assert!(ids.contains(&id), "{id} missing from {ids:?}");
    }
    let page = std::fs::read_to_string(out.join("report.md")).unwrap();
    // The sampled loop's results are fractions over its seeds (issue 82): the edge
    // of Fig. 9 from mu 0.86 to 0.9, each with its interval, and the command that made it.
    assert!(page.contains("`sil-host report --size quick --seeds 2`"), "the page names its seeds");
    let edge = page.split("## Fig. 9 at the saturation edge").nth(1).expect("the edge's section").split("\n## ").next().unwrap();
    assert!(edge.contains("--seeds 2"), "the edge's command has its seeds");
    for mu in ["0.86", "0.87", "0.88", "0.89", "0.90"] {
        let row = edge.lines().find(|l| l.starts_with(&format!("| {mu} | "))).unwrap_or_else(|| panic!("no row for mu {mu}"));
        assert!(row.contains("/38 = ") && row.contains(" ["), "{row}");
    }
    assert!(!page.contains("at `mu` 0.86 to 0.89 all keep contact"), "the single-seed claim is gone");
    // Every figure written is shown, and every link points at a file that exists.
    let mut figures = 0;
    for s in steps {
        for f in s["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap()) {
            assert!(out.join(f).is_file(), "{f}");
            if f.ends_with(".svg") {
                figures += 1;
                assert!(page.contains(&format!("]({f})")), "{f} not shown");
            }
        }
    }
    assert!(figures >= 10, "{figures} figures");
    // Every figure fit for a paper: no text off the canvas or over another, no -0
    // (tests/e2e/figure_check.rs); rendered to PNG under target/tmp/figures/report.
    assert!(figure_check::check_all(&out, "report") >= figures);
    // The controller comparison of the paper: the hybrid law slides from x0d, PID from x0u lifts off.
    let summary = |id: &str| steps.iter().find(|s| s["id"] == id).unwrap()["result"].clone();
    assert_eq!(summary("hybrid-x0d")["lift_offs"], 0);
    assert!(summary("pid-x0u")["lift_offs"].as_u64().unwrap() >= 1);
    // Numbers keep their digits: the integrator's tolerances are not rounded to 0.
    assert!(page.contains("| rtol, atol | 1e-9, 1e-11 |"), "tolerances not shown as 1e-9, 1e-11");
    assert!(!page.contains("| rtol, atol | 0, 0 |"));
    sensitivity_properties(&summary("sensitivity")["study"]);
    assert!(page.contains("Sensitivity to the choices the paper leaves open"));
    // The paper side by side: every printed number with ours next to it.
    let side = page.split("## The paper side by side").nth(1).expect("the side-by-side section").split("\n## ").next().unwrap();
    for printed in ["0.183 m", "0.168 m", "[-0.575, -0.3] m/s", "0.0375 m", "0.148 m", "0.163 m", "none (lifts off)"] {
        assert!(side.contains(printed), "the paper's {printed} is in the table");
    }
    assert!(side.lines().filter(|l| l.starts_with("| ")).count() >= 12, "{side}");
    assert!(!side.contains("did not run"), "every row has ours: {side}");
    // The closed loop: the sampled firmware beside the ideal law, per mu.
    assert!(page.contains("sweep-hybrid-ideal: lift-off / not reached / contact / safe state / other"));
    // Every figure numbered, in order, with its caption below it.
    let numbered = page.matches("**Figure ").count();
    assert_eq!(numbered, page.matches("![Figure ").count() - side_by_side_extra(&page), "{page}");
    for n in 1..=numbered {
        assert!(page.contains(&format!("**Figure {n}.** ")), "Figure {n} has no caption");
    }
    // The engineering sections come after the reproduction, in the appendix.
    let appendix = page.find("## Appendix: the rig and the firmware").expect("the appendix");
    assert!(page.find("### Speed of the rig").is_some_and(|b| b > appendix), "bench in the appendix");
    assert!(page.find("## Sensitivity to the choices").is_some_and(|s| s < appendix));
    // The results page: the same page, stamped, its figures copied beside it and
    // referenced by relative path; no temporary folder named.
    let results_dir = results.parent().unwrap().to_path_buf();
    let results = std::fs::read_to_string(&results).unwrap();
    assert!(results.contains("commit `") && results.contains("UTC") && results.contains("CPUs"), "no stamp");
    assert!(results.contains("| hybrid-x0d |") || results.contains(" hybrid-x0d |"), "no run comparison");
    let images = image_targets(&results);
    assert!(images.len() >= figures, "{} of {figures} figures on the results page", images.len());
    for target in &images {
        assert!(target.starts_with("figures/") && (target.ends_with(".svg") || target.ends_with("/animation.gif")), "{target}");
        assert!(results_dir.join(target).is_file(), "{target} not copied");
    }
    assert!(!results.contains(&dir.path().display().to_string()), "the results page names the temporary folder");
    assert!(results.contains("--out OUT/modes"), "commands write to OUT");
}

/// The images a Markdown page shows: the targets of its `![alt](target)`.
fn image_targets(page: &str) -> Vec<String> {
    page.split("![")
        .skip(1)
        .filter_map(|s| s.split_once("](").and_then(|(_, rest)| rest.split_once(')')).map(|(t, _)| t.to_string()))
        .collect()
}

/// Images beyond the first of each side-by-side figure (one number, several images).
fn side_by_side_extra(page: &str) -> usize {
    page.lines().filter(|l| l.starts_with("| ![Figure ")).map(|l| l.matches("![Figure ").count() - 1).sum()
}

/// Properties of the sensitivity study (issue 14) that do not depend on its numbers:
/// every dimension's default gives the same results (each is computed on its own);
/// the bouncing band at mu = 0.6 from x0a grows with e_n for every impact law
/// (more restitution, more bouncing); a choice that does not enter a result leaves
/// it uncomputed; nothing simulated violates the model.
fn sensitivity_properties(study: &serde_json::Value) {
    let results = study["results"].as_array().unwrap();
    let defaults: Vec<&serde_json::Value> = results.iter().filter(|r| r["choice"]["is_default"] == true).collect();
    assert_eq!(defaults.len(), 12, "one default per dimension (12 dimensions since issue 40's singular-point rule)");
    let zmax_of = |r: &serde_json::Value| -> Vec<(String, serde_json::Value)> {
        r["zmax"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|z| {
                [
                    (format!("{} sliding", z["combination"]), z["z_t_sliding"].clone()),
                    (format!("{} tracking", z["combination"]), z["z_t_tracking"].clone()),
                ]
            })
            .collect()
    };
    let reference = defaults.iter().find(|r| r["choice"]["dimension"] == "impact_law").unwrap();
    for d in &defaults {
        for (k, v) in zmax_of(d) {
            let want = zmax_of(reference).into_iter().find(|(rk, _)| *rk == k).map(|(_, v)| v);
            assert_eq!(Some(v), want, "{}: Z_t,sliding of {k}", d["choice"]["dimension"]);
        }
        if !d["open_loop"].is_null() {
            assert_eq!(d["open_loop"], reference["open_loop"], "{}", d["choice"]["dimension"]);
        }
        if !d["closed_loop"].is_null() {
            assert_eq!(d["closed_loop"], reference["closed_loop"], "{}", d["choice"]["dimension"]);
        }
    }
    for law in ["newton", "poisson", "energetic"] {
        let width = |e: &str| {
            let r = results.iter().find(|r| r["choice"]["value"] == format!("{law}, e_n = {e}")).unwrap();
            let b = &r["open_loop"]["band_x0a_mu06"];
            if b.is_null() { 0.0 } else { b[1].as_f64().unwrap() - b[0].as_f64().unwrap() }
        };
        assert!(width("0") <= width("0.2") && width("0.2") <= width("0.5"), "{law}: {} {} {}", width("0"), width("0.2"), width("0.5"));
        assert!(width("0.5") > 0.0, "{law} bounces at e_n = 0.5");
    }
    for r in results {
        let dim = r["choice"]["dimension"].as_str().unwrap();
        if ["rate", "encoder_bits", "load_noise", "mu_hat", "friction", "move_time", "torque_limit", "delay"].contains(&dim) {
            assert!(r["open_loop"].is_null(), "{dim} does not enter the open loop");
        }
        if ["rate", "encoder_bits", "load_noise", "mu_hat", "friction", "torque_limit", "delay"].contains(&dim) {
            assert!(r["zmax"].as_array().unwrap().iter().all(|z| z["combination"]["setting"] == "sampled"), "{dim}: sampled only");
        }
    }
    for k in ["energy_gains", "cone_violations", "integrator_failures"] {
        assert_eq!(study["validity"][k], 0, "{k}");
    }
}

/// Issue 27: a signal stopped only the sweep running at that moment, and the report
/// went on (161 s in one trial). One cancellation now reaches every step: the
/// running experiment stops (a sweep within a run), the later ones are not run,
/// the page is written with what finished, and the exit code is the shell's 130.
#[test]
fn ctrl_c_stops_the_whole_report_and_keeps_what_finished() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let child = Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["report", "--json", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Once the open-loop sweep holds its folder (it runs), however loaded the machine.
    let owner = out.join("sweep-open-loop").join(".sil-host.owner");
    let start = std::time::Instant::now();
    while !owner.exists() {
        assert!(start.elapsed() < std::time::Duration::from_secs(300), "the report never reached its sweep");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let signalled = std::time::Instant::now();
    let o = child.wait_with_output().unwrap();
    let took = signalled.elapsed();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted") && err.contains("experiments finished"), "{err}");
    // The stop takes the sweep's current run and the 0.5 s grace; 30 s leaves room
    // for a loaded machine and is still far from the report's remaining minutes.
    assert!(took < std::time::Duration::from_secs(30), "stopped after {took:?}");
    let index: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let step = |id: &str| index["steps"].as_array().unwrap().iter().find(|s| s["id"] == id).unwrap().clone();
    for id in ["modes", "admissible", "simulate"] {
        assert_eq!(step(id)["ok"], true, "{id} finished before the signal");
    }
    assert!(step("sweep-open-loop")["error"].as_str().unwrap().contains("interrupted"), "{}", step("sweep-open-loop"));
    for id in ["sweep-hybrid", "zmax", "sensitivity", "hybrid-x0d"] {
        assert!(step(id)["error"].as_str().unwrap().starts_with("not run: the report was interrupted"), "{}", step(id));
    }
    assert!(std::fs::read_to_string(out.join("report.md")).unwrap().contains("not run: the report was interrupted"));
}
