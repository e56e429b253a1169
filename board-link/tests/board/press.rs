//! A law that presses the tip into the belt cannot escape the overload
//! (issue 80, docs/board.md "Runaway limits": the press count of
//! `firmware::runaway`), and no healthy law of the envelope ever comes near it.
//!
//! - [`Press`], a law of one's own that holds `z_t` with a spring and presses
//!   along the belt's normal with `force_n` in `on` periods of every
//!   `on + off` (the rest with none: the contact chatters between a press and
//!   none), over random admissible scenarios on the board twin: stopped
//!   `Overload`, within ten periods of a held press, and within ten pressed
//!   periods plus a quarter of those between when the press chatters (the
//!   count's algebra: each pressed period adds 4, each other takes 1 back,
//!   40 trips).
//! - The envelope (`random_envelope`: 250 Hz to 10 kHz, `f_n*` 2 to 20 N,
//!   every friction term, random gains) under the paper's two laws: the press
//!   count, replayed on the normal force each run's frames carried, trips
//!   only where the law itself fails (the same arm, unprotected, lifts off or
//!   saturates a motor: issue 66's criterion).

use board_link::{
    random_scenarios::{random_admissible, random_envelope},
    twin_link::TwinLink,
};
use firmware::{
    Config, ControlLaw, Declares, LawContext, LawInput, LawOutput, LawSpec, ParamSpec, SafeReason,
    law::LawError,
    runaway::{PRESS_LEAK, PRESS_N, PRESS_PERIODS, RunawayMonitor, RunawayRule},
};
use rig::{
    law::LawTable,
    period_loop::{RunObserver, run_loop},
    record::RunError,
    scenario::Scenario,
    setup::RunSetup,
};
use shared::wire::{LOAD_FULL_SCALE_N, SensorFrame};

/// Holds `z_t` on its reference with a spring and presses the tip into the
/// belt with `force_n` (N) in `on` of every `on + off` periods, with none in
/// the others. Declares no tracking and that it may lift off: only the
/// overload can stop it.
#[derive(Debug, Clone, Copy, Default)]
struct Press {
    k: u32,
}

impl ControlLaw for Press {
    const SPEC: LawSpec = LawSpec {
        name: "press",
        source: "issue 80's pressing law (a test)",
        params: &[
            ParamSpec { name: "force_n", unit: "N", min: 0.0, max: 100.0, default: 30.0 },
            ParamSpec { name: "on", unit: "periods", min: 1.0, max: 10.0, default: 1.0 },
            ParamSpec { name: "off", unit: "periods", min: 0.0, max: 10.0, default: 0.0 },
        ],
    };

    fn fresh(_cfg: &Config) -> Self {
        Self::default()
    }

    fn declares(_cfg: &Config) -> Declares {
        Declares { tracking: None, on_belt: false, uses_reference_acceleration: false }
    }

    fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError> {
        let p = ctx.params();
        let (on, off) = (p[1] as u32, p[2] as u32);
        let pressing = self.k % (on + off) < on;
        self.k = self.k.wrapping_add(1);
        let (z, z_dot, j) = (input.kin.z, input.kin.z_dot, input.kin.jac);
        let f_t = 300.0 * (input.reference.pos - z[0]) - 20.0 * z_dot[0];
        let f_n = if pressing { -p[0] } else { 0.0 };
        let wc = ctx.arm.w_sin(input.trig.s1, input.trig.s2, &input.q, &input.qd) + ctx.arm.c_sin(input.trig.s12(), &input.qd);
        let u0 = wc[0] + j[(0, 0)] * f_t + j[(1, 0)] * f_n;
        let u1 = wc[1] + j[(0, 1)] * f_t + j[(1, 1)] * f_n;
        Ok(LawOutput { u: [u0 + u1, u1], disturbance: 0.0 })
    }
}

/// The normal force each frame carried, N (the load cell's codes of 25/2048 N).
#[derive(Default)]
struct NormalForce(Vec<f32>);

impl RunObserver for NormalForce {
    fn on_frame(&mut self, frame: &SensorFrame) {
        self.0.push(f32::from(frame.f_n_code) * LOAD_FULL_SCALE_N / 2048.0);
    }
}

/// `s` under [`Press`] on the twin: the normal force each frame carried (N),
/// the true normal force at each period (N), and how the run ended.
fn press_run(s: &Scenario) -> (Vec<f32>, Vec<f64>, Option<RunError>) {
    let setup = RunSetup::new(s.clone()).unwrap();
    let mut link = TwinLink::<Press>::for_law(&setup).unwrap();
    let mut seen = NormalForce::default();
    let (records, err) = run_loop(&setup, &mut link, &mut seen);
    (seen.0, records.iter().map(|p| p.f_n).collect(), err)
}

#[test]
fn a_law_pressing_at_24_n_or_more_is_stopped_within_ten_pressed_periods_held_or_chattering() {
    let n: u64 = std::env::var("PAINLEVE_PRESS_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(60);
    let patterns = [(1u32, 0u32), (3, 1), (2, 1), (1, 1), (4, 3)];
    let (mut spans, mut reasons, mut pressing, mut reached) = (Vec::new(), std::collections::BTreeMap::new(), 0usize, 0usize);
    for i in 0..n {
        let (on, off) = patterns[i as usize % patterns.len()];
        let force = [24.5, 30.0, 50.0, 80.0][(i / 5) as usize % 4];
        let mut s = random_admissible(5_000 + i, "hybrid", 0.5);
        s.law = Some(LawTable {
            name: "press".into(),
            params: [("force_n".into(), force), ("on".into(), f64::from(on)), ("off".into(), f64::from(off))].into(),
        });
        let what = format!("scenario {i}: {force} N in {on} of {} periods", on + off);
        let (f_n, true_f_n, err) = press_run(&s);
        // The press count replayed on the normal force the frames carried.
        let rule = RunawayRule::at_period(s.timing.period().as_secs_f32());
        let mut m = RunawayMonitor::default();
        let tripped = f_n.iter().position(|f| m.update(&rule, [0.0; 2], false, *f).is_some());
        let stop = match err {
            Some(RunError::SafeState { k, reason, .. }) => {
                *reasons.entry(format!("{reason:?}")).or_insert(0usize) += 1;
                // Whichever check comes first (the law's commands reverse as
                // its contact chatters: `Unstable`; its joints accelerate
                // against its torques: `Miswired`), never later than the count.
                if reason == SafeReason::Overload {
                    assert_eq!(tripped, Some(k), "{what}: Overload at period {k}");
                } else {
                    assert!(
                        tripped.is_none_or(|t| t >= k),
                        "{what}: {reason:?} at period {k}, after the press count's trip at {tripped:?}"
                    );
                }
                Some(k)
            }
            None => {
                assert_eq!(tripped, None, "{what}: ran on past the press count's trip");
                None
            }
            Some(other) => panic!("{what}: {other}"),
        };
        // Where the law pressed at 24 N (true force) or more, in ten periods'
        // worth of the count's own measure (each such period 4, each other
        // -1, 40), it is stopped by then: within ten periods of a held press.
        reached += usize::from(true_f_n.iter().any(|f| *f >= 24.0));
        let mut count = 0u32;
        let Some(due) = true_f_n.iter().position(|f| {
            count = if *f >= 24.0 { count + u32::from(PRESS_LEAK) } else { count.saturating_sub(1) };
            count >= u32::from(PRESS_PERIODS * PRESS_LEAK)
        }) else {
            continue;
        };
        pressing += 1;
        let k = stop.unwrap_or_else(|| panic!("{what}: pressed at 24 N or more for ten periods' worth by period {due}, never stopped"));
        assert!(k <= due, "{what}: pressed at 24 N or more for ten periods' worth by period {due}, stopped at {k}");
        let read = f_n.iter().position(|f| f.abs() >= PRESS_N).unwrap_or(k);
        let window = &f_n[read..=k];
        let pressed = window.iter().filter(|f| f.abs() >= PRESS_N).count();
        let other = window.len() - pressed;
        if other == 0 {
            assert!(window.len() <= usize::from(PRESS_PERIODS), "{what}: a press read every period stopped after {} periods", window.len());
        }
        spans.push(window.len());
    }
    spans.sort_unstable();
    println!(
        "{n} runs of a pressing law ({reasons:?}); {reached} reached 24 N, {pressing} pressed at 24 N or more for ten periods' worth and were stopped by then, from the first period read at {PRESS_N} N or more: median {} periods, latest {}",
        spans[spans.len() / 2],
        spans[spans.len() - 1]
    );
    assert!(reached >= n as usize / 3, "the law reaches 24 N in a third of the runs or more: {reached}");
    assert!(reasons.get("Overload").is_some_and(|&o| o >= 10), "the press count stops held presses: {reasons:?}");
}

#[test]
fn the_press_count_trips_on_no_healthy_run_of_the_envelope() {
    let n: u64 = std::env::var("PAINLEVE_ENVELOPE_SCENARIOS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let (mut peak, mut unhealthy) = ((0.0f32, String::new()), Vec::new());
    for kind in ["hybrid", "pid"] {
        for i in 0..n {
            let (s, what) = random_envelope(i, kind, 1.0);
            let mut seen = NormalForce::default();
            let (_, err) = rig::in_process::run(&s, &mut seen);
            let rule = RunawayRule::at_period(s.timing.period().as_secs_f32());
            let mut m = RunawayMonitor::default();
            if let Some(k) = seen.0.iter().position(|f| m.update(&rule, [0.0; 2], false, *f).is_some()) {
                // Only where the law itself fails (issue 66's criterion: the
                // same arm, unprotected, lifts off or saturates a motor).
                let (lifts, saturates) = board_link::fmea::unprotected::<firmware::PaperLaws>(&s);
                assert!(lifts || saturates, "{what} (scenario {i}): the press count tripped at period {k} on a healthy arm ({err:?})");
                unhealthy.push(format!("{what}: at period {k} (unprotected: lifts off {lifts}, saturates {saturates})"));
                continue;
            }
            let top = seen.0.iter().fold(0.0f32, |a, f| a.max(f.abs()));
            if top > peak.0 {
                peak = (top, what);
            }
        }
    }
    for u in &unhealthy {
        println!("the law's own failure: {u}");
    }
    println!(
        "{} runs, {} where the count trips (each the law's own failure); elsewhere the largest normal force read {:.2} N ({})",
        2 * n,
        unhealthy.len(),
        peak.0,
        peak.1
    );
}
