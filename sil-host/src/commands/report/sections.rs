//! The experiments of the report: each a section with the commands (argument
//! lists, exactly as a user would type them) that reproduce it.

use std::path::{Path, PathBuf};

use crate::cli::ReportSize;

/// One command of an experiment.
#[derive(Debug, Clone)]
pub struct Step {
    /// Sub-folder of the report (and the step's name).
    pub id: &'static str,
    /// Arguments after `sil-host` (without `--out` and `--json`).
    pub args: Vec<String>,
    /// Whether the command writes files (takes `--out`).
    pub writes: bool,
    /// What this run is within its section, where the section has runs of different
    /// kinds (`the sampled firmware` beside `the paper's ideal law`).
    pub what: Option<&'static str>,
}

/// One section of the report: an experiment of docs/model.md with its commands.
#[derive(Debug, Clone)]
pub struct Section {
    /// What the paper shows, and where.
    pub title: &'static str,
    /// docs/model.md experiment and paper figure or table.
    pub source: &'static str,
    /// The commands that reproduce it.
    pub steps: Vec<Step>,
    /// Whether it belongs in the appendix (the rig and the firmware, not a result of
    /// the paper): shown after the reproduction's sections.
    pub appendix: bool,
}

fn step(id: &'static str, args: &[&str]) -> Step {
    Step { id, args: args.iter().map(|s| (*s).to_string()).collect(), writes: true, what: None }
}

/// [`step`] with what the run is within its section ([`Step::what`]).
fn step_of(id: &'static str, what: &'static str, args: &[&str]) -> Step {
    Step { what: Some(what), ..step(id, args) }
}

/// The paper's scenario files: `./scenarios`, else the repository's at build time.
pub fn scenario_dir() -> Option<PathBuf> {
    [PathBuf::from("scenarios"), Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")].into_iter().find(|p| p.is_dir())
}

/// `--seeds N` for the sampled loop's commands (nothing for one seed, the commands' default).
fn seeds_args(seeds: usize) -> Vec<String> {
    if seeds > 1 { vec!["--seeds".into(), seeds.to_string()] } else { Vec::new() }
}

/// `args` then `extra`.
fn with(args: &[&str], extra: &[String]) -> Vec<String> {
    args.iter().map(|s| (*s).to_string()).chain(extra.iter().cloned()).collect()
}

/// The experiments, at the size asked for, the sampled loop's over `seeds` sensor-noise seeds.
pub fn sections(size: ReportSize, scenarios: &Path, seeds: usize) -> Vec<Section> {
    let quick = size == ReportSize::Quick;
    let seeded = seeds_args(seeds);
    let mut v = vec![
        Section {
            title: "Contact modes on the belt",
            source: "docs/model.md experiment 1, paper Fig. 2",
            appendix: false,
            steps: vec![step("modes", &["modes", "--mu", "0.6", "--grid", if quick { "200" } else { "400" }])],
        },
        Section {
            title: "Admissible configurations",
            source: "docs/model.md experiment 2, paper Table II",
            appendix: false,
            steps: vec![step("admissible", &["admissible", "--mu", "0.6"])],
        },
        Section {
            title: "Open-loop bouncing from x0a",
            source: "docs/model.md experiments 3 and 4 (one run of the open-loop system, u = 0)",
            appendix: false,
            steps: vec![step("simulate", &["simulate", "--x0", "a", "--mu", "0.6", "--v-belt", "-0.4", "--duration", "10"])],
        },
    ];
    v.push(Section {
        title: "Open-loop two-parameter bifurcation diagram",
        source: "docs/model.md experiment 3, paper Fig. 3: persistent bouncing over (v_belt, mu), u = 0, from x0a and x0d, for e_n = 0, 0.2 and 0.5 (how the band moves with the impact law)",
        appendix: false,
        steps: vec![step(
            "sweep-open-loop",
            &if quick {
                vec!["sweep", "--v-belt-step", "0.01", "--transient", "100", "--record", "30", "--e-n", "0,0.2,0.5"]
            } else {
                vec!["sweep", "--e-n", "0,0.2,0.5"]
            },
        )],
    });
    v.push(Section {
        title: "Closed-loop bifurcation diagram (hybrid force/motion control)",
        source: "docs/model.md experiment 7, paper Fig. 9: experiment 3's sweep from x0d with the hybrid controller in the loop",
        appendix: false,
        steps: {
            let args = if quick {
                vec!["sweep", "--controller", "hybrid", "--ics", "d", "--v-belt-step", "0.05", "--transient", "20", "--record", "10"]
            } else {
                vec!["sweep", "--controller", "hybrid", "--ics", "d"]
            };
            vec![
                Step {
                    args: with(&args, &seeded),
                    ..step_of("sweep-hybrid", "the sampled firmware (1 kHz, docs/hardware.md's sensors, saturated torques)", &args)
                },
                step_of(
                    "sweep-hybrid-ideal",
                    "the paper's ideal law (continuous time, exact measurements, no saturation)",
                    &[&args[..], &["--ideal"]].concat(),
                ),
            ]
        },
    });
    v.push(Section {
        title: "Fig. 9 at the saturation edge: the sampled loop over its sensor noise",
        source: "issue 82: the sampled hybrid loop from x0d at mu 0.86 to 0.9, where holding f_n* takes the base motor to its 5 N m limit; \
                 each cell over the sensor noise's seeds, as a fraction with its Wilson 95 % interval",
        appendix: false,
        steps: {
            let grid: Vec<&str> = if quick { vec!["--v-belt-step", "0.05", "--transient", "20", "--record", "10"] } else { vec![] };
            let args =
                [&["sweep", "--controller", "hybrid", "--ics", "d", "--mu", "0.86,0.9", "--mu-step", "0.01"][..], &grid[..]].concat();
            vec![Step { args: with(&args, &seeded), ..step("sweep-hybrid-edge", &args) }]
        },
    });
    v.push(Section {
        title: "One-parameter bifurcation diagram (Poincaré section)",
        source: "docs/model.md experiment 4, paper Fig. 4: mu = 0.6 from x0a, theta1 where theta1_dot crosses 0 upwards",
        appendix: false,
        steps: vec![step(
            "poincare",
            &if quick {
                vec!["poincare", "--mu", "0.6", "--v-step", "0.004", "--transient", "150", "--record", "50"]
            } else {
                vec!["poincare", "--mu", "0.6"]
            },
        )],
    });
    v.push(Section {
        title: "Z_t,sliding: how far each controller drives the tip with no lift-off",
        source: "docs/model.md experiments 5 and 6 (the paper's continuous-time setting, --ideal, and our sampled firmware)",
        appendix: false,
        steps: vec![Step { args: with(&["zmax", "--all"], &seeded), ..step("zmax", &["zmax", "--all"]) }],
    });
    v.push(Section {
        title: "Sensitivity to the choices the paper leaves open",
        source: "docs/model.md \"What the paper leaves open\": the headline results under each open choice, one at a time from the defaults (sil-host sensitivity)",
        appendix: false,
        steps: {
            let args = ["sensitivity", "--size", if quick { "quick" } else { "paper" }];
            vec![Step { args: with(&args, &seeded), ..step("sensitivity", &args) }]
        },
    });
    v.push(Section {
        title: "PID and hybrid force/motion control in the SIL loop",
        source: "docs/model.md experiments 5 and 6 (paper Figs. 6 to 8): the firmware sampled at 1 kHz with docs/hardware.md's sensors",
        appendix: false,
        steps: ["pid-x0d", "pid-x0u", "hybrid-x0d", "hybrid-x0u"]
            .into_iter()
            .map(|name| Step {
                id: name,
                writes: true,
                what: None,
                args: vec![
                    "run".into(),
                    "--in-process".into(),
                    "--scenario".into(),
                    scenarios.join(format!("{name}.toml")).to_string_lossy().into_owned(),
                ],
            })
            .collect(),
    });
    v.push(Section {
        title: "The hybrid law when friction is not known",
        source: "issue 41, docs/analyses.md \"The hybrid law when friction is not known\": the sampled hybrid law from x0d with mu_hat 10 % low, the paper's friction term beside the estimated one (controller.friction = estimated)",
        appendix: false,
        steps: [("hybrid-x0d-mu-hat-low", "commanded"), ("hybrid-x0d-mu-hat-low-estimated", "estimated")]
            .into_iter()
            .map(|(id, friction)| Step {
                id,
                writes: true,
                what: Some(if friction == "commanded" {
                    "mu_hat 10 % low, the commanded friction term"
                } else {
                    "mu_hat 10 % low, the friction term from the estimated mu"
                }),
                args: vec![
                    "run".into(),
                    "--in-process".into(),
                    "--scenario".into(),
                    scenarios.join("hybrid-x0d.toml").to_string_lossy().into_owned(),
                    "--set".into(),
                    "controller.mu_hat=0.54".into(),
                    "--set".into(),
                    format!("controller.friction={friction}"),
                ],
            })
            .collect(),
    });
    v.push(Section {
        title: "Speed of the rig",
        source: "control periods per wall second on the default scenario, in-process and in lockstep over iceoryx2 (sil-host bench)",
        appendix: true,
        steps: vec![Step {
            writes: false,
            ..step(
                "bench",
                &if quick {
                    vec!["bench", "--only", "in-process,lockstep", "--repeat", "3", "--duration", "2"]
                } else {
                    vec!["bench", "--only", "in-process,lockstep", "--repeat", "5", "--duration", "10"]
                },
            )
        }],
    });
    // The MCU image in QEMU, when it is built and QEMU is here (docs/board.md).
    let qemu = std::process::Command::new("qemu-system-arm").arg("--version").output().is_ok_and(|o| o.status.success());
    if qemu && rig::pil_link::default_image().is_file() {
        v.push(Section {
            title: "The firmware on the MCU (processor in the loop)",
            source: "the default scenario with the Cortex-M4F image in QEMU; instructions per control step against docs/hardware.md \"Budgets\"",
            appendix: true,
            steps: vec![step("pil", &["pil", "--duration", if quick { "2" } else { "10" }])],
        });
    }
    v
}
