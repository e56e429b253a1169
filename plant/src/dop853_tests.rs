//! Tests of the integrator ([`super`]): its tableau, its orders of convergence
//! and of dense output, step-size control with FSAL, lazy dense stages, an event
//! located on the dense output, its limits and any state size.

use std::cell::Cell;

use super::*;

/// Two uncoupled oscillators and a decay, `y = [cos t, -sin t, sin 2t, 2 cos 2t, e^-t, t]`.
struct Test {
    evals: Cell<usize>,
}

impl OdeSystem<6> for Test {
    fn rhs(&self, _t: f64, y: &State<6>, dy: &mut State<6>) {
        self.evals.set(self.evals.get() + 1);
        *dy = [y[1], -y[0], y[3], -4.0 * y[2], -y[4], 1.0];
    }
}

fn exact(t: f64) -> State<6> {
    [t.cos(), -t.sin(), (2.0 * t).sin(), 2.0 * (2.0 * t).cos(), (-t).exp(), t]
}

fn max_err(a: &State<6>, b: &State<6>) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

fn sys() -> Test {
    Test { evals: Cell::new(0) }
}

/// Sums of the rows of `A` equal the nodes `c`; the weights are consistent.
#[test]
fn tableau_is_consistent() {
    use tableau::*;
    let rows: [(&[f64], f64); 14] = [
        (&[A21], C2),
        (&[A31, A32], C3),
        (&[A41, A43], C4),
        (&[A51, A53, A54], C5),
        (&[A61, A64, A65], C6),
        (&[A71, A74, A75, A76], C7),
        (&[A81, A84, A85, A86, A87], C8),
        (&[A91, A94, A95, A96, A97, A98], C9),
        (&[A101, A104, A105, A106, A107, A108, A109], C10),
        (&[A111, A114, A115, A116, A117, A118, A119, A1110], C11),
        (&[A121, A124, A125, A126, A127, A128, A129, A1210, A1211], 1.0),
        (&[A141, A147, A148, A149, A1410, A1411, A1412, A1413], C14),
        (&[A151, A156, A157, A158, A1511, A1512, A1513, A1514], C15),
        (&[A161, A166, A167, A168, A169, A1613, A1614, A1615], C16),
    ];
    for (i, (row, c)) in rows.iter().enumerate() {
        let sum: f64 = row.iter().sum();
        assert!((sum - c).abs() < 1e-14, "row {i}: {sum} vs {c}");
    }
    let b = [B1, B6, B7, B8, B9, B10, B11, B12];
    assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    assert!(([ER1, ER6, ER7, ER8, ER9, ER10, ER11, ER12].iter().sum::<f64>()).abs() < 1e-14);
    // The 3rd-order estimate b - bhh: bhh is itself a quadrature rule.
    assert!((BHH1 + BHH2 + BHH3 - 1.0).abs() < 1e-14);
    // The dense rows vanish on constants (the interpolant's corrections).
    for d in D {
        assert!(d.iter().sum::<f64>().abs() < 1e-12, "{d:?}");
    }
}

/// The global error of fixed steps falls as `h^8`.
#[test]
fn eighth_order_convergence() {
    let err = |h: f64| {
        let m = Dop853 { h_max: h, ..Dop853::new(1e-2, 1e-2) };
        let s = sys();
        let r = m.solve(&s, 0.0, &exact(0.0), None, 2.0, h, |_| Control::Continue).unwrap();
        assert_eq!(r.rejected, 0);
        assert_eq!(r.accepted, (2.0 / h).round() as usize);
        max_err(&r.y, &exact(2.0))
    };
    let (e1, e2) = (err(0.2), err(0.1));
    let order = (e1 / e2).log2();
    assert!(order > 7.5 && order < 9.0, "observed order {order} ({e1:e}, {e2:e})");
}

/// The dense output's error inside a step falls as `h^8` (a 7th-order interpolant).
#[test]
fn dense_output_is_seventh_order() {
    let err = |h: f64| {
        let m = Dop853 { h_max: h, ..Dop853::new(1e-2, 1e-2) };
        let s = sys();
        let mut worst: f64 = 0.0;
        m.solve(&s, 0.0, &exact(0.0), None, h, h, |step| {
            for j in 1..10 {
                let t = step.t_prev() + h * j as f64 / 10.0;
                worst = worst.max(max_err(&step.interpolate(t), &exact(t)));
            }
            // The ends are the step's values.
            assert!(max_err(&step.interpolate(step.t_curr()), step.y_curr()) < 1e-15);
            assert!(max_err(&step.interpolate(step.t_prev()), step.y_prev()) < 1e-15);
            Control::Continue
        })
        .unwrap();
        worst
    };
    let (e1, e2) = (err(0.4), err(0.2));
    let order = (e1 / e2).log2();
    assert!(order > 7.0 && order < 9.5, "observed local order {order} ({e1:e}, {e2:e})");
}

/// Tolerance control: the error follows the tolerance; 12 evaluations per
/// accepted step (11 stages and the FSAL stage) plus one per rejected step's 11.
#[test]
fn adaptive_solve_meets_the_tolerance_with_fsal() {
    for rtol in [1e-6, 1e-9, 1e-12] {
        let m = Dop853::new(rtol, rtol);
        let s = sys();
        let r = m.solve(&s, 0.0, &exact(0.0), None, 10.0, 0.0, |_| Control::Continue).unwrap();
        let e = max_err(&r.y, &exact(10.0));
        assert!(e < 100.0 * rtol, "rtol {rtol}: error {e:e}");
        // 1 for f0, 1 for HINIT, then 11 + 1 per accepted and 11 per rejected step.
        assert_eq!(s.evals.get(), 2 + 12 * r.accepted + 11 * r.rejected, "rtol {rtol}");
        assert!(r.h_next > 0.0);
    }
}

/// Dense output is evaluated only when asked for: 3 extra stages per step that uses it.
#[test]
fn dense_stages_are_lazy() {
    let m = Dop853::new(1e-9, 1e-9);
    let s = sys();
    let mut interpolated = 0;
    let r = m
        .solve(&s, 0.0, &exact(0.0), Some(&[0.0, -1.0, 2.0, 0.0, -1.0, 1.0]), 5.0, 0.1, |step| {
            if step.t_curr() > 2.0 && interpolated < 2 {
                interpolated += 1;
                let t = 0.5 * (step.t_prev() + step.t_curr());
                step.interpolate(t);
                step.interpolate(t);
            }
            Control::Continue
        })
        .unwrap();
    assert_eq!(s.evals.get(), 12 * r.accepted + 11 * r.rejected + 3 * 2);
}

/// A ballistic hop located on the dense output: `y'' = -10`, `y(0) = 0`,
/// `y'(0) = 1` returns to 0 at exactly 0.2 s; stopping ends the solve at that step.
#[test]
fn stop_and_locate_a_ballistic_hop() {
    struct Hop;
    impl OdeSystem<6> for Hop {
        fn rhs(&self, _t: f64, y: &State<6>, d: &mut State<6>) {
            *d = [y[1], -10.0, 0.0, 0.0, 0.0, 0.0];
        }
    }
    let m = Dop853::new(1e-9, 1e-11);
    let mut found = None;
    let r = m
        .solve(&Hop, 0.0, &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0], None, 1.0, 0.05, |step| {
            if step.y_curr()[0] <= 0.0 && step.y_prev()[0] > 0.0 {
                let (mut a, mut b) = (step.t_prev(), step.t_curr());
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if step.interpolate(m)[0] > 0.0 { a = m } else { b = m }
                }
                found = Some(b);
                return Control::Stop;
            }
            Control::Continue
        })
        .unwrap();
    assert!(r.stopped && r.t < 1.0);
    assert!((found.unwrap() - 0.2).abs() < 1e-13, "{found:?}");
}

/// Step control: `h_max` is respected; too few steps is an error, not a hang.
#[test]
fn limits() {
    let m = Dop853 { h_max: 0.01, ..Dop853::new(1e-6, 1e-6) };
    let s = sys();
    let mut widest: f64 = 0.0;
    m.solve(&s, 0.0, &exact(0.0), None, 1.0, 1.0, |step| {
        widest = widest.max(step.t_curr() - step.t_prev());
        Control::Continue
    })
    .unwrap();
    assert!(widest <= 0.01 * (1.0 + 1e-12));
    let m = Dop853 { max_steps: 5, ..Dop853::new(1e-12, 1e-12) };
    assert!(matches!(m.solve(&s, 0.0, &exact(0.0), None, 100.0, 0.0, |_| Control::Continue), Err(SolveError::MaxSteps { .. })));
    // A derivative that is NaN: every step is rejected until the step is too small.
    struct Bad;
    impl OdeSystem<6> for Bad {
        fn rhs(&self, _t: f64, _y: &State<6>, d: &mut State<6>) {
            *d = [f64::NAN; 6];
        }
    }
    let m = Dop853::new(1e-9, 1e-9);
    let r = m.solve(&Bad, 1.0, &[0.0; 6], None, 2.0, 0.1, |_| Control::Continue);
    assert!(matches!(r, Err(SolveError::StepSizeTooSmall { .. })), "{r:?}");
}

/// The integrator is generic over the state's size: a 2-component harmonic
/// oscillator keeps its energy and phase to the tolerance over ten periods.
#[test]
fn any_state_size() {
    struct Oscillator;
    impl OdeSystem<2> for Oscillator {
        fn rhs(&self, _t: f64, y: &State<2>, dy: &mut State<2>) {
            *dy = [y[1], -y[0]];
        }
    }
    let end = 20.0 * std::f64::consts::PI;
    let solved = Dop853::new(1e-11, 1e-13).solve(&Oscillator, 0.0, &[1.0, 0.0], None, end, 0.0, |_| Control::Continue).unwrap();
    assert_eq!(solved.t, end);
    assert!((solved.y[0] - 1.0).abs() < 1e-8 && solved.y[1].abs() < 1e-8, "{:?}", solved.y);
}

/// Quadratures outside [`OdeSystem::READ_LEN`] are summed in the solution and the
/// dense output alone: a damped oscillator with its damping's work and the time
/// integral of `x^2` as quadratures gives the same bits, step for step and in the
/// dense output, as when every stage forms them, and the work closes the energy
/// balance `E(t) - E(0) = W` to the tolerance.
#[test]
fn quadratures_outside_the_read_components() {
    /// `x'' = -x - 0.1 x'`, then `W' = -0.1 x'^2` and `Q' = x^2`.
    fn field(y: &State<4>) -> State<4> {
        [y[1], -y[0] - 0.1 * y[1], -0.1 * y[1] * y[1], y[0] * y[0]]
    }
    struct Every;
    impl OdeSystem<4> for Every {
        const NORM_LEN: usize = 2;
        fn rhs(&self, _t: f64, y: &State<4>, dy: &mut State<4>) {
            *dy = field(y);
        }
    }
    struct Read;
    impl OdeSystem<4> for Read {
        const NORM_LEN: usize = 2;
        const READ_LEN: usize = 2;
        fn rhs(&self, _t: f64, y: &State<4>, dy: &mut State<4>) {
            *dy = field(y);
        }
    }
    fn run<S: OdeSystem<4>>(sys: &S) -> (Vec<(f64, State<4>, State<4>)>, State<4>) {
        let mut steps = Vec::new();
        let solved = Dop853::new(1e-10, 1e-12)
            .solve(sys, 0.0, &[1.0, 0.0, 0.0, 0.0], None, 30.0, 0.0, |step| {
                let mid = 0.5 * (step.t_prev() + step.t_curr());
                steps.push((step.t_curr(), *step.y_curr(), step.interpolate(mid)));
                Control::Continue
            })
            .unwrap();
        (steps, solved.y)
    }
    let (every, y_every) = run(&Every);
    let (read, y_read) = run(&Read);
    assert!(every.len() > 50, "{} steps", every.len());
    assert_eq!(every.len(), read.len());
    let bits = |y: &State<4>| y.map(f64::to_bits);
    for ((t, y, m), (t2, y2, m2)) in every.iter().zip(&read) {
        assert_eq!(t.to_bits(), t2.to_bits());
        assert_eq!(bits(y), bits(y2), "at t = {t}");
        assert_eq!(bits(m), bits(m2), "dense output before t = {t}");
    }
    assert_eq!(bits(&y_every), bits(&y_read));
    let energy = |y: &State<4>| 0.5 * (y[0] * y[0] + y[1] * y[1]);
    let residual = energy(&y_read) - energy(&[1.0, 0.0, 0.0, 0.0]) - y_read[2];
    assert!(residual.abs() < 1e-9, "balance misses by {residual:e} J");
    assert!(y_read[2] < -0.4 && y_read[3] > 1.0, "{y_read:?}");
}
