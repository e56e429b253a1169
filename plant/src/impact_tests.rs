//! Tests of the impact laws ([`super`]): the laws' impulses against their
//! definitions and each other, their contact work, and Kane's energy-creating
//! Newton impact with its fallback.

use super::*;
use proptest::prelude::*;

/// Kinetic energy change of a one-phase impact seen from a frame moving with
/// the belt: `dT = P . (v- + v+) / 2` (exact for an impulse at fixed configuration).
fn energy_change(imp: &Impulse, v: Vector2<f64>) -> f64 {
    imp.p.dot(&(v + v + imp.dv)) * 0.5
}

fn spd(a: f64, b: f64, c: f64) -> Matrix2<f64> {
    // Q = L L^T with L lower-triangular, positive diagonal.
    let l = Matrix2::new(a, 0.0, b, c);
    l * l.transpose()
}

#[test]
fn frictionless_poisson_equals_newton() {
    let qm = spd(3.0, 1.0, 2.0);
    let n = touchdown(&qm, 0.0, 0.3, -0.5, ImpactLaw::Newton, 0.5).unwrap();
    let p = touchdown(&qm, 0.0, 0.3, -0.5, ImpactLaw::Poisson, 0.5).unwrap();
    assert!((n.p - p.p).norm() < 1e-12);
    assert!((n.dv[1] - 0.75).abs() < 1e-12); // v_n+ = -e v_n- = 0.25
}

#[test]
fn head_on_sticking_impact_is_newton_exact() {
    // Diagonal Q with enough friction: the tip sticks, v_n+ = -e v_n-.
    let qm = Matrix2::new(2.0, 0.0, 0.0, 1.0);
    for law in [ImpactLaw::Newton, ImpactLaw::Poisson] {
        let imp = touchdown(&qm, 1.0, 0.1, -1.0, law, 0.3).unwrap();
        assert!((0.1 + imp.dv[0]).abs() < 1e-12, "{law:?} slip stopped");
        assert!((-1.0 + imp.dv[1] - 0.3).abs() < 1e-12, "{law:?}: v_n+ = 0.3");
    }
}

#[test]
fn iwc_stops_the_slip_and_lifts_the_tip_off() {
    // A Q with strong coupling so that p(+) < 0 at mu = 0.8.
    let qm = spd(2.0, 0.5, 0.1);
    let s = SlipDirection::Positive;
    let mu = 0.8;
    assert!(shared::contact::p_of(&qm, mu, s) < 0.0);
    for law in ImpactLaw::ALL {
        let imp = without_collision(&qm, mu, 0.4, law, 0.5, IwcRule::Restitution).unwrap();
        assert!((0.4 + imp.dv[0]).abs() < 1e-12, "{law:?}: slip stopped");
        assert!(imp.dv[1] > 0.0, "{law:?}: lifts off");
        assert!(imp.v_n_min < 0.0, "{law:?}: compression");
        assert!(imp.contact_work <= 1e-12, "{law:?}: work {}", imp.contact_work);
        let with_zero = without_collision(&qm, mu, 0.4, law, 0.0, IwcRule::Restitution).unwrap();
        assert!(with_zero.dv[1].abs() < 1e-12, "{law:?}: e = 0 leaves the tip on the belt");
        // The plastic rule: stuck tangentially, v_n = 0, whatever the law and e.
        for e in [0.0, 0.5, 1.0] {
            let plastic = without_collision(&qm, mu, 0.4, law, e, IwcRule::Plastic).unwrap();
            assert_eq!(plastic.resolution, Resolution::PlasticIwc);
            assert!((0.4 + plastic.dv[0]).abs() < 1e-12 && plastic.dv[1].abs() < 1e-12, "{law:?} e {e}: {:?}", plastic.dv);
            assert!(plastic.contact_work < 0.0 && in_cone(&plastic.p, mu));
            assert!((plastic.p - with_zero.p).norm() < 1e-12, "the e = 0 restitution result");
        }
    }
}

#[test]
fn without_friction_the_three_laws_agree() {
    // mu = 0: one phase, and Stronge's, Poisson's and Newton's coefficients coincide.
    let qm = spd(1.5, -0.7, 0.9);
    for e in [0.0, 0.3, 1.0] {
        let v: Vec<Impulse> = ImpactLaw::ALL.iter().map(|&law| touchdown(&qm, 0.0, 0.2, -0.8, law, e).unwrap()).collect();
        for imp in &v {
            assert!((-0.8 + imp.dv[1] - 0.8 * e).abs() < 1e-12, "v_n+ = -e v_n-: {imp:?}");
            assert!((imp.p - v[0].p).norm() < 1e-12);
        }
        assert_eq!(v[2].resolution, Resolution::EnergeticDarbouxKeller);
    }
}

#[test]
fn energetic_work_is_the_restitution_fraction_of_compression() {
    // A slip that does not stop: the normal work in restitution is e^2 of
    // compression's, W_n = (1 - e^2) W_c, checked against P_n and v_n directly.
    let qm = spd(1.0, 0.3, 1.2);
    let (mu, v_r, v_n, e) = (0.2, 2.0, -0.5, 0.6);
    let imp = energetic(&qm, mu, v_r, v_n, e).unwrap();
    let s = 1.0;
    let dvn = qm[(1, 1)] - mu * s * qm[(1, 0)];
    // One phase: v_n(P) = v_n + dvn P; W_n(P) = v_n P + dvn P^2 / 2.
    let w = |p: f64| v_n * p + 0.5 * dvn * p * p;
    let p_c = -v_n / dvn;
    assert!(v_r + (qm[(0, 1)] - mu * s * qm[(0, 0)]) * imp.p[1] > 0.0, "still slipping");
    assert!((w(imp.p[1]) - (1.0 - e * e) * w(p_c)).abs() < 1e-12, "{} vs {}", w(imp.p[1]), (1.0 - e * e) * w(p_c));
    // Its final normal velocity: v_n+^2 = e^2 v_n-^2 for a single phase.
    assert!(((v_n + imp.dv[1]) - e * v_n.abs()).abs() < 1e-12);
}

proptest! {
    /// No law does positive work at a touchdown or an impact without collision
    /// (after the fallback), every impulse lies in the cone and pushes, and the
    /// tip leaves the impact not approaching the belt.
    #[test]
    fn no_impact_creates_energy(
        a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.05f64..3.0,
        mu in 0.0f64..1.5, v_r in -1.0f64..1.0, v_n in -1.0f64..0.0, e in 0.0f64..=1.0,
    ) {
        let qm = spd(a, b, c);
        for law in ImpactLaw::ALL {
            let imp = touchdown(&qm, mu, v_r, v_n, law, e);
            prop_assert!(imp.is_ok(), "{:?}", imp);
            let imp = imp.unwrap();
            prop_assert!(imp.contact_work <= work_tolerance(&qm, v_r, v_n), "{law:?}: work {} ({:?})", imp.contact_work, imp.resolution);
            prop_assert!(imp.p[1] >= 0.0);
            prop_assert!(imp.p[0].abs() <= mu * imp.p[1] * (1.0 + 1e-9) + 1e-12);
            prop_assert!(v_n + imp.dv[1] >= -1e-12, "{law:?} separates: {}", v_n + imp.dv[1]);
            if law == ImpactLaw::Energetic {
                prop_assert_eq!(imp.resolution, Resolution::EnergeticDarbouxKeller);
            }
            // The impact without collision, where the state is inconsistent.
            if shared::contact::p_of(&qm, mu, SlipDirection::of(v_r)) < 0.0 && v_r.abs() > 1e-6 {
                for rule in IwcRule::ALL {
                    let iwc = without_collision(&qm, mu, v_r, law, e, rule);
                    prop_assert!(iwc.is_ok(), "{:?}", iwc);
                    let iwc = iwc.unwrap();
                    prop_assert!(iwc.contact_work <= work_tolerance(&qm, v_r, 0.0), "{law:?}/{rule:?}: work {}", iwc.contact_work);
                    prop_assert!(iwc.dv[1] >= -1e-12);
                }
            }
        }
    }

    #[test]
    fn poisson_never_gains_energy_and_respects_the_cone(
        a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.3f64..3.0,
        mu in 0.0f64..1.2, v_r in -1.0f64..1.0, v_n in -1.0f64..-0.01, e in 0.0f64..1.0,
    ) {
        let qm = spd(a, b, c);
        // With Q symmetric positive definite, compression always ends: no jam.
        let imp = darboux_keller(&qm, mu, v_r, v_n, e);
        prop_assert!(imp.is_ok(), "{:?}", imp);
        if let Ok(imp) = imp {
            prop_assert!(imp.p[1] >= 0.0);
            prop_assert!(imp.p[0].abs() <= mu * imp.p[1] * (1.0 + 1e-9) + 1e-12);
            let v_after_n = v_n + imp.dv[1];
            prop_assert!(v_after_n >= -1e-12, "separates: {}", v_after_n);
            // Poisson with Coulomb friction can create energy only with slip reversal
            // (Stronge 2000); the plant reports it. Without reversal it must not.
            let vr_after = v_r + imp.dv[0];
            let scale = 1e-9 * (v_r * v_r + v_n * v_n) / qm.norm();
            if vr_after * v_r >= 0.0 {
                prop_assert!(imp.contact_work <= scale, "work {}", imp.contact_work);
            }
            // With one phase, the phase-wise work equals P . (v- + v+)/2.
            if mu == 0.0 {
                prop_assert!((imp.contact_work - energy_change(&imp, Vector2::new(v_r, v_n))).abs() <= scale.max(1e-12));
            }
        }
    }

    /// Newton-Coulomb at the impulse level (module documentation, "Newton"):
    /// the impulse sticks the tip inside the cone, or lies on the cone's edge
    /// whose friction opposes the slip the impact leaves; the edge always exists
    /// for an approaching tip (`p(s) > 0` on the side the sticking impulse
    /// leaves by), so Darboux-Keller is never needed at a touchdown. Only an
    /// impact that would create energy (a slip reversed by friction itself,
    /// Kane and Levinson 1985) falls back to the energetic law.
    #[test]
    fn newton_friction_never_points_along_the_slip_it_leaves(
        a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.05f64..3.0,
        mu in 0.0f64..1.5, v_r in -1.0f64..1.0, v_n in -1.0f64..-1e-3, e in 0.0f64..=1.0,
    ) {
        let qm = spd(a, b, c);
        let imp = newton_touchdown(&qm, mu, v_r, v_n, e).unwrap();
        let v_r_after = v_r + imp.dv[0];
        let scale = v_r.abs().max(v_n.abs());
        match imp.resolution {
            Resolution::NewtonSticking => prop_assert!(v_r_after.abs() <= 1e-9 * scale, "sticks: v_r+ {}", v_r_after),
            Resolution::NewtonSliding => {
                prop_assert!(imp.p[0] * v_r_after <= 0.0, "P_t {} along v_r+ {}", imp.p[0], v_r_after);
                prop_assert!((imp.p[0].abs() - mu * imp.p[1]).abs() <= 1e-9 * mu * imp.p[1] + 1e-15, "on the edge");
            }
            other => prop_assert!(false, "{:?} at a touchdown", other),
        }
        let used = touchdown(&qm, mu, v_r, v_n, ImpactLaw::Newton, e).unwrap();
        if used.resolution != Resolution::NewtonFallback {
            prop_assert_eq!(used, imp);
        } else {
            prop_assert!(imp.contact_work > work_tolerance(&qm, v_r, v_n));
        }
    }

    #[test]
    fn newton_sticking_and_edge_impulses_restore_normal_velocity(
        a in 0.3f64..3.0, b in -2.0f64..2.0, c in 0.3f64..3.0,
        mu in 0.0f64..1.2, v_r in -1.0f64..1.0, v_n in -1.0f64..-0.01, e in 0.0f64..1.0,
    ) {
        let qm = spd(a, b, c);
        let imp = touchdown(&qm, mu, v_r, v_n, ImpactLaw::Newton, e);
        prop_assert!(imp.is_ok(), "{:?}", imp);
        let imp = imp.unwrap();
        if matches!(imp.resolution, Resolution::NewtonSticking | Resolution::NewtonSliding) {
            prop_assert!((v_n + imp.dv[1] + e * v_n).abs() < 1e-9);
            prop_assert!(imp.p[1] >= 0.0);
            prop_assert!(imp.p[0].abs() <= mu * imp.p[1] * (1.0 + 1e-9) + 1e-12);
        }
    }
}

mod kane {
    use super::*;

    /// Kane's classic observation (Kane and Levinson, "Dynamics Online", 1985; Stronge
    /// 2000, sec. 5.4): Newton's restitution with Coulomb friction can create energy
    /// when the slip reverses during the impact. Newton's own impulse shows it; the
    /// law then falls back to the energetic one, and Poisson's does not create it here.
    #[test]
    fn newton_with_friction_can_create_energy_and_falls_back() {
        let mut found = None;
        'search: for a in [0.5, 1.0, 2.0] {
            for b in [-1.5, -1.0, -0.5, 0.5, 1.0, 1.5] {
                for c in [0.2, 0.5, 1.0] {
                    let l = Matrix2::new(a, 0.0, b, c);
                    let qm = l * l.transpose();
                    for mu in [0.2, 0.5, 0.8] {
                        for v_r in [-0.5, -0.1, 0.1, 0.5] {
                            let imp = newton_touchdown(&qm, mu, v_r, -1.0, 0.9).unwrap();
                            if imp.contact_work > 1e-6 {
                                found = Some((qm, mu, v_r, imp));
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        let (qm, mu, v_r, imp) = found.expect("a Newton impact that creates energy");
        assert_eq!(imp.resolution, Resolution::NewtonSliding);
        let dk = darboux_keller(&qm, mu, v_r, -1.0, 0.9).unwrap();
        assert!(dk.contact_work <= 1e-12, "Poisson dissipates at the same impact: {}", dk.contact_work);
        let used = touchdown(&qm, mu, v_r, -1.0, ImpactLaw::Newton, 0.9).unwrap();
        assert_eq!(used.resolution, Resolution::NewtonFallback);
        assert_eq!(used.p, energetic(&qm, mu, v_r, -1.0, 0.9).unwrap().p);
        assert!(used.contact_work <= 0.0, "{}", used.contact_work);
    }
}
