//! The singular point `p = b = 0` and the Moreau-Jean bridge (issue 40): a slide
//! driven through the singular point by a torque law, resolved event-driven (the
//! located passage, `p_zero`) and by the bridge under both singular rules, and the
//! bridge's refinement.

use nalgebra::{Matrix2, Vector2};
use shared::{Arm, ElbowBranch, Params, SlipDirection, kinematics::inverse_kinematics};

use crate::{
    Controller, EventKind, NoObserver, Plant, SimConfig,
    moreau_jean::SingularRule,
    plant::bridge::BRIDGE_TOLERANCE,
    segment::{Boundary, OdeState},
};

/// A torque law with the plant's model (as the paper's hybrid law has) that holds
/// a slide's normal reaction at `f_star` (N), by `b = -f_star p(+)`, and its tip
/// speed at `v_des` (m/s): the slide reaches `p = 0` with `b = 0` and a finite
/// force, and passes into the indeterminate region `p < 0, b > 0`.
struct ThroughTheCorner {
    arm: Arm<f64>,
    f_star: f64,
    v_des: f64,
    /// The `p / Q_22` at which `b` reaches 0 (`b = -f_star (p - lead Q_22)`): 0 for
    /// the two together, positive for `b = 0` first, negative for `p = 0` first.
    lead: f64,
}

impl Controller for ThroughTheCorner {
    fn torque(&self, _t: f64, x: &[f64; 4], _xi: &[f64; 2], _xi_dot: &mut [f64; 2]) -> [f64; 2] {
        let mu = self.arm.params.mu;
        let (q, qd) = (Vector2::new(x[0], x[2]), Vector2::new(x[1], x[3]));
        let td = |u: [f64; 2]| self.arm.tip_dynamics(&q, &qd, &Arm::generalised_torque(&Vector2::new(u[0], u[1])));
        let (t0, t1, t2) = (td([0.0, 0.0]), td([1.0, 0.0]), td([0.0, 1.0]));
        let p = t0.p(mu, SlipDirection::Positive);
        let g = Matrix2::new(t1.b() - t0.b(), t2.b() - t0.b(), t1.a_free[0] - t0.a_free[0], t2.a_free[0] - t0.a_free[0]);
        let tangential = (t0.qmat[(0, 1)] - mu * t0.qmat[(0, 0)]) * self.f_star;
        let b_target = -self.f_star * (p - self.lead * t0.qmat[(1, 1)]);
        let rhs = Vector2::new(b_target - t0.b(), -20.0 * (t0.z_dot[0] - self.v_des) - tangential - t0.a_free[0]);
        let u = g.try_inverse().map_or(Vector2::zeros(), |gi| gi * rhs);
        [u[0], u[1]]
    }
}

/// The paper's arm at `mu = 0.6` sliding elbow down at `z_t = 0.160 m`
/// (Table II: `p(+) > 0` up to 0.168 m) towards the `p = 0` point at 5 cm/s,
/// pressed with 3 N, under `rule`.
fn corner_case(rule: SingularRule, bridge_step: f64) -> (Plant, ThroughTheCorner) {
    let params = Params::<f64>::paper();
    let ctrl = ThroughTheCorner { arm: Arm::new(params), f_star: 3.0, v_des: 0.05, lead: 0.0 };
    let q = inverse_kinematics(params.l, &Vector2::new(0.160, -params.h), ElbowBranch::Down).unwrap();
    let jac = shared::kinematics::jacobian(params.l, &q);
    let qd = jac.try_inverse().unwrap() * Vector2::new(ctrl.v_des, 0.0);
    let x0 = [q[0], qd[0], q[1], qd[1]];
    let u0 = ctrl.torque(0.0, &x0, &[0.0; 2], &mut [0.0; 2]);
    let cfg = SimConfig { singular: rule, bridge_step, ..SimConfig::default() };
    let plant = Plant::new(params, cfg, x0, 0.0, u0).unwrap();
    assert_eq!(plant.mode(), shared::ContactMode::Sliding);
    (plant, ctrl)
}

/// `p(+) / Q_22` and `b` (m/s^2) of the plant's current state under `ctrl`.
fn p_and_b(plant: &Plant, ctrl: &ThroughTheCorner) -> (f64, f64) {
    let x = plant.state();
    let u = ctrl.torque(0.0, &x, &[0.0; 2], &mut [0.0; 2]);
    let td =
        plant.arm().tip_dynamics(&Vector2::new(x[0], x[2]), &Vector2::new(x[1], x[3]), &Arm::generalised_torque(&Vector2::new(u[0], u[1])));
    (td.p(0.6, SlipDirection::Positive) / td.qmat[(1, 1)], td.b())
}

/// Runs the case to 0.2 ms before the event-driven `p_zero`, then crosses the
/// singular point by a bridge; returns the plant 5 ms later and the bridge's events.
/// The time (s) the event-driven run of `plant` under `ctrl` reaches `p = 0` (its
/// `p_zero` event), advancing a copy in 1 ms intervals.
fn time_of_p_zero(plant: &Plant, ctrl: &ThroughTheCorner) -> f64 {
    let mut reference = plant.clone();
    for k in 0..1000 {
        let r = reference.advance(ctrl, (k + 1) as f64 * 1e-3 - reference.time(), &mut NoObserver).unwrap();
        // The located passage (`leave`) or the bridge that slides through it (`slide`).
        if let Some(e) = r.events.iter().find(|e| matches!(e.kind, EventKind::PZero | EventKind::SingularPoint)) {
            return e.t;
        }
    }
    panic!("the slide never reaches p = 0");
}

fn bridged(rule: SingularRule, bridge_step: f64) -> (Plant, Vec<crate::PlantEvent>) {
    let (mut plant, ctrl) = corner_case(rule, bridge_step);
    let t_zero = time_of_p_zero(&plant, &ctrl);
    plant.advance(&ctrl, t_zero - 2e-4, &mut NoObserver).unwrap();
    let (p, b) = p_and_b(&plant, &ctrl);
    assert!(p > 0.0 && p < 1e-3 && b < 0.0 && -b / 9.81 < 1e-2, "near the singular point: p/Q22 {p}, b {b}");
    let mut events = Vec::new();
    plant.bridge(&ctrl, Boundary::Singular, plant.time() + 5e-3, &mut NoObserver, &mut events).unwrap();
    while plant.time() < t_zero - 2e-4 + 5e-3 - 1e-12 {
        events.extend(plant.advance(&ctrl, t_zero - 2e-4 + 5e-3 - plant.time(), &mut NoObserver).unwrap().events);
    }
    (plant, events)
}

/// Event-driven, the located passage through the singular point is `p_zero`
/// followed by an impact without collision, as before issue 40 (the controlled
/// corner of the hybrid law's `Z_t,sliding` trials): no singular point, no bridge.
#[test]
fn a_located_passage_through_the_singular_point_stays_p_zero() {
    let (mut plant, ctrl) = corner_case(SingularRule::Leave, crate::config::BRIDGE_STEP);
    for k in 0..1000 {
        plant.advance(&ctrl, (k + 1) as f64 * 1e-3 - plant.time(), &mut NoObserver).unwrap();
        if plant.counters().p_zero > 0 {
            break;
        }
    }
    let c = plant.counters();
    assert_eq!((c.p_zero, c.impacts_without_collision, c.singular_points, c.bridges), (1, 1, 0, 0));
}

/// The first events of `plant` under `ctrl`, advanced in 1 ms intervals (`None` if
/// an interval fails or none comes within 1 s).
fn first_events(plant: &mut Plant, ctrl: &ThroughTheCorner) -> Option<Vec<crate::PlantEvent>> {
    for k in 0..1000 {
        let events = plant.advance(ctrl, (k + 1) as f64 * 1e-3 - plant.time(), &mut NoObserver).ok()?.events;
        if !events.is_empty() {
            return Some(events);
        }
    }
    None
}

/// How a crossing of the controlled corner with its roots `lead` of `Q_22` apart
/// went, checked against the slide's limit (issue 81). The law holds `f_n = f_star (1 -
/// lead Q_22 / p)`: the order of its approach is 0 and its limit `f_star`, so the slide
/// is held at its force down to `p / Q_22 = |lead|`, where the force reaches 0 (`lead >
/// 0`: a lift-off with the slip kept) or grows without bound (`lead < 0`: the jam). Down
/// to [`crate::segment::HELD_P`] (1e-9) the two are the singular point: arrested by
/// the impact without collision at `p = 0`. The arrest's and the jam's impulses are both
/// the edge impulse at `p = 0`: returned for comparison.
fn check_crossing(events: &[crate::PlantEvent], counters: &crate::Counters, lead: f64, what: &str) -> Option<[f64; 2]> {
    let kinds: Vec<EventKind> = events.iter().take(2).map(|e| e.kind).collect();
    let counts = (counters.corners_arrested, counters.corners_lifted_off, counters.corners_jammed);
    if lead.abs() <= 1e-10 {
        assert_eq!(kinds, [EventKind::PZero, EventKind::ImpactWithoutCollision], "{what}");
        assert_eq!(counts, (1, 0, 0), "{what}");
        let iwc = &events[1];
        assert!(iwc.v_r_after.abs() < 1e-12 && iwc.v_r_before.abs() > 0.01, "{what}: the slip stopped: {iwc:?}");
        Some(iwc.impulse)
    } else if lead > 0.0 {
        assert_eq!(kinds[0], EventKind::LiftOff, "{what}");
        assert_eq!(counts, (0, u64::from(lead < 1e-6), 0), "{what}");
        let e = &events[0];
        assert!(e.v_r_after == e.v_r_before && e.v_r_after.abs() > 0.01, "{what}: the slip kept: {e:?}");
        None
    } else {
        assert_eq!(kinds[0], EventKind::Jam, "{what}");
        assert_eq!(counts, (0, 0, 1), "{what}");
        let jam = &events[0];
        assert!(jam.v_r_after.abs() < 1e-9 && jam.v_r_before.abs() > 0.01, "{what}: the slip stopped: {jam:?}");
        Some(jam.impulse)
    }
}

/// Issue 81: the crossing of `p = 0` and `b = 0` is decided by the slide's own limit,
/// not by which root the locator meets first, nor by a band on `p`. The controlled
/// corner with `b` reaching 0 before `p` (`lead` above 0), after it, and with both
/// together ([`check_crossing`]): held to 1e-10 of `Q_22`, the impact without collision
/// that stops the slip; the force reaching 0 at 1e-8 of `Q_22` or before, a lift-off with
/// the slip kept (all three references of issue 81 keep it); growing without bound from
/// 1e-8, the jam, its tangential impulse the same edge impulse, to `1e-6 + 1e4 |lead|` of
/// it (a crossing `lead Q_22` earlier is a slightly different state). A lift-off well before `p = 0` (`lead` 1e-3) is an ordinary one.
#[test]
fn the_crossing_follows_the_slides_limit_whichever_root_is_located_first() {
    let run = |lead: f64| {
        let (mut plant, mut ctrl) = corner_case(SingularRule::Leave, crate::config::BRIDGE_STEP);
        ctrl.lead = lead;
        let events = first_events(&mut plant, &ctrl).unwrap_or_else(|| panic!("lead {lead}: no event"));
        check_crossing(&events, plant.counters(), lead, &format!("lead {lead}"))
    };
    let reference = run(0.0).unwrap();
    assert!(reference[1] > 0.0);
    for lead in [1e-10, -1e-10, 1e-8, 1e-7, 1e-3, -1e-8, -1e-7] {
        if let Some(impulse) = run(lead) {
            for i in 0..2 {
                let tol = 1e-6 + 1e4 * lead.abs();
                assert!((impulse[i] - reference[i]).abs() < tol * reference[1], "lead {lead}: {impulse:?} against {reference:?}");
            }
        }
    }
}

/// The controlled corner on any arm: `params` sliding elbow down towards the first
/// `p(+) = 0` point along the belt (`z_t` increasing) at 5 cm/s, pressed with 3 N,
/// from 6 mm before it; `None` when the belt within reach has no such point.
fn corner_case_of(params: Params<f64>, lead: f64) -> Option<(Plant, ThroughTheCorner)> {
    let arm = Arm::new(params);
    let ctrl = ThroughTheCorner { arm, f_star: 3.0, v_des: 0.05, lead };
    let p_over_q22 = |z_t: f64| {
        let q = inverse_kinematics(params.l, &Vector2::new(z_t, -params.h), ElbowBranch::Down).ok()?;
        let qm = arm.q_matrix(&q);
        Some((qm[(1, 1)] - params.mu * qm[(1, 0)]) / qm[(1, 1)])
    };
    // The reach along the belt, sampled every 0.5 mm: a sign change from + to -.
    let reach = (4.0 * params.l * params.l - params.h * params.h).sqrt();
    let n = (2.0 * reach / 5e-4) as usize;
    let z = |i: usize| -reach + 1e-6 + i as f64 * 5e-4;
    let i = (1..n).find(|&i| matches!((p_over_q22(z(i - 1)), p_over_q22(z(i))), (Some(a), Some(b)) if a > 0.0 && b <= 0.0))?;
    let z_start = z(i) - 6e-3;
    if !(z_start > -reach + 1e-3 && p_over_q22(z_start)? > 1e-3) {
        return None;
    }
    let q = inverse_kinematics(params.l, &Vector2::new(z_start, -params.h), ElbowBranch::Down).ok()?;
    let jac = shared::kinematics::jacobian(params.l, &q);
    let qd = jac.try_inverse()? * Vector2::new(ctrl.v_des, 0.0);
    let x0 = [q[0], qd[0], q[1], qd[1]];
    let u0 = ctrl.torque(0.0, &x0, &[0.0; 2], &mut [0.0; 2]);
    let cfg = SimConfig { singular: SingularRule::Leave, ..SimConfig::default() };
    let plant = Plant::new(params, cfg, x0, 0.0, u0).ok()?;
    (plant.mode() == shared::ContactMode::Sliding).then_some((plant, ctrl))
}

/// Issue 81: the crossing's rule over random arms. On each arm with a `p = 0` point on
/// its belt (masses, lengths, springs, damping, `mu` and `v_belt` drawn over the
/// envelope), the controlled corner held to its point, with `b` reaching 0 a little
/// before `p` and with `p` first ([`check_crossing`]): arrested where held to 1e-10 of
/// `Q_22`, the same impulse to `1e-6 + 1e4 |lead|` of it (a crossing `lead Q_22` earlier
/// is a slightly different state: 2e-5 at 1e-8 on the steepest arm drawn; the impulse is
/// continuous in the lead); a lift-off with the slip kept, or the jam with that impulse,
/// from 1e-8.
#[test]
fn the_crossing_follows_the_slides_limit_over_random_arms() {
    let mut seed = 0x5851_f42d_4c95_7f2du64;
    let mut uniform = |lo: f64, hi: f64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        lo + (hi - lo) * (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut tested = 0;
    for _ in 0..60 {
        let l = uniform(0.1, 0.4);
        let params = Params {
            m: uniform(0.05, 0.4),
            l,
            sigma: uniform(0.001, 0.01),
            k: uniform(0.5, 2.0),
            h: l * uniform(1.3, 1.9),
            alpha0: uniform(0.0, 0.4),
            mu: uniform(0.4, 1.0),
            v_belt: -uniform(0.1, 1.0),
            ..Params::paper()
        };
        let run = |lead: f64| -> Option<(Vec<crate::PlantEvent>, crate::Counters)> {
            let (mut plant, ctrl) = corner_case_of(params, lead)?;
            let events = first_events(&mut plant, &ctrl)?;
            Some((events, *plant.counters()))
        };
        let Some((events, counters)) = run(0.0) else { continue };
        if events.first().map(|e| e.kind) != Some(EventKind::PZero) {
            // The slide met another event first (the law cannot hold it): not a corner.
            continue;
        }
        tested += 1;
        let reference = check_crossing(&events, &counters, 0.0, &format!("{params:?}")).unwrap();
        for lead in [1e-10, -1e-10, 1e-8, -1e-8] {
            let what = format!("{params:?}, lead {lead}");
            let (events, counters) = run(lead).unwrap_or_else(|| panic!("{what}: no event"));
            if let Some(impulse) = check_crossing(&events, &counters, lead, &what) {
                for i in 0..2 {
                    assert!(
                        (impulse[i] - reference[i]).abs() < (1e-6 + 1e4 * lead.abs()) * reference[1],
                        "{what}: {impulse:?} against {reference:?}"
                    );
                }
            }
        }
    }
    println!("{tested} of 60 random arms have a corner to cross");
    assert!(tested >= 20, "{tested} arms with a corner");
}

/// Issue 67's reproducer: issue 53's arm from its start at `mu` 0.428 to 0.432 and
/// `v_belt` -0.5 +- 0.001 (the two roots 1e-10 to 4e-8 of `Q_22` apart, `b = 0`
/// first, where the locator took a lift-off with the slip kept at `mu` 0.431 and
/// 0.432 and the IWC at 0.430): every run's first events are the passage through
/// the singular point, `p_zero` then the IWC that stops the slip (the references'
/// outcome), then the departure from rest.
#[test]
fn issue53s_arm_meets_the_singular_point_the_same_way_on_both_sides_of_the_crossing() {
    for mu in [0.428, 0.429, 0.430, 0.431, 0.432] {
        for dv in [-1e-3, 0.0, 1e-3] {
            let mut params = Params::<f64>::paper();
            (params.m, params.l, params.sigma, params.k, params.h, params.alpha0) = (0.15, 0.23, 0.008, 1.0, 0.40, 0.20);
            (params.mu, params.v_belt) = (mu, -0.5 + dv);
            let cfg = SimConfig {
                impact_law: crate::impact::ImpactLaw::Newton,
                e_n: 0.2,
                iwc: crate::impact::IwcRule::Plastic,
                ..SimConfig::default()
            };
            let x0 = crate::initial::deg_to_state([34.53531701873741, 0.0, 23.744016380660902, 0.0]);
            let mut plant = Plant::new(params, cfg, x0, 0.0, [0.0, 0.0]).unwrap();
            let mut events = Vec::new();
            for k in 0..20 {
                events
                    .extend(plant.advance(&crate::Hold([0.0, 0.0]), (k + 1) as f64 * 1e-3 - plant.time(), &mut NoObserver).unwrap().events);
            }
            let kinds: Vec<EventKind> = events.iter().take(3).map(|e| e.kind).collect();
            assert_eq!(
                kinds,
                [EventKind::PZero, EventKind::ImpactWithoutCollision, EventKind::LiftOff],
                "mu {mu}, v_belt {}",
                params.v_belt
            );
            assert!(events[1].v_r_before > 0.3 && events[1].v_r_after.abs() < 1e-12, "mu {mu}: {:?}", events[1]);
        }
    }
}

/// Issue 81: issue 53's slide is attracted into the singular point. Its approach's
/// order `k = beta / |A|` exceeds 1, and the limit `f_inf = -alpha / (beta - |A|)` it
/// predicts at the crossing is the force the integrated slide tends to: `f_n = -b/p`
/// 1 ms, 0.1 ms and 10 us before the crossing departs from it less and less (like
/// `tau^(k - 1)`), to within 1 % at 10 us.
#[test]
fn issue53s_slide_tends_to_the_limit_its_approach_predicts() {
    let mut params = Params::<f64>::paper();
    (params.m, params.l, params.sigma, params.k, params.h, params.alpha0) = (0.15, 0.23, 0.008, 1.0, 0.40, 0.20);
    (params.mu, params.v_belt) = (0.43, -0.5);
    let cfg =
        SimConfig { impact_law: crate::impact::ImpactLaw::Newton, e_n: 0.2, iwc: crate::impact::IwcRule::Plastic, ..SimConfig::default() };
    let x0 = crate::initial::deg_to_state([34.53531701873741, 0.0, 23.744016380660902, 0.0]);
    let start = Plant::new(params, cfg, x0, 0.0, [0.0, 0.0]).unwrap();
    let hold = crate::Hold([0.0, 0.0]);
    let mut first = start.clone();
    let mut t_star = f64::NAN;
    for k in 0..20 {
        let r = first.advance(&hold, (k + 1) as f64 * 1e-3 - first.time(), &mut NoObserver).unwrap();
        if let Some(e) = r.events.iter().find(|e| e.kind == EventKind::PZero) {
            t_star = e.t;
            break;
        }
    }
    assert!(t_star.is_finite(), "no crossing");
    let mut departures = Vec::new();
    for tau in [1e-3, 1e-4, 1e-5] {
        let mut plant = start.clone();
        plant.advance(&hold, t_star - tau, &mut NoObserver).unwrap();
        let a = plant.approach(&hold).unwrap();
        let x = plant.state();
        let td = plant.arm().tip_dynamics(&Vector2::new(x[0], x[2]), &Vector2::new(x[1], x[3]), &Vector2::zeros());
        let f_n = -td.b() / td.p(params.mu, SlipDirection::Positive);
        println!("tau {tau:e}: k {:.4}, f_inf {:.5} N, f_n {f_n:.5} N", a.order(), a.limit_force());
        assert!(a.order() > 1.0 && a.limit_force() > 0.0, "tau {tau}: {a:?}");
        departures.push((f_n - a.limit_force()).abs() / a.limit_force());
    }
    assert!(departures[0] > departures[1] && departures[1] > departures[2] && departures[2] < 0.01, "{departures:?}");
}

/// The rule decides the indeterminate region: `leave` takes the flight solution
/// (the tip is off the belt 5 ms later), `slide` the sliding one (still sliding,
/// time-stepped, with the reaction `f_n = -b/p` at the law's 3 N and `p < 0, b > 0`).
#[test]
fn the_singular_rule_leaves_or_slides_through_the_indeterminate_region() {
    let (plant, events) = bridged(SingularRule::Leave, crate::config::BRIDGE_STEP);
    assert_eq!(events[0].kind, EventKind::SingularPoint);
    assert_eq!(events[0].mode_after, shared::ContactMode::Flight);
    assert_eq!(plant.mode(), shared::ContactMode::Flight);
    assert!(plant.tip()[1] + plant.arm().params.h > 0.0, "off the belt");
    assert_eq!((plant.counters().singular_points, plant.counters().bridges), (1, 1));

    let (plant, events) = bridged(SingularRule::Slide, crate::config::BRIDGE_STEP);
    assert_eq!(events[0].kind, EventKind::SingularPoint);
    assert_eq!(plant.mode(), shared::ContactMode::Sliding);
    let (p, b) = p_and_b(&plant, &PRESS);
    assert!(p < 0.0 && b > 0.0, "in the indeterminate region: p/Q22 {p}, b {b}");
    let u = PRESS.torque(0.0, &plant.state(), &[0.0; 2], &mut [0.0; 2]);
    let f_n = plant.contact_force(u)[1];
    assert!((f_n - 3.0).abs() < 0.05, "the law's reaction: {f_n} N");
    assert!(plant.counters().bridges >= 5, "time-stepped on: {}", plant.counters().bridges);
}

/// The law of the two tests above, for reading `p` and `b` after the run.
const PRESS: ThroughTheCorner = ThroughTheCorner {
    arm: Arm {
        params: Params { m: 0.12, l: 0.21, sigma: 0.005, k: 1.3, h: 0.3775, alpha0: 0.23945917337362202, g: 9.81, mu: 0.6, v_belt: -0.4 },
    },
    f_star: 3.0,
    v_des: 0.05,
    lead: 0.0,
};

/// The bridge converges as its step shrinks: from 0.2 ms before the singular
/// point, a 1 ms stretch's end angles move about half as much at each halving of
/// the step (Moreau-Jean is first order) and its outcome does not change; and the
/// bridged run, refined to [`BRIDGE_TOLERANCE`], has the same outcome and end
/// state (to twice that tolerance) from any starting bridge step.
#[test]
fn a_bridged_run_converges_as_the_bridge_step_shrinks() {
    let (mut plant, ctrl) = corner_case(SingularRule::Leave, crate::config::BRIDGE_STEP);
    let t_zero = time_of_p_zero(&plant, &ctrl);
    plant.advance(&ctrl, t_zero - 2e-4, &mut NoObserver).unwrap();
    let y0: OdeState = {
        let x = plant.state();
        [x[0], x[1], x[2], x[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    };
    let ends: Vec<(OdeState, crate::moreau_jean::ContactSolution)> = [25, 50, 100, 200, 400, 800]
        .into_iter()
        .map(|n| {
            let s = plant.stretch(&ctrl, plant.time(), &y0, 1e-3, n).unwrap();
            (*s.states.last().unwrap(), s.last)
        })
        .collect();
    let moved: Vec<f64> = ends.windows(2).map(|w| (w[0].0[0] - w[1].0[0]).abs().max((w[0].0[2] - w[1].0[2]).abs())).collect();
    assert!(ends.windows(2).all(|w| w[0].1 == w[1].1), "the same outcome: {:?}", ends.iter().map(|e| e.1).collect::<Vec<_>>());
    assert!(moved.windows(2).all(|w| w[1] < 0.7 * w[0] && w[1] > 0.3 * w[0]), "first-order convergence: {moved:?}");

    let runs: Vec<([f64; 4], shared::ContactMode, Vec<EventKind>)> = [4e-5, 2e-5, 1e-5, 3e-6]
        .into_iter()
        .map(|h| {
            let (plant, events) = bridged(SingularRule::Leave, h);
            (plant.state(), plant.mode(), events.iter().map(|e| e.kind).collect())
        })
        .collect();
    for w in runs.windows(2) {
        assert_eq!((w[0].1, &w[0].2), (w[1].1, &w[1].2), "the same outcome");
        let d = (w[0].0[0] - w[1].0[0]).abs().max((w[0].0[2] - w[1].0[2]).abs());
        assert!(d <= 2.0 * BRIDGE_TOLERANCE, "end angles within the tolerance: {d}");
    }
}

/// A bridge keeps the energy ledger (issue 53): its works are booked step by step,
/// its balance is within what its convergence tolerances are worth, and the ledger
/// of the bridged run closes, whatever step the bridge started from. Its end rates,
/// refined with its angles, agree across those starts to twice
/// [`super::plant::bridge::BRIDGE_RATE_TOLERANCE`] right after the bridge.
#[test]
fn a_bridge_keeps_the_energy_ledger_and_converges_in_its_rates() {
    let mut ends = Vec::new();
    for h in [4e-5, 1e-5] {
        let (mut plant, ctrl) = corner_case(SingularRule::Leave, h);
        let t_zero = time_of_p_zero(&plant, &ctrl);
        plant.advance(&ctrl, t_zero - 2e-4, &mut NoObserver).unwrap();
        let e0 = plant.energy();
        let works = |p: &Plant| {
            let l = p.ledger();
            l.motors_j + l.damping_j + l.belt_j + l.slip_j + l.projections_j
        };
        let w0 = works(&plant);
        let mut events = Vec::new();
        plant.bridge(&ctrl, Boundary::Singular, plant.time() + 5e-3, &mut NoObserver, &mut events).unwrap();
        let l = plant.ledger();
        assert_eq!(plant.counters().bridges, 1);
        assert_eq!(l.violations, 0, "{l:?}");
        let across = (plant.energy() - e0) - (works(&plant) - w0);
        assert!(across.abs() < 1e-5, "the bridge's balance: {across} J unexplained ({l:?})");
        assert!(l.residual_j.abs() < 1e-5, "{l:?}");
        ends.push(plant.state());
    }
    let dv = (ends[0][1] - ends[1][1]).abs().max((ends[0][3] - ends[1][3]).abs());
    assert!(dv <= 2.0 * super::plant::bridge::BRIDGE_RATE_TOLERANCE, "end rates {dv} rad/s apart");
}

/// `near_singular` names the neighbourhood along the slide into the corner: both
/// `p/Q22` and `-b/g` at most 0.05 with the reaction (3 N) finite; false at the
/// start of the slide, true just before `p = 0`.
#[test]
fn the_singular_neighbourhood_is_both_small_with_a_finite_force() {
    let (mut plant, ctrl) = corner_case(SingularRule::Leave, crate::config::BRIDGE_STEP);
    let (cell, trig) = (std::cell::Cell::new(0), crate::trig::TrigCache::new());
    let mut seen = Vec::new();
    for k in 0..1000 {
        let x = plant.state();
        let y: OdeState = [x[0], x[1], x[2], x[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let seg = crate::segment::Segment::new(
            plant.arm(),
            crate::Phase::Sliding(SlipDirection::Positive),
            &ctrl,
            false,
            plant.config(),
            &cell,
            &trig,
        );
        let (p, b) = p_and_b(&plant, &ctrl);
        let near = seg.near_singular(plant.time(), &y, None);
        assert_eq!(near, p <= 0.05 && -b / 9.81 <= 0.05, "p/Q22 {p}, b {b}");
        seen.push(near);
        plant.advance(&ctrl, (k + 1) as f64 * 1e-3 - plant.time(), &mut NoObserver).unwrap();
        if plant.counters().p_zero > 0 {
            break;
        }
    }
    assert!(!seen[0] && *seen.last().unwrap(), "{seen:?}");
}

/// Whatever the mode, the bridge is the same model: from a flight that lands on
/// the belt within it (an impact, Newton's law with friction, as the event-driven
/// touchdown), a 1 ms bridge ends where the event-driven integration does, to
/// within a few times its step (first order: half as far at half the step).
#[test]
fn a_bridge_across_a_touchdown_agrees_with_the_event_driven_run() {
    let params = Params::<f64>::paper();
    // x0a lifted 1 mm, falling at 0.2 m/s.
    let q = inverse_kinematics(params.l, &Vector2::new(0.17, -params.h + 1e-4), ElbowBranch::Down).unwrap();
    let qd = shared::kinematics::jacobian(params.l, &q).try_inverse().unwrap() * Vector2::new(0.0, -0.2);
    let x0 = [q[0], qd[0], q[1], qd[1]];
    let mut reference = Plant::new(params, SimConfig::default(), x0, 0.0, [0.0; 2]).unwrap();
    assert_eq!(reference.mode(), shared::ContactMode::Flight);
    let events = reference.advance(&crate::Hold([0.0; 2]), 2e-3, &mut NoObserver).unwrap().events;
    assert!(events.iter().any(|e| e.kind == EventKind::Touchdown), "it lands: {events:?}");
    let gaps: Vec<f64> = [2e-5, 1e-5]
        .into_iter()
        .map(|h| {
            let cfg = SimConfig { bridge_step: h, bridge_length: 2e-3, ..SimConfig::default() };
            let mut plant = Plant::new(params, cfg, x0, 0.0, [0.0; 2]).unwrap();
            let mut events = Vec::new();
            // One stretch at exactly this step: the refinement is tested above.
            let y0: OdeState = [x0[0], x0[1], x0[2], x0[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            let stretch = plant.stretch(&crate::Hold([0.0; 2]), 0.0, &y0, 2e-3, (2e-3 / h) as usize).unwrap();
            let end = stretch.states.last().unwrap();
            plant.bridge(&crate::Hold([0.0; 2]), Boundary::Collapse, 2e-3, &mut NoObserver, &mut events).unwrap();
            assert_eq!(events[0].kind, EventKind::Bridge);
            let x = reference.state();
            (0..4).map(|i| (end[[0, 1, 2, 3][i]] - x[i]).abs()).fold(0.0, f64::max)
        })
        .collect();
    // Measured: 6.3e-3 and 3.1e-3 (rad, rad/s) at 20 and 10 us.
    assert!(gaps[0] < 0.02, "agrees to first order: {gaps:?}");
    assert!(gaps[1] > 0.4 * gaps[0] && gaps[1] < 0.6 * gaps[0], "half as far at half the step: {gaps:?}");
}
