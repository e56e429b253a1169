//! The MCU figures: the worst control step of each controller and PIL periods per
//! wall second, from PIL runs of the image in QEMU ([`crate::bench::pil`]); the
//! image's flash and static RAM ([`crate::bench::elf`]); the worst step's cycle
//! estimate (`scripts/cycles.py`).

use std::path::{Path, PathBuf};

use super::STEP_INSTRUCTIONS_TARGET;
use crate::bench::{
    elf::image_size,
    figure::{Figure, Goal, median},
    pil::{self, PilRuns, highest_rate},
};
use crate::{cli::BenchArgs, error::CliError};
use firmware::ControllerKind;

/// Target of PIL periods per wall second (real time at 1 kHz; issue 16).
pub const PIL_RATE_TARGET: f64 = 1_000.0;
/// Flash target of the PIL image built with profile `mcu`, bytes (issue 16).
pub const FLASH_MCU_TARGET: f64 = 32.0 * 1024.0;
/// Flash target of the PIL image built with plain `--release`: the budget, bytes
/// (docs/hardware.md: 64 KiB).
pub const FLASH_RELEASE_TARGET: f64 = 64.0 * 1024.0;

/// The PIL image the bench runs: `--image`, else `target/thumbv7em-none-eabihf/qemu/pil`.
fn image(args: &BenchArgs, target: &Path) -> PathBuf {
    args.image.clone().unwrap_or_else(|| target.join("thumbv7em-none-eabihf/qemu/pil"))
}

/// Runs the image ([`image`]) in QEMU: `--repeat` (at most 3) runs of the hybrid
/// controller, then one of PID, each `--pil-s` long ([`pil::pil_runs`]). No image
/// or no QEMU: `Err` with the reason and the fix (the figures are skipped).
///
/// # Errors
/// A run that fails once started (exit 1).
pub fn pil_runs(args: &BenchArgs, target: &Path) -> Result<PilRuns, CliError> {
    pil::pil_runs(&image(args, target), &args.qemu, args.repeat, args.pil_s)
}

/// The worst control step of each controller, instructions, against
/// [`STEP_INSTRUCTIONS_TARGET`].
pub fn step_figures(runs: &PilRuns) -> Vec<Figure> {
    let name = |k: &str| format!("worst {k} control step, PIL (QEMU -icount)");
    let mut out = Vec::new();
    // An image of a law of one's own: its one figure, held to the same target.
    if let Ok(r) = runs
        && let Some(run) = r.iter().find(|r| r.law.is_some())
    {
        let law = run.law.as_deref().unwrap_or_default();
        let worst = r.iter().map(|r| r.step.worst).fold(0.0, f64::max);
        out.push(
            Figure::measured("control_step_law", "step", name(&format!("law `{law}`")), worst, "instructions", STEP_INSTRUCTIONS_TARGET, Goal::AtMost)
                .note(format!(
                    "median {:.0}, p99 {:.0}; frame (decode + step) median {:.0}, worst {:.0}; {} periods; the image's own law (PAINLEVE_LAW_SPEC) at its declared defaults",
                    run.step.median, run.step.p99, run.frame.median, run.frame.worst, run.periods
                ))
                .note(format!("fits 5 % of the period up to {:.0} Hz if an instruction took one cycle", highest_rate(worst))),
        );
        return out;
    }
    for (id, kind, label) in [("control_step_hybrid", ControllerKind::Hybrid, "hybrid"), ("control_step_pid", ControllerKind::Pid, "PID")] {
        let run = match runs {
            Ok(r) => r.iter().find(|r| r.controller == kind),
            Err(why) => {
                out.push(Figure::skipped(id, "step", name(label), "instructions", STEP_INSTRUCTIONS_TARGET, Goal::AtMost, why.clone()));
                continue;
            }
        };
        let Some(r) = run else { continue };
        out.push(
            Figure::measured(id, "step", name(label), r.step.worst, "instructions", STEP_INSTRUCTIONS_TARGET, Goal::AtMost)
                .note(format!(
                    "median {:.0}, p99 {:.0}; frame (decode + step) median {:.0}, worst {:.0}; {} periods",
                    r.step.median, r.step.p99, r.frame.median, r.frame.worst, r.periods
                ))
                .note(format!(
                    "fits 5 % of the period up to {:.0} Hz if an instruction took one cycle (a lower bound of cycles; 10 kHz needs <= 840)",
                    highest_rate(r.step.worst)
                )),
        );
    }
    out
}

/// PIL periods per wall second (median of the runs) against [`PIL_RATE_TARGET`].
pub fn rate_figure(runs: &PilRuns) -> Figure {
    let name = "PIL periods per wall second (image in QEMU)";
    match runs {
        Err(why) => Figure::skipped("pil_rate", "pil", name, "periods/s", PIL_RATE_TARGET, Goal::AtLeast, why.clone()),
        Ok(runs) => {
            let rates: Vec<f64> = runs.iter().map(|r| r.rate).collect();
            let boot = median(&runs.iter().map(|r| r.boot_s).collect::<Vec<_>>());
            Figure::measured("pil_rate", "pil", name, median(&rates), "periods/s", PIL_RATE_TARGET, Goal::AtLeast)
                .note(format!(
                    "{} runs (hybrid, then PID) of {} periods; QEMU start and boot {boot:.2} s, not counted; frames over semihosting FIFOs (`pil --qemu-link semihosting`)",
                    runs.len(),
                    runs[0].periods
                ))
                .with_runs(rates)
        }
    }
}

/// The aim for the highest control rate at which the worst step fits 5 % of the
/// period: 10 kHz, 840 cycles at 168 MHz (issue 16).
pub const RATE_AIM_HZ: f64 = 10_000.0;

/// The controllers and friction terms `scripts/cycles.py` measures (its
/// `--controller all`): the figure's id, the script's JSON key, the label.
const STEPS: [(&str, &str, &str); 6] = [
    ("max_rate_hybrid", "hybrid", "hybrid (friction commanded)"),
    ("max_rate_hybrid_estimated", "hybrid-estimated", "hybrid (friction estimated)"),
    ("max_rate_hybrid_measured", "hybrid-measured", "hybrid (friction measured)"),
    ("max_rate_hybrid_measured_normal", "hybrid-measured_normal", "hybrid (friction measured_normal)"),
    ("max_rate_hybrid_none", "hybrid-none", "hybrid (no friction term)"),
    ("max_rate_pid", "pid", "PID"),
];

/// The worst step's Cortex-M4 cycle estimate and the highest control rate at
/// which it fits 5 % of the period, per controller and friction term
/// ([`STEPS`]), from `scripts/cycles.py`
/// (QEMU's exec trace of the first second, TRM timings on the executed path;
/// docs/board.md "The control step's cost"). Needs the repository's script,
/// Python 3 and LLVM's objdump, nm and addr2line; skipped without them.
///
/// # Errors
/// None: a failing script is a skipped figure with its message.
pub fn cycle_figures(args: &BenchArgs, target: &Path) -> Vec<Figure> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/cycles.py");
    let name = |k: &str| format!("highest control rate, worst {k} step within 5 % (cycle estimate)");
    // An image of a law of one's own: `--controller law` on the default scenario
    // with the law's `[law]` table (its declared defaults), one figure.
    let img = image(args, target);
    let law = rig::law::LawDescription::from_elf(&img).ok().flatten().filter(|d| !d.is_paper());
    let steps: Vec<(&str, &str, String)> = match &law {
        Some(d) => vec![("max_rate_law", "law", format!("law `{}`", d.name))],
        None => STEPS.into_iter().map(|(id, key, label)| (id, key, label.to_string())).collect(),
    };
    let skip = |why: String| -> Vec<Figure> {
        steps.iter().map(|(id, _, k)| Figure::skipped(id, "cycles", name(k), "Hz", RATE_AIM_HZ, Goal::AtLeast, why.clone())).collect()
    };
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => return skip(format!("cannot find this executable: {e}")),
    };
    let scenario_file = match &law {
        Some(d) => {
            let text = format!("{}\n[law]\nname = \"{}\"\n", rig::scenario::DEFAULT_TOML, d.name);
            let file = std::env::temp_dir().join(format!("painleve-bench-law-{}.toml", std::process::id()));
            if let Err(e) = std::fs::write(&file, text) {
                return skip(format!("cannot write {}: {e}", file.display()));
            }
            Some(file)
        }
        None => None,
    };
    let mut cmd = std::process::Command::new("python3");
    cmd.arg(&script).args(["--duration", "1", "--json", "--image"]).arg(&img).arg("--sil-host").arg(exe);
    if let Some(file) = &scenario_file {
        cmd.args(["--controller", "law", "--scenario"]).arg(file);
    }
    let out = cmd.output();
    if let Some(file) = &scenario_file {
        let _ = std::fs::remove_file(file);
    }
    let out = match out {
        Ok(o) if o.status.success() => o,
        Ok(o) => return skip(format!("scripts/cycles.py failed: {}", String::from_utf8_lossy(&o.stderr).trim())),
        Err(e) => return skip(format!("cannot run python3 {}: {e}", script.display())),
    };
    let v: serde_json::Value = match serde_json::from_slice(&out.stdout) {
        Ok(v) => v,
        Err(e) => return skip(format!("scripts/cycles.py printed no JSON: {e}")),
    };
    let mut figures = Vec::new();
    for (id, key, label) in &steps {
        let (id, key, label) = (*id, *key, label.as_str());
        let r = &v[key];
        let (Some(rate), Some(hi), Some(lo), Some(instr)) = (
            r["max_rate_hz"].as_f64(),
            r["cycles_max"]["worst"].as_f64(),
            r["cycles_min"]["worst"].as_f64(),
            r["instructions"]["worst"].as_f64(),
        ) else {
            figures.push(Figure::skipped(
                id,
                "cycles",
                name(label),
                "Hz",
                RATE_AIM_HZ,
                Goal::AtLeast,
                format!("scripts/cycles.py gave no {key} figures"),
            ));
            continue;
        };
        figures.push(
            Figure::measured(id, "cycles", name(label), rate, "Hz", RATE_AIM_HZ, Goal::AtLeast)
                .note(format!(
                    "worst step: {instr:.0} instructions (exact), {lo:.0} to {hi:.0} cycles (Cortex-M4 TRM; the rate uses {hi:.0}); 10 kHz needs <= 840"
                ))
                .note(format!("{} steps of the first second", r["steps"])),
        );
    }
    figures
}

/// The PIL image's flash in profiles `mcu` and `release` against their targets.
pub fn flash_figures(target: &Path) -> Vec<Figure> {
    let base = target.join("thumbv7em-none-eabihf");
    let cases = [
        (
            "flash_pil_mcu",
            "mcu",
            "PIL image flash, profile mcu",
            FLASH_MCU_TARGET,
            "cargo build -p board-stm32f405 --profile mcu --target thumbv7em-none-eabihf --bin pil --bin arm",
        ),
        (
            "flash_pil_release",
            "release",
            "PIL image flash, plain --release",
            FLASH_RELEASE_TARGET,
            "cargo build -p board-stm32f405 --release --target thumbv7em-none-eabihf --bin pil --bin arm",
        ),
    ];
    let mut out = Vec::new();
    for (id, profile, name, goal, build) in cases {
        let path = base.join(profile).join("pil");
        let figure = match image_size(&path) {
            Err(e) => Figure::skipped(id, "flash", name, "bytes", goal, Goal::AtMost, format!("{e} (build it with `{build}`)")),
            Ok((flash, ram)) => {
                let mut f = Figure::measured(id, "flash", name, flash as f64, "bytes", goal, Goal::AtMost)
                    .note(format!("{}: {flash} bytes of flash, {ram} bytes of static RAM", path.display()));
                if let Ok((arm_flash, arm_ram)) = image_size(&base.join(profile).join("arm")) {
                    f = f.note(format!("the arm image of the same profile: {arm_flash} bytes of flash, {arm_ram} of static RAM"));
                }
                f
            }
        };
        out.push(figure);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_images_are_skipped_with_the_build_command() {
        let dir = tempfile::tempdir().unwrap();
        let f = flash_figures(dir.path());
        assert_eq!(f.len(), 2);
        for f in f {
            match &f.status {
                crate::bench::figure::Status::Skipped(why) => assert!(why.contains("cargo build -p board-stm32f405"), "{why}"),
                s => panic!("{s:?}"),
            }
        }
    }
}
