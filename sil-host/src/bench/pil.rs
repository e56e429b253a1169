//! PIL runs of the image in QEMU for the bench (`-icount shift=0`: the step's
//! ticks count retired instructions, the same on every run): the worst control
//! step of each controller and PIL periods per wall second; and the highest
//! control rate a step's cost allows.

use std::{path::Path, time::Instant};

use crate::error::CliError;
use firmware::ControllerKind;
use rig::{
    pil_link::{self, CORE_HZ, PilLink, PilOptions, PilTarget, QemuLink},
    scenario::Scenario,
    stream_loop,
    summary::Spread,
};

/// One PIL run of the default scenario with one controller.
#[derive(Debug, Clone)]
pub struct PilRun {
    /// The controller the image ran (with a law of one's own: `law`).
    pub controller: ControllerKind,
    /// The law of one's own the image runs (its `PAINLEVE_LAW_SPEC`, issue 70);
    /// `None` for the paper's laws.
    pub law: Option<String>,
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

/// Runs the PIL `image` (ELF) in QEMU (the executable `qemu`): `repeat` (at most 3)
/// runs of the hybrid controller, then one of PID, each `pil_s` (s) of the default
/// scenario; for an image of a law of one's own (its `PAINLEVE_LAW_SPEC`), `repeat`
/// runs of that law at its declared defaults instead. No image or no QEMU: `Err` with the reason and the fix (the figures
/// are skipped).
///
/// # Errors
/// [`CliError::Analysis`] for a run length the scenario refuses (exit 2: a scenario error);
/// [`CliError::Analysis`] for a run that fails once started (exit 1).
pub fn pil_runs(image: &Path, qemu: &Path, repeat: usize, pil_s: f64) -> Result<PilRuns, CliError> {
    if !image.is_file() {
        return Ok(Err(format!("no PIL image at {}: build it with `{}`", image.display(), pil_link::BUILD_HINT)));
    }
    let mut runs = Vec::new();
    // A law of one's own (the image's declaration): its runs, the default
    // scenario under its declared defaults, in place of the hybrid and PID runs.
    let law = match rig::law::LawDescription::from_elf(image) {
        Ok(d) => d.filter(|d| !d.is_paper()).map(|d| d.name),
        Err(e) => return Ok(Err(e.to_string())),
    };
    let kinds: Vec<ControllerKind> = match law {
        Some(_) => vec![ControllerKind::Hybrid; repeat.clamp(1, 3)],
        None => std::iter::repeat_n(ControllerKind::Hybrid, repeat.min(3)).chain([ControllerKind::Pid]).collect(),
    };
    for kind in kinds {
        let mut s = Scenario::default_scenario();
        s.controller.kind = kind;
        s.timing.duration_s = pil_s;
        s.law = law.as_ref().map(|name| rig::law::LawTable { name: name.clone(), params: Default::default() });
        s.validate()?;
        let setup = rig::RunSetup::new(s).map_err(CliError::from)?;
        let opts =
            PilOptions::for_target(PilTarget::Qemu { image: image.to_path_buf(), qemu: qemu.to_path_buf(), link: QemuLink::default() });
        let t = Instant::now();
        let mut link = match PilLink::start(&setup, &opts, None) {
            Ok(l) => l,
            // QEMU missing or the image not booting is a set-up matter: the figure is skipped.
            Err(e) if runs.is_empty() => return Ok(Err(format!("cannot start the image in QEMU: {e}"))),
            Err(e) => return Err(CliError::from(e)),
        };
        let boot_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (periods, e) = stream_loop(&setup, &mut link, &mut ());
        let rate = periods as f64 / t.elapsed().as_secs_f64();
        if let Some(e) = e {
            return Err(CliError::from(e));
        }
        let per_tick = link.counts.counts_per_tick();
        runs.push(PilRun {
            controller: kind,
            law: law.clone(),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_kilohertz_is_840_cycles() {
        assert!((highest_rate(840.0) - 10_000.0).abs() < 1e-9);
        assert!((highest_rate(8_400.0) - 1_000.0).abs() < 1e-9);
    }
}
