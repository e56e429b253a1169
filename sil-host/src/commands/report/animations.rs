//! The report's animations (issue 55): the open-loop bounce from x0a (the
//! `simulate` step) and the hybrid law's run from x0d (the `hybrid-x0d` step),
//! each an `animation.gif` drawn from the step's own `trace.csv` (and
//! `events.csv`) into its folder, shown in the step's section after its figures.

use std::path::Path;

use super::{
    format::given,
    outcome::{Outcome, StepResult},
};
use crate::error::CliError;
use figures::animation::{self, Animation, Arm, Look, Strip};

/// The file each animated step gets, in its folder.
pub const FILE: &str = "animation.gif";

/// Frames per second of both animations.
pub const FPS: u32 = 25;

/// The stretch of the run, slow-down and strip plot of step `id`'s animation
/// (`None`: the step is not animated): the first 2 s of the open-loop bounce
/// slowed down 4 times (the bounces last 0.1 s to 0.2 s); the first 5 s of the
/// hybrid run (its 2 s move and the hold) in real time.
pub fn plan(id: &str) -> Option<(f64, f64, f64, Strip)> {
    match id {
        "simulate" => Some((0.0, 2.0, 4.0, Strip::Height)),
        "hybrid-x0d" => Some((0.0, 5.0, 1.0, Strip::Tangential)),
        _ => None,
    }
}

/// Draws the animation of every animated step of `results` that finished
/// (`root` the report's folder) and adds it to the step's files; a step whose
/// animation fails gets the error (the report then exits 1).
pub(super) fn animate(root: &Path, results: &mut [Vec<StepResult>]) {
    for r in results.iter_mut().flatten().filter(|r| r.error.is_none()) {
        if plan(r.id).is_none() {
            continue;
        }
        let (params, title) = match &r.outcome {
            Some(Outcome::Simulate(s)) => (
                s.params,
                format!("Open loop (u = 0) from {}, μ = {}: the tip bounces (the Painlevé paradox)", s.initial_condition.name, s.params.mu),
            ),
            Some(Outcome::Run(s)) => (
                s.scenario_used.plant.params(),
                format!(
                    "The {} law from x0{}, μ = {}: the tip slides to zₜ* = {} m",
                    law_named(&s.controller),
                    s.scenario_used.plant.x0.letter(),
                    s.scenario_used.plant.mu,
                    s.scenario_used.controller.target_z_t
                ),
            ),
            _ => continue,
        };
        let arm = Arm { l: params.l, h: params.h, v_belt: params.v_belt };
        let written = write(r.id, &root.join(r.id), arm, title);
        match written {
            Ok(None) => {}
            Ok(Some(_)) => {
                r.files.push(format!("{}/{FILE}", r.id));
                r.files.sort();
            }
            Err(e) => r.error = Some(format!("the animation: {e}")),
        }
    }
}

/// Writes step `id`'s animation ([`plan`]; `Ok(None)` for a step that has none)
/// to [`FILE`] in the step's folder `dir`, drawn from its `trace.csv` (and its
/// `events.csv`, if there) with `arm` and `title`.
///
/// # Errors
/// As [`animation::trace::read`] and [`animation::write_gif`].
pub fn write(id: &str, dir: &Path, arm: Arm, title: String) -> Result<Option<animation::Written>, CliError> {
    let Some((t0, t1, slow_down, strip)) = plan(id) else { return Ok(None) };
    let events = dir.join("events.csv");
    let trace = animation::trace::read(&dir.join("trace.csv"), events.is_file().then_some(events.as_path()))?;
    let a = Animation { t0, t1, fps: FPS, look: Look { title, strip, slow_down } };
    animation::write_gif(&dir.join(FILE), &trace, arm, &a).map(Some).map_err(CliError::from)
}

/// The caption of an animation `file` of the step whose result is `outcome`, as
/// `(what, parameters)`: what is drawn with which scales, the scenario and
/// controller, and the time scale (the stretch of the run, the slow-down, the
/// frames); `None` for a step that is not animated (`super::captions` words it).
pub(super) fn caption(outcome: Option<&Outcome>, file: &str) -> Option<(String, String)> {
    use figures::animation::frame::{FORCE_PX_PER_N, IMPULSE_PX_PER_NS, PATH_S};
    let id = file.split('/').next().unwrap_or(file);
    let (Some((t0, t1, slow_down, strip)), Some(outcome)) = (plan(id), outcome) else {
        return None;
    };
    let frames = ((t1 - t0) * slow_down * f64::from(FPS)).round();
    let time = if (slow_down - 1.0).abs() < 1e-9 {
        format!("t from {} to {} s in real time", given(t0), given(t1))
    } else {
        format!("t from {} to {} s slowed down {} times", given(t0), given(t1), given(slow_down))
    };
    let timing = format!("{time}: {frames} frames at {FPS} frames per second ({} s of animation), looping", given(frames / f64::from(FPS)));
    let strip_text = match strip {
        Strip::Height => "the tip's height above the belt (z_n + H, mm)",
        Strip::Tangential => "z_t and z_t* (m)",
    };
    let common = format!(
        "the two links from theta1 and theta2 by the plant's kinematics, the belt (its stripes move with it), \
         the tip (vermilion) and its path over the last {PATH_S} s (orange), the contact force on the tip as a green \
         arrow ({FORCE_PX_PER_N} px per N)"
    );
    let (what, parameters) = match outcome {
        Outcome::Simulate(s) => (
            format!(
                "The arm in motion (animated): {common} and each impact's impulse as a purple arrow ({IMPULSE_PX_PER_NS} px per N s), \
                 the time and contact mode; below, {strip_text} against time with a cursor"
            ),
            format!(
                "From {}, mu = {}, v_belt = {} m/s, open loop (u = 0), {} impacts with e_n = {}; {timing}",
                s.initial_condition.name,
                given(s.params.mu),
                given(s.params.v_belt),
                s.sim.impact_law.name(),
                given(s.sim.e_n)
            ),
        ),
        Outcome::Run(r) => {
            let sc = &r.scenario_used;
            (
                format!(
                    "The arm in motion (animated): {common}, the time and contact mode; below, {strip_text} against time with a cursor"
                ),
                format!(
                    "Scenario {}: the {} law (the firmware sampled at {} Hz) from x0{}, mu = {}, v_belt = {} m/s, a {} s move to z_t* = {} m; {timing}",
                    sc.name,
                    law_named(&r.controller),
                    given(sc.timing.rate_hz),
                    sc.plant.x0.letter(),
                    given(sc.plant.mu),
                    given(sc.plant.v_belt),
                    given(sc.controller.move_time_s),
                    given(sc.controller.target_z_t)
                ),
            )
        }
        _ => return None,
    };
    Some((what, parameters))
}

/// A run's `controller` as the text names it: `PID`, `hybrid`, or a law of
/// one's own by its name (the captions' too).
pub(super) fn law_named(name: &str) -> &str {
    match name {
        "pid" => "PID",
        other => other,
    }
}
