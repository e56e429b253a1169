//! The MCU figures: the worst control step of each controller and PIL periods per
//! wall second, from PIL runs of the image in QEMU (`-icount shift=0`: the step's
//! ticks count retired instructions, the same on every run); the image's flash
//! and static RAM, read from the ELF's section headers as `scripts/budgets.py`
//! does (docs/hardware.md "Budgets").

use std::{
    path::{Path, PathBuf},
    time::Instant,
};

use super::{Figure, Goal, STEP_INSTRUCTIONS_TARGET, median};
use crate::{cli::BenchArgs, error::CliError};
use firmware::ControllerKind;
use rig::{
    RunObserver,
    pil_link::{self, CORE_HZ, PilLink, PilOptions, PilTarget, QemuLink},
    scenario::Scenario,
    stream_loop,
    summary::Spread,
};

/// Keeps nothing: the bench wants the link's counts and the loop's speed.
struct Discard;
impl RunObserver for Discard {}

/// Target of PIL periods per wall second (real time at 1 kHz; issue 16).
pub const PIL_RATE_TARGET: f64 = 1_000.0;
/// Flash target of the PIL image built with profile `mcu`, bytes (issue 16).
pub const FLASH_MCU_TARGET: f64 = 32.0 * 1024.0;
/// Flash target of the PIL image built with plain `--release`: the budget, bytes
/// (docs/hardware.md: 64 KiB).
pub const FLASH_RELEASE_TARGET: f64 = 64.0 * 1024.0;

/// One PIL run of the default scenario with one controller.
#[derive(Debug, Clone)]
pub struct PilRun {
    /// The controller the image ran.
    pub controller: ControllerKind,
    /// Control steps, instructions (median, p99, worst).
    pub step: Spread,
    /// Frames (decode + step), instructions.
    pub frame: Spread,
    /// Periods run.
    pub periods: usize,
    /// Periods per wall second of the loop (QEMU's boot excluded).
    pub rate: f64,
    /// QEMU's start and the image's boot, s.
    pub boot_s: f64,
}

/// The PIL runs, or why there are none.
pub type PilRuns = Result<Vec<PilRun>, String>;

/// The PIL image the bench runs: `--image`, else `target/thumbv7em-none-eabihf/qemu/pil`.
fn image(args: &BenchArgs, target: &Path) -> PathBuf {
    args.image.clone().unwrap_or_else(|| target.join("thumbv7em-none-eabihf/qemu/pil"))
}

/// Runs the image in QEMU: `--repeat` (at most 3) runs of the hybrid controller,
/// then one of PID, each `--pil-s` long. No image or no QEMU: `Err` with the
/// reason and the fix (the figures are skipped).
///
/// # Errors
/// A run that fails once started (exit 1).
pub fn pil_runs(args: &BenchArgs, target: &Path) -> Result<PilRuns, CliError> {
    let image = image(args, target);
    if !image.is_file() {
        return Ok(Err(format!("no PIL image at {}: build it with `{}`", image.display(), pil_link::BUILD_HINT)));
    }
    let mut runs = Vec::new();
    let kinds = std::iter::repeat_n(ControllerKind::Hybrid, args.repeat.min(3)).chain([ControllerKind::Pid]);
    for kind in kinds {
        let mut s = Scenario::default_scenario();
        s.controller.kind = kind;
        s.timing.duration_s = args.pil_s;
        s.validate()?;
        let opts = PilOptions::for_target(PilTarget::Qemu { image: image.clone(), qemu: args.qemu.clone(), link: QemuLink::default() });
        let t = Instant::now();
        let mut link = match PilLink::start(&s, &opts, None) {
            Ok(l) => l,
            // QEMU missing or the image not booting is a set-up matter: the figure is skipped.
            Err(e) if runs.is_empty() => return Ok(Err(format!("cannot start the image in QEMU: {e}"))),
            Err(e) => return Err(CliError::Run(e)),
        };
        let boot_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (periods, e) = stream_loop(&s, &mut link, &mut Discard);
        let rate = periods as f64 / t.elapsed().as_secs_f64();
        if let Some(e) = e {
            return Err(CliError::Run(e));
        }
        let per_tick = link.counts.counts_per_tick();
        runs.push(PilRun {
            controller: kind,
            step: link.counts.step.spread(per_tick),
            frame: link.counts.frame.spread(per_tick),
            periods,
            rate,
            boot_s,
        });
    }
    Ok(Ok(runs))
}

/// The highest control rate (Hz) at which a step of `cycles` fits 5 % of the
/// period at 168 MHz (docs/hardware.md "Budgets").
pub fn highest_rate(cycles: f64) -> f64 {
    CORE_HZ / 20.0 / cycles
}

/// The worst control step of each controller, instructions, against
/// [`STEP_INSTRUCTIONS_TARGET`].
pub fn step_figures(runs: &PilRuns) -> Vec<Figure> {
    let name = |k: &str| format!("worst {k} control step, PIL (QEMU -icount)");
    let mut out = Vec::new();
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

/// The worst step's Cortex-M4 cycle estimate and the highest control rate at
/// which it fits 5 % of the period, per controller, from `scripts/cycles.py`
/// (QEMU's exec trace of the first second, TRM timings on the executed path;
/// docs/board.md "The control step's cost"). Needs the repository's script,
/// Python 3 and LLVM's objdump, nm and addr2line; skipped without them.
///
/// # Errors
/// None: a failing script is a skipped figure with its message.
pub fn cycle_figures(args: &BenchArgs, target: &Path) -> Vec<Figure> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/cycles.py");
    let name = |k: &str| format!("highest control rate, worst {k} step within 5 % (cycle estimate)");
    let skip = |why: String| -> Vec<Figure> {
        [("max_rate_hybrid", "hybrid"), ("max_rate_pid", "PID")]
            .into_iter()
            .map(|(id, k)| Figure::skipped(id, "cycles", name(k), "Hz", RATE_AIM_HZ, Goal::AtLeast, why.clone()))
            .collect()
    };
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => return skip(format!("cannot find this executable: {e}")),
    };
    let out = std::process::Command::new("python3")
        .arg(&script)
        .args(["--duration", "1", "--json", "--image"])
        .arg(image(args, target))
        .arg("--sil-host")
        .arg(exe)
        .output();
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
    for (id, key, label) in [("max_rate_hybrid", "hybrid", "hybrid"), ("max_rate_pid", "pid", "PID")] {
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

/// Flash and static RAM of an ELF image, bytes: the loaded sections
/// `.vector_table`, `.text`, `.rodata`, `.data` (its initial values are in
/// flash); RAM `.data`, `.bss`, `.uninit` (the stack and the defmt buffers are
/// counted by the image's own checks).
///
/// # Errors
/// The file cannot be read or is not an ELF file.
pub fn image_size(path: &Path) -> Result<(u64, u64), String> {
    use object::{Object, ObjectSection};
    let data = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let elf = object::File::parse(&*data).map_err(|e| format!("{}: not an ELF image: {e}", path.display()))?;
    let size = |names: &[&str]| -> u64 { elf.sections().filter(|s| s.name().is_ok_and(|n| names.contains(&n))).map(|s| s.size()).sum() };
    Ok((size(&[".vector_table", ".text", ".rodata", ".data"]), size(&[".data", ".bss", ".uninit"])))
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
    fn ten_kilohertz_is_840_cycles() {
        assert!((highest_rate(840.0) - 10_000.0).abs() < 1e-9);
        assert!((highest_rate(8_400.0) - 1_000.0).abs() < 1e-9);
    }

    #[test]
    fn a_file_that_is_not_elf_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pil");
        std::fs::write(&p, b"not an image").unwrap();
        let e = image_size(&p).unwrap_err();
        assert!(e.contains("not an ELF image"), "{e}");
        let e = image_size(&dir.path().join("missing")).unwrap_err();
        assert!(e.contains("cannot read"), "{e}");
    }

    #[test]
    fn sizes_are_read_from_the_section_headers() {
        // This test's own executable is an ELF file with .text, .rodata and .data.
        let (flash, ram) = image_size(&std::env::current_exe().unwrap()).unwrap();
        assert!(flash > 100_000 && ram > 0, "flash {flash}, ram {ram}");
    }

    #[test]
    fn missing_images_are_skipped_with_the_build_command() {
        let dir = tempfile::tempdir().unwrap();
        let f = flash_figures(dir.path());
        assert_eq!(f.len(), 2);
        for f in f {
            match &f.status {
                super::super::Status::Skipped(why) => assert!(why.contains("cargo build -p board-stm32f405"), "{why}"),
                s => panic!("{s:?}"),
            }
        }
    }
}
