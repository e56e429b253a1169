//! The energy ledger (docs/plant.md "The energy ledger") and issue 53's energy jump:
//! the ledger closes on every run, and the arm that jumped off its bouncing orbit at
//! a singular-point passage (an event located on a dense output across the pole of
//! `f_n = -b/p`) bounces to 300 s under both IWC rules and three sample periods, as
//! a Moreau-Jean time-stepper and a SciPy event-driven simulator do.

use super::*;
use crate::{
    impact::{ImpactLaw, IwcRule},
    initial::{X0A, X0D, deg_to_state},
};
use shared::Params;

/// Issue 53's arm: `m 0.15, l 0.23, sigma 0.008, k 1.0, H 0.40, alpha0 0.20`,
/// `v_belt -0.5`, `mu 0.422`.
fn issue53_arm() -> Params<f64> {
    let mut p = Params::<f64>::paper();
    (p.m, p.l, p.sigma, p.k, p.h, p.alpha0, p.v_belt, p.mu) = (0.15, 0.23, 0.008, 1.0, 0.40, 0.20, -0.5, 0.422);
    p
}

/// Issue 53's start (degrees, deg/s).
const ISSUE53_X0: [f64; 4] = [34.53531701873741, 0.0, 23.744016380660902, 0.0];

/// The rest state the jump ended in has `E = -0.6078 J`; the bouncing orbit stays
/// above -0.59 J.
const BOUNCING_ABOVE: f64 = -0.59;

/// What one open-loop run sampled every `dt` s showed.
struct Watched {
    /// The largest rise of the energy between two samples, J, and when.
    largest_rise: (f64, f64),
    /// The energy at the end, J.
    e_end: f64,
    plant: Plant,
}

fn watch(params: Params<f64>, cfg: SimConfig, deg: [f64; 4], duration: f64, dt: f64) -> Watched {
    let mut plant = Plant::new(params, cfg, deg_to_state(deg), 0.0, [0.0, 0.0]).unwrap();
    let n = (duration / dt).round() as usize;
    let mut e = plant.energy();
    let mut largest_rise = (f64::NEG_INFINITY, 0.0);
    for k in 0..n {
        plant.advance(&Hold([0.0, 0.0]), (k + 1) as f64 * dt - plant.time(), &mut NoObserver).unwrap();
        let e_next = plant.energy();
        if e_next - e > largest_rise.0 {
            largest_rise = (e_next - e, plant.time());
        }
        e = e_next;
    }
    Watched { largest_rise, e_end: e, plant }
}

/// The ledger of a finished run closes: what it does not explain is within the sum
/// of its entries' tolerances, far below any work it books.
fn assert_closed(what: &str, plant: &Plant) {
    let l = plant.ledger();
    assert_eq!(l.violations, 0, "{what}: {l:?}");
    assert!(plant.validity(None).is_valid(), "{what}: {}", plant.validity(None));
    let scale = l.motors_j.abs() + l.damping_j.abs() + l.belt_j.abs() + l.slip_j.abs() + 1.0;
    assert!(l.residual_j.abs() <= 1e-6 * scale, "{what}: residual {} J of {scale} J booked: {l:?}", l.residual_j);
}

/// Issue 53's reproducers, and the four other runs of the same arm: each bounces to
/// 300 s (as both references do), no energy rise between two samples beyond the
/// orbit's own (0.033 J), the ledger closed.
#[test]
fn the_issue53_arm_keeps_bouncing_under_both_iwc_rules_and_every_sample_period() {
    for iwc in [IwcRule::Plastic, IwcRule::Restitution] {
        for dt in [0.1, 0.01, 0.001] {
            let cfg = SimConfig { impact_law: ImpactLaw::Newton, e_n: 0.2, iwc, ..SimConfig::default() };
            let w = watch(issue53_arm(), cfg, ISSUE53_X0, 300.0, dt);
            let what = format!("{iwc:?} at {dt} s");
            assert!(w.largest_rise.0 < 0.2, "{what}: the energy rose by {} J at t = {} s", w.largest_rise.0, w.largest_rise.1);
            assert!(w.e_end > BOUNCING_ABOVE, "{what}: E(300) = {} J, the rest state's, not the bouncing orbit's", w.e_end);
            assert!(w.plant.counters().singular_points > 0, "{what}: the run meets the singular point");
            assert_closed(&what, &w.plant);
        }
    }
}

/// The ledger closes on the paper's runs: open loop from `x0a` (bouncing, IWCs),
/// `x0d` (sliding) under a held torque, across both IWC rules.
#[test]
fn the_ledger_closes_on_the_paper_runs() {
    for iwc in [IwcRule::Plastic, IwcRule::Restitution] {
        for (name, x0, u) in [("x0a", X0A.deg, [0.0, 0.0]), ("x0d", X0D.deg, [0.3, -0.1])] {
            let cfg = SimConfig { iwc, ..SimConfig::default() };
            let mut p = Plant::new(Params::paper(), cfg, deg_to_state(x0), 0.0, u).unwrap();
            for k in 0..2000 {
                p.advance(&Hold(u), (k + 1) as f64 * 5e-3 - p.time(), &mut NoObserver).unwrap();
            }
            let what = format!("{name} {iwc:?}");
            assert_closed(&what, &p);
            let l = p.ledger();
            assert!(l.damping_j < 0.0 && l.slip_j <= 1e-9, "{what}: damping and the contact dissipate: {l:?}");
            if u != [0.0, 0.0] {
                assert!(l.motors_j.abs() > 1e-3, "{what}: the motors work: {l:?}");
            } else {
                assert_eq!(l.motors_j, 0.0);
            }
        }
    }
}

/// Issue 67: the events table books every impulse. Over issue 53's reproducer
/// (`mu 0.422`, the plastic IWC, 20 s with its singular-point passages, slip stops
/// and Zeno ends) and the paper's bouncing `x0a`: no row changes the tip's
/// velocity by more than what a located event leaves (1e-6 m/s) without an impulse
/// (a `zeno_ended` row carries its projection's, a `velocity_projection` row any
/// other), and the rows' energy changes sum to the ledger's `events_j`, the
/// table's own closure against the trace's `E(t) - E(0)`.
#[test]
fn the_events_table_books_every_impulse() {
    let mut paper = Params::<f64>::paper();
    paper.v_belt = -0.5;
    for (name, params, deg) in [("issue 53", issue53_arm(), ISSUE53_X0), ("x0a", paper, X0A.deg)] {
        let cfg = SimConfig { impact_law: ImpactLaw::Newton, e_n: 0.2, iwc: IwcRule::Plastic, ..SimConfig::default() };
        let mut plant = Plant::new(params, cfg, deg_to_state(deg), 0.0, [0.0, 0.0]).unwrap();
        let mut events = plant.startup_events().to_vec();
        for k in 0..2000 {
            events.extend(plant.advance(&Hold([0.0, 0.0]), (k + 1) as f64 * 1e-2 - plant.time(), &mut NoObserver).unwrap().events);
        }
        let mut sum = 0.0;
        let mut booked = 0;
        for e in &events {
            let moved = (e.v_n_after - e.v_n_before).hypot(e.v_r_after - e.v_r_before);
            let impulse = e.impulse[0].hypot(e.impulse[1]);
            assert!(
                moved <= crate::segment::ROOT_TOLERANCE || impulse > 0.0,
                "{name}: a {} row at t = {} changes the velocity by {moved} m/s with no impulse: {e:?}",
                e.kind.name(),
                e.t
            );
            if e.resolution.is_some() && e.kind != EventKind::EnergyGain {
                sum += e.energy_change;
                booked += 1;
            }
        }
        let l = plant.ledger();
        assert!((sum - l.events_j).abs() <= 1e-12 * (1.0 + l.events_j.abs()), "{name}: rows {sum} J, ledger {} J", l.events_j);
        assert!(booked > 100, "{name}: {booked} impulses");
        assert_eq!((l.violations, l.impulses_outside_cone, l.impulses_off_law), (0, 0, 0), "{name}: {l:?}");
        println!("{name}: {} rows, {booked} with an impulse, {sum:.6} J booked", events.len());
    }
}

/// Issue 67: the ledger's impulse checks can fail. Planted on a plant at rest on
/// the belt (`x0d`), for a tip arriving at `[v_r, v_n] = [0.3, -0.2]` m/s: Newton's
/// own impulse passes; one pushed outside the friction cone (`|P_t| > mu P_n`) or
/// pulling (`P_n < 0`) is a violation and a cone violation (and, no longer being
/// Newton's, off its law); one that does positive work in the belt's frame (the
/// contact creating energy) is a violation and an `energy_gain` row.
#[test]
fn a_planted_impulse_outside_the_cone_or_creating_energy_fails_the_ledger() {
    use crate::impact::{ImpactLaw, Impulse};
    let mut plant = Plant::new(Params::paper(), SimConfig::default(), deg_to_state(X0D.deg), 0.0, [0.0, 0.0]).unwrap();
    let x = plant.state();
    let qm = plant.arm().q_matrix(&nalgebra::Vector2::new(x[0], x[2]));
    let (mu, e) = (plant.arm().params.mu, SimConfig::default().e_n);
    let before = nalgebra::Vector2::new(0.3, -0.2);
    let newton = crate::impact::touchdown(&qm, mu, before[0], before[1], ImpactLaw::Newton, e).unwrap();
    let with_p = |p: [f64; 2]| {
        let p = nalgebra::Vector2::new(p[0], p[1]);
        Impulse { p, dv: qm * p, contact_work: p.dot(&(before + 0.5 * qm * p)), ..newton }
    };
    let counts = |plant: &Plant| {
        let l = plant.ledger();
        (l.violations, l.impulses_outside_cone, l.impulses_off_law)
    };
    let mut events = Vec::new();
    plant.check_impact(&mut events, &newton, &qm, 0.0, before);
    assert_eq!(counts(&plant), (0, 0, 0), "Newton's own impulse: {newton:?}");
    let pn = newton.p[1];
    plant.check_impact(&mut events, &with_p([-1.2 * mu * pn, pn]), &qm, 0.0, before);
    assert_eq!(counts(&plant), (2, 1, 1), "|P_t| = 1.2 mu P_n");
    plant.check_impact(&mut events, &with_p([0.0, -1e-3]), &qm, 0.0, before);
    assert_eq!(counts(&plant), (5, 2, 2), "P_n < 0: a pull (which also does positive work)");
    let creating = Impulse { contact_work: 1e-3, ..newton };
    plant.check_impact(&mut events, &creating, &qm, 0.0, before);
    assert_eq!(counts(&plant), (6, 2, 2), "the contact creates 1 mJ");
    assert_eq!(events.iter().filter(|e| e.kind == EventKind::EnergyGain).count(), 2);
}

/// Issue 67: the ledger holds each impulse to its own impact law
/// ([`crate::impact::breach`]). Planted on the same plant and tip: each law's own
/// impulse passes; Newton's scaled by 1.01 leaves `v_n+ != -e v_n-`; Poisson's
/// with its restitution ended for another `e` leaves `P_n != (1 + e) P_c`; the
/// energetic law's with 1 % more restitution work, or whose friction did positive
/// work while the whole impact still dissipates (so the belt-frame check alone
/// passes it), each fail the ledger and are counted in `impulses_off_law`; and a
/// plastic IWC that leaves the tip moving off the belt.
#[test]
fn a_planted_impulse_off_its_own_law_fails_the_ledger() {
    use crate::impact::{Compression, ImpactLaw, Impulse, IwcRule};
    let x0 = deg_to_state(X0D.deg);
    let before = nalgebra::Vector2::new(0.3, -0.2);
    for law in ImpactLaw::ALL {
        let cfg = SimConfig { impact_law: law, e_n: 0.5, ..SimConfig::default() };
        let mut plant = Plant::new(Params::paper(), cfg, x0, 0.0, [0.0, 0.0]).unwrap();
        let x = plant.state();
        let qm = plant.arm().q_matrix(&nalgebra::Vector2::new(x[0], x[2]));
        let mu = plant.arm().params.mu;
        let own = crate::impact::touchdown(&qm, mu, before[0], before[1], law, cfg.e_n).unwrap();
        let mut events = Vec::new();
        let mut check = |imp: &Impulse| {
            plant.check_impact(&mut events, imp, &qm, 0.0, before);
            let l = plant.ledger();
            (l.violations, l.impulses_off_law, l.impulses_outside_cone)
        };
        assert_eq!(check(&own), (0, 0, 0), "{law}: its own impulse {own:?}");
        let wrong = match law {
            ImpactLaw::Newton => Impulse { p: own.p * 1.01, dv: qm * own.p * 1.01, ..own },
            ImpactLaw::Poisson => crate::impact::darboux_keller(&qm, mu, before[0], before[1], 0.6).unwrap(),
            ImpactLaw::Energetic => Impulse { compression: Compression { w_r: 1.01 * own.compression.w_r, ..own.compression }, ..own },
        };
        assert_eq!(check(&wrong), (1, 1, 0), "{law}: {wrong:?}");
        if law == ImpactLaw::Energetic {
            let c = own.compression;
            let pushed = Impulse { contact_work: 0.9 * (c.w_c + c.w_r), ..own };
            assert!(pushed.contact_work < -1e-4, "still dissipative: {}", pushed.contact_work);
            assert_eq!(check(&pushed), (2, 2, 0), "friction's work > 0");
        }
    }
    // The plastic IWC leaves the tip on the belt; one that throws it off breaks the rule.
    let cfg = SimConfig { iwc: IwcRule::Plastic, ..SimConfig::default() };
    let mut plant = Plant::new(Params::paper(), cfg, x0, 0.0, [0.0, 0.0]).unwrap();
    let x = plant.state();
    let qm = plant.arm().q_matrix(&nalgebra::Vector2::new(x[0], x[2]));
    let v = nalgebra::Vector2::new(0.3, 0.0);
    let stuck = qm.try_inverse().unwrap() * -v;
    let plastic = Impulse {
        p: stuck,
        dv: -v,
        v_n_min: 0.0,
        contact_work: -0.5 * v.dot(&(qm.try_inverse().unwrap() * v)),
        resolution: crate::impact::Resolution::PlasticIwc,
        compression: Compression::default(),
    };
    let mut events = Vec::new();
    plant.check_impact(&mut events, &plastic, &qm, 0.0, v);
    assert_eq!(plant.ledger().impulses_off_law, 0, "{plastic:?}");
    let thrown = qm.try_inverse().unwrap() * nalgebra::Vector2::new(-0.3, 0.05);
    plant.check_impact(&mut events, &Impulse { p: thrown, dv: qm * thrown, ..plastic }, &qm, 0.0, v);
    assert_eq!(plant.ledger().impulses_off_law, 1);
}

/// Issue 67: the ledger checks each velocity projection against the drift it
/// removes. Sliding at 0.3 m/s with a normal drift `v_n` of 0.2 mm/s, the smallest
/// kinetic-energy correction dissipates exactly `v_n^2 / (2 Q_22)` in the belt's
/// frame and passes, as does a partial one; a planted projection that also brakes
/// the slip (it dissipates far more than the drift allows) or that pulls the tip
/// off (it creates energy) is a violation, counted in `projections_beyond_drift`;
/// the largest drift is kept.
#[test]
fn a_planted_projection_beyond_its_drift_fails_the_ledger() {
    let mut plant = Plant::new(Params::paper(), SimConfig::default(), deg_to_state(X0D.deg), 0.0, [0.0, 0.0]).unwrap();
    let x = plant.state();
    let qm = plant.arm().q_matrix(&nalgebra::Vector2::new(x[0], x[2]));
    let v_rel = nalgebra::Vector2::new(0.3, 2e-4);
    let drift = nalgebra::Vector2::new(0.0, v_rel[1]);
    let allowed = 0.5 * drift[1] * drift[1] / qm[(1, 1)];
    let right = nalgebra::Vector2::new(0.0, -drift[1] / qm[(1, 1)]);
    // Its work in the belt's frame, from the velocities before and after (as booked).
    let work = |p: nalgebra::Vector2<f64>| p.dot(&(v_rel + 0.5 * qm * p));
    assert!((work(right) + allowed).abs() < 1e-12 * allowed, "{} against {allowed}", work(right));
    let mut check = |p: nalgebra::Vector2<f64>| {
        plant.check_projection(p, work(p), drift, allowed);
        let l = plant.ledger();
        (l.violations, l.projections_beyond_drift, l.largest_projection_drift_m_s)
    };
    assert_eq!(check(right), (0, 0, 2e-4), "the exact projection");
    assert_eq!(check(0.5 * right), (0, 0, 2e-4), "half of it (half the drift left) dissipates 3/4 of the allowance");
    let braking = right + nalgebra::Vector2::new(-0.6 * right[1].abs(), 0.0);
    assert_eq!(check(braking), (1, 1, 2e-4), "a projection that brakes the slip too");
    assert_eq!(check(-right), (2, 2, 2e-4), "a pull, creating energy");
}

/// Issue 81: the ledger fails an impulse where none is due. The impact without
/// collision of each IWC rule and impact law, planted on `x0d`'s tip sliding where
/// sliding is consistent (`p(s) > 0`), is a violation counted in `impulses_undue`;
/// the same impulses where they are due, `x0a`'s tip in the Painlevé region (`p(s) < 0`),
/// pass that check.
#[test]
fn a_planted_impact_without_collision_where_none_is_due_fails_the_ledger() {
    use crate::impact::{ImpactLaw, IwcRule};
    let v_r = 0.3;
    let before = nalgebra::Vector2::new(v_r, 0.0);
    for (name, deg, due) in [("x0d", X0D.deg, false), ("x0a", X0A.deg, true)] {
        let mut plant = Plant::new(Params::paper(), SimConfig::default(), deg_to_state(deg), 0.0, [0.0, 0.0]).unwrap();
        let x = plant.state();
        let qm = plant.arm().q_matrix(&nalgebra::Vector2::new(x[0], x[2]));
        let mu = plant.arm().params.mu;
        let p = shared::slip::p_of(&qm, mu, shared::SlipDirection::Positive) / qm[(1, 1)];
        assert_eq!(p < 0.0, due, "{name}: p(+)/Q_22 {p}");
        let mut checked = 0;
        for law in ImpactLaw::ALL {
            for rule in [IwcRule::Plastic, IwcRule::Restitution] {
                let Ok(imp) = crate::impact::without_collision(&qm, mu, v_r, law, 0.5, rule) else { continue };
                let before_count = plant.ledger().impulses_undue;
                plant.check_impact(&mut Vec::new(), &imp, &qm, 0.0, before);
                let undue = plant.ledger().impulses_undue - before_count;
                assert_eq!(undue, u64::from(!due), "{name}, {law}, {rule:?}: {imp:?}");
                checked += 1;
            }
        }
        assert!(checked >= 4, "{name}: {checked} impulses");
    }
}

/// Issue 81: a velocity projection whose impulse no contact could give, a pull onto
/// the belt (the tip's drift off it removed) or friction beyond the cone, is counted in
/// `projections_unphysical` with the energy it changed; a push within the cone is not.
/// Such a projection is a violation where its drift exceeds twice the Zeno rule's
/// `zeno_velocity` (2e-4 m/s), else only counted (the violations counted here are
/// those, apart from the drift allowance's `projections_beyond_drift`).
#[test]
fn a_projection_that_pulls_or_leaves_the_cone_is_counted_with_its_energy() {
    let mut plant = Plant::new(Params::paper(), SimConfig::default(), deg_to_state(X0D.deg), 0.0, [0.0, 0.0]).unwrap();
    let x = plant.state();
    let qm = plant.arm().q_matrix(&nalgebra::Vector2::new(x[0], x[2]));
    let mu = plant.arm().params.mu;
    let mut check = |v_n: f64, tangential: f64| {
        let v_rel = nalgebra::Vector2::new(0.3, v_n);
        let drift = nalgebra::Vector2::new(0.0, v_n);
        let allowed = 0.5 * v_n * v_n / qm[(1, 1)];
        let p = nalgebra::Vector2::new(tangential * (v_n / qm[(1, 1)]).abs(), -v_n / qm[(1, 1)]);
        let work = p.dot(&(v_rel + 0.5 * qm * p));
        plant.check_projection(p, work, drift, allowed);
        let l = plant.ledger();
        (l.projections_unphysical, l.projections_unphysical_j, work.abs(), l.violations - l.projections_beyond_drift)
    };
    let (n, e, _, v) = check(-2e-4, 0.0);
    assert_eq!((n, e, v), (0, 0.0, 0), "a push that removes the drift into the belt");
    let (n, e, w, v) = check(5e-5, 0.0);
    assert_eq!((n, e, v), (1, w, 0), "a pull that removes a drift off the belt within the Zeno rule's 1e-4 m/s");
    assert!(w > 0.0);
    let (n, e, w2, v) = check(3e-4, 0.0);
    assert_eq!((n, e, v), (2, w + w2, 1), "a pull of 3e-4 m/s: a violation");
    let (n, e, _, v) = check(-3e-4, 0.5 * mu);
    assert_eq!((n, e, v), (2, w + w2, 1), "friction at half the cone: within it");
    let (n, e, w3, v) = check(-1e-4, 1.5 * mu);
    assert_eq!((n, e, v), (3, w + w2 + w3, 1), "friction at 1.5 times the cone, 1e-4 m/s of drift: counted");
    let (n, e, w4, v) = check(-3e-4, 1.5 * mu);
    assert_eq!((n, e, v), (4, w + w2 + w3 + w4, 2), "friction at 1.5 times the cone, 3e-4 m/s of drift: a violation");
}
