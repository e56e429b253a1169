//! Tests of the mode map ([`super`]): every point on the belt and classified by
//! an independent `b` and `p`, reachability, the curves `b = 0`, `p = 0` and
//! `z_r_dot = 0`, and the counts.

use super::*;

const MU: f64 = 0.6;
const V: f64 = -0.4;

/// `b` and `p` recomputed from docs/model.md's formulas, without the shared model.
fn independent_b_p(pr: &Params<f64>, t1: f64, t2: f64, w1: f64, w2: f64, dir_sign: f64) -> (f64, f64) {
    let (m, l, g, k, s, a0) = (pr.m, pr.l, pr.g, pr.k, pr.sigma, pr.alpha0);
    let ml2 = m * l * l;
    let (m11, m12, m22) = (4.0 / 3.0 * ml2, 0.5 * ml2 * (t2 - t1).cos(), ml2 / 3.0);
    let det = m11 * m22 - m12 * m12;
    let (i11, i12, i22) = (m22 / det, -m12 / det, m11 / det);
    let spring = k * (t2 - t1 + a0);
    let w = [1.5 * m * g * l * t1.sin() - spring - s * (w2 - 2.0 * w1), 0.5 * m * g * l * t2.sin() + spring + s * (w2 - w1)];
    let c = [0.5 * ml2 * w2 * w2 * (t1 - t2).sin(), 0.5 * ml2 * w1 * w1 * (t2 - t1).sin()];
    let r = [w[0] + c[0], w[1] + c[1]];
    let minv_r = [i11 * r[0] + i12 * r[1], i12 * r[0] + i22 * r[1]];
    let j1 = [l * t1.cos(), l * t2.cos()];
    let j2 = [l * t1.sin(), l * t2.sin()];
    let s2 = l * (w1 * w1 * t1.cos() + w2 * w2 * t2.cos());
    let b = -(j2[0] * minv_r[0] + j2[1] * minv_r[1]) + s2;
    let quad = |u: [f64; 2], v: [f64; 2]| u[0] * (i11 * v[0] + i12 * v[1]) + u[1] * (i12 * v[0] + i22 * v[1]);
    let p = quad(j2, j2) - pr.mu * dir_sign * quad(j2, j1);
    (b, p)
}

fn map(branch: ElbowBranch, sign: Theta2Sign, grid: usize) -> ModeMap {
    compute(MU, V, branch, sign, (-90.0, 90.0), (-10.0, 10.0), grid).unwrap()
}

#[test]
fn every_point_is_on_the_belt_and_classified_by_independent_b_and_p() {
    for (branch, sign) in [
        (ElbowBranch::Down, Theta2Sign::Auto),
        (ElbowBranch::Up, Theta2Sign::Auto),
        (ElbowBranch::Down, Theta2Sign::Plus),
        (ElbowBranch::Up, Theta2Sign::Minus),
    ] {
        let m = map(branch, sign, 101);
        let pr = m.params;
        let mut contact = 0;
        for (i, &t1) in m.theta1.iter().enumerate() {
            for (j, &w1) in m.theta1_dot.iter().enumerate() {
                let pt = m.at(i, j).unwrap();
                let PointMode::Contact(mode) = pt.mode else { continue };
                contact += 1;
                let (t2, w2) = (pt.theta2, pt.theta2_dot);
                // On the belt, moving along it, on the branch.
                assert!((-pr.l * (t1.cos() + t2.cos()) + pr.h).abs() < 1e-12);
                assert!((pr.l * (t1.sin() * w1 + t2.sin() * w2)).abs() < 1e-12 * (1.0 + w1.abs()));
                if sign == Theta2Sign::Auto {
                    assert!(t2 - t1 == 0.0 || ElbowBranch::of(&Vector2::new(t1, t2)) == branch);
                } else {
                    assert_eq!(t2.signum(), sign.sign(branch));
                }
                // z_r_dot.
                let zr = pr.l * (t1.cos() * w1 + t2.cos() * w2) - V;
                assert!((zr - pt.z_r_dot).abs() < 1e-12 * (1.0 + zr.abs()));
                // b and p from scratch.
                let (b, p) = independent_b_p(&pr, t1, t2, w1, w2, if zr < 0.0 { -1.0 } else { 1.0 });
                assert!((b - pt.b).abs() < 1e-9 * (1.0 + b.abs()), "b {b} vs {}", pt.b);
                assert!((p - pt.p).abs() < 1e-9 * (1.0 + p.abs()), "p {p} vs {}", pt.p);
                // The mode follows docs/model.md's table of signs.
                match mode {
                    ContactMode::Sliding => assert!(p > 0.0 && b < 0.0),
                    ContactMode::Flight => assert!(p > 0.0 && b >= 0.0),
                    ContactMode::Indeterminate => assert!(p <= 0.0 && b >= 0.0),
                    ContactMode::Inconsistent => assert!(p <= 0.0 && b < 0.0),
                    ContactMode::Sticking => panic!("sticking is not part of the slipping map"),
                }
            }
        }
        assert!(contact > 0, "{branch:?} {sign:?}: no point on the belt");
    }
}

#[test]
fn reachability_follows_the_geometry() {
    let pr = Params::<f64>::paper();
    let th_max = (pr.h / pr.l - 1.0).acos(); // 37.1 deg: theta2 = 0.
    let th_straight = (pr.h / (2.0 * pr.l)).acos(); // 25.98 deg: theta2 = theta1.
    let m = map(ElbowBranch::Down, Theta2Sign::Auto, 181);
    for (i, &t1) in m.theta1.iter().enumerate() {
        let mode = m.at(i, 7).unwrap().mode;
        if t1.abs() > th_max + 1e-9 || t1 < -th_straight - 1e-9 {
            assert_eq!(mode, PointMode::Unreachable, "theta1 = {} deg", t1.to_degrees());
        } else if t1.abs() < th_max - 1e-3 && t1 > -th_straight + 1e-9 {
            assert!(matches!(mode, PointMode::Contact(_)), "theta1 = {} deg: {mode:?}", t1.to_degrees());
        }
    }
    // The paper's initial conditions sit on the sheets the docs say. They are
    // rounded (docs/model.md: the tip is a fraction of a millimetre inside the belt), and
    // near theta2 = 0, theta2 is sensitive to theta1 (x0u: -11.63 deg here), so the
    // tolerance is 0.5 deg; the tips then agree to about a millimetre.
    let d = |x: f64| x.to_radians();
    for (name, t1, t2_paper, branch, sign) in [
        ("x0d", -11.4, -35.1, ElbowBranch::Down, Theta2Sign::Auto),
        ("x0d", -11.4, -35.1, ElbowBranch::Down, Theta2Sign::Minus),
        ("x0a", 32.0, 18.27, ElbowBranch::Down, Theta2Sign::Plus),
        ("x0u", -35.1, -11.4, ElbowBranch::Up, Theta2Sign::Minus),
    ] {
        let t2 = belt_theta2(&pr, d(t1), branch, sign).unwrap();
        assert!((t2.to_degrees() - t2_paper).abs() < 0.5, "{name}: theta2 = {} deg", t2.to_degrees());
        let ours = shared::kinematics::tip_position(pr.l, &Vector2::new(d(t1), t2));
        let paper = shared::kinematics::tip_position(pr.l, &Vector2::new(d(t1), d(t2_paper)));
        assert!((ours - paper).norm() < 1.5e-3, "{name}: tip {ours:?} vs {paper:?}");
        assert_eq!(ElbowBranch::of(&Vector2::new(d(t1), t2)), branch, "{name}");
    }
    assert!(belt_theta2(&pr, d(-35.1), ElbowBranch::Down, Theta2Sign::Auto).is_none());
    assert!(belt_theta2(&pr, f64::NAN, ElbowBranch::Down, Theta2Sign::Auto).is_none());
    // Singular: theta2 = 0 exactly at theta1 = th_max.
    let pt = evaluate_point(&Arm::new(pr), th_max, 1.0, ElbowBranch::Down, Theta2Sign::Auto);
    assert_eq!(pt.mode, PointMode::Singular);
}

#[test]
fn b_zero_curve_points_have_b_zero() {
    for sign in [Theta2Sign::Auto, Theta2Sign::Plus] {
        let m = map(ElbowBranch::Down, sign, 200);
        let arm = Arm::new(m.params);
        let pts: Vec<_> = m.b_zero.iter().flatten().collect();
        assert!(pts.len() > 100, "{sign:?}: only {} points on b = 0", pts.len());
        for &&(deg, w) in &pts {
            let t = deg.to_radians();
            let b = |t: f64, w: f64| evaluate_point(&arm, t, w, m.branch, m.sign).b;
            // b is O(10) m/s^2 and its slopes O(10^3) per rad: bisection to 1e-12 leaves |b| ~ 1e-9.
            assert!(b(t, w).abs() < 1e-7, "b({deg}, {w}) = {}", b(t, w));
            // and b changes sign across it, along theta1 or along theta1_dot.
            let h = 1e-7;
            assert!(b(t - h, w) * b(t + h, w) < 0.0 || b(t, w - h) * b(t, w + h) < 0.0, "no sign change at ({deg}, {w})");
        }
        // The curve separates the grid: neighbours across it have b of opposite signs,
        // and every sign change between on-belt neighbours has a curve point between them.
        let n2 = m.theta1_dot.len();
        for i in 0..m.theta1.len() {
            for j in 0..n2 - 1 {
                let (a, c) = (m.at(i, j).unwrap(), m.at(i, j + 1).unwrap());
                if matches!(a.mode, PointMode::Contact(_)) && matches!(c.mode, PointMode::Contact(_)) && (a.b > 0.0) != (c.b > 0.0) {
                    let deg = m.theta1[i].to_degrees();
                    let found = pts.iter().any(|&&(d, w)| d == deg && w >= m.theta1_dot[j] && w <= m.theta1_dot[j + 1]);
                    let border = i == 0
                        || i + 1 == m.theta1.len()
                        || !matches!(m.at(i - 1, j).unwrap().mode, PointMode::Contact(_))
                        || !matches!(m.at(i + 1, j).unwrap().mode, PointMode::Contact(_));
                    assert!(found || border, "{sign:?}: missed b = 0 at theta1 = {deg}, row {j}");
                }
            }
        }
    }
}

#[test]
fn p_zero_is_a_zero_of_p_and_bounds_the_p_sign_on_the_grid() {
    let m = map(ElbowBranch::Down, Theta2Sign::Auto, 200);
    let arm = Arm::new(m.params);
    assert!(!m.p_zero.is_empty(), "mu = 0.6 should have a zero of p on the elbow-down map");
    for z in &m.p_zero {
        let t = z.theta1_deg.to_radians();
        let p = |x: f64| p_of_theta1(&arm, x, m.branch, m.sign, z.dir);
        assert!(p(t).abs() < 1e-8, "p = {}", p(t));
        assert!(p(t - 1e-7) * p(t + 1e-7) < 0.0);
        // Over its window, z_r_dot has the direction dir.
        if let Some([a, b]) = z.theta1_dot_range {
            for w in [a + 1e-9 * (b - a), 0.5 * (a + b), b - 1e-9 * (b - a)] {
                let pt = evaluate_point(&arm, t, w, m.branch, m.sign);
                assert_eq!(SlipDirection::of(pt.z_r_dot), z.dir);
            }
        }
    }
    // Grid points on either side of a zero carry p of opposite signs (same direction).
    for (i, &t1) in m.theta1.iter().enumerate() {
        for (j, _) in m.theta1_dot.iter().enumerate().step_by(17) {
            let pt = m.at(i, j).unwrap();
            if let PointMode::Contact(_) = pt.mode {
                let dir = SlipDirection::of(pt.z_r_dot);
                let expect_pos = p_of_theta1(&arm, t1, m.branch, m.sign, dir) > 0.0;
                assert_eq!(pt.p > 0.0, expect_pos);
            }
        }
    }
}

#[test]
fn z_r_dot_zero_curve_is_where_z_r_dot_vanishes() {
    let m = map(ElbowBranch::Down, Theta2Sign::Auto, 150);
    let arm = Arm::new(m.params);
    let n: usize = m.zr_zero.iter().map(Vec::len).sum();
    assert!(n > 0);
    for &(deg, w) in m.zr_zero.iter().flatten() {
        let pt = evaluate_point(&arm, deg.to_radians(), w, m.branch, m.sign);
        assert!(pt.z_r_dot.abs() < 1e-12, "{}", pt.z_r_dot);
    }
}

#[test]
fn counts_add_up_and_the_map_has_the_paper_modes() {
    let m = map(ElbowBranch::Down, Theta2Sign::Auto, 120);
    let counts = m.counts();
    assert_eq!(counts.iter().map(|(_, c)| c).sum::<usize>(), 120 * 120);
    let get = |mode| counts.iter().find(|(m, _)| *m == mode).unwrap().1;
    assert!(get(PointMode::Contact(ContactMode::Sliding)) > 0);
    assert!(get(PointMode::Contact(ContactMode::Flight)) > 0);
    assert!(get(PointMode::Unreachable) > 0);
}

#[test]
fn polylines_join_equal_root_counts() {
    let cols = vec![(0.0, vec![1.0]), (1.0, vec![2.0]), (2.0, vec![]), (3.0, vec![1.0, 5.0]), (4.0, vec![2.0, 4.0])];
    let l = polylines(&cols);
    assert_eq!(l, vec![vec![(0.0, 1.0), (1.0, 2.0)], vec![(3.0, 1.0), (4.0, 2.0)], vec![(3.0, 5.0), (4.0, 4.0)]]);
}
