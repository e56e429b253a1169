//! The location of a segment's event on the dense output ([`EventLocator`], the
//! step callback of a solve, with the energy ledger's checks that reject a step),
//! and the Illinois root search it runs ([`illinois_root`], also the Poincare
//! section's).

use shared::kinematics::JointTrig;

use super::{OdeState, Phase, STATE_LEN, Segment, nearest};
use crate::{
    controller::Controller,
    dop853::{Control, StepView},
};

/// The step callback that locates this segment's event and keeps the energy
/// ledger's checks.
///
/// The detection is the standard one: a sign change of the event function (the
/// nearest boundary's component) from positive to non-positive across an accepted
/// step, then a bracketing root search (Illinois regula falsi, safeguarded by
/// bisection) on the step's 7th-order dense output, to `1e-14 s + 1e-15 |t|`.
///
/// Three checks can reject a step DOP853 accepted ([`Control::Reject`]: it is taken
/// again at a quarter of its size), so that no state is kept from a step that is
/// not a solution of its mode (issue 53):
/// - its energy balance ([`Segment::balance`]) misses by more than its tolerance;
/// - a slide ends it with `p < 0` and `b < 0`: the step crossed the pole of
///   `f_n = -b/p` at `p = 0` (the force is negative at its end, and its dense output
///   between the ends is no solution);
/// - the located event is no root (`|g| > ` [`ROOT_TOLERANCE`] there) or breaks the
///   balance from the step's start to it.
///
/// A step that cannot be mended collapses, and the plant resolves the collapse
/// from the last accepted point (docs/plant.md "The singular point").
pub struct EventLocator<'s, 'a, C: ?Sized> {
    /// The segment (its event function).
    pub segment: &'s Segment<'a, C>,
    /// Event function at the previous accepted point (at the start: its value at `t0`).
    pub g_prev: f64,
    /// The located event `(t, y)`, if any.
    pub hit: Option<(f64, OdeState)>,
    /// The last accepted point `(t, y)` (none before the first step).
    pub last: Option<(f64, OdeState)>,
    /// The arm's energy at the previous accepted point, J (NaN: not yet known; a
    /// caller that knows it at the solve's start may set it).
    pub e_prev: f64,
    /// The sines and cosines of the angles of [`EventLocator::last`] (NaN before the first step).
    pub trig_last: JointTrig<f64>,
    /// The ledger of the accepted steps: largest residual (J) and ratio to its tolerance.
    pub worst: (f64, f64),
    /// Steps rejected by the checks above.
    pub rejected: u64,
    /// While sliding: the slide's force on its approach to `p = 0` ([`Trend`]).
    pub trend: Option<Trend>,
}

/// A slide's force on its approach to `p = 0`: the normal force at the last accepted
/// point whose `p / Q_22` is at least [`TREND_P`], before the integration's residue of
/// `b` dominates `-b/p`, and that point's `p / Q_22`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trend {
    /// The normal force `f_n = -b/p`, N.
    pub f_n: f64,
    /// `p / Q_22` there (dimensionless, at least [`TREND_P`]).
    pub p: f64,
}

/// Event-function magnitude that counts as on the boundary (rounding after a
/// projection): the same margin [`crate::Plant`] allows at a segment's end.
const ON_BOUNDARY: f64 = 1e-9;

/// The largest `|g|` (dimensionless, the event components' scale) at a located
/// event: the root search brackets the crossing to `1e-14 s`, where a continuous
/// event function is within about 1e-9 of 0 (the largest measured over the
/// reproducer of issue 53 outside the pole crossings was below 1e-7); a
/// located "root" across a discontinuity (the pole of `-b/p`) is far from it
/// (-2428 in issue 53).
pub const ROOT_TOLERANCE: f64 = 1e-6;

/// The `p / Q_22` down to which a slide's normal force shows its trend
/// ([`EventLocator::trend`]): below it the integration's residue in `b` (about
/// 1e-9 m/s^2) can dominate `f_n = -b/p` (issue 53: 1.4e3 N at `p / Q_22 = 6.5e-13`
/// where the slide's force tends to 4.2 N).
pub const TREND_P: f64 = 1e-6;

impl<'s, 'a, C: Controller + ?Sized> EventLocator<'s, 'a, C> {
    /// A locator for a solve of `segment` starting where the event function is `g0`.
    pub fn new(segment: &'s Segment<'a, C>, g0: f64) -> Self {
        let trig_last = JointTrig { s1: f64::NAN, c1: f64::NAN, s2: f64::NAN, c2: f64::NAN };
        Self { segment, g_prev: g0, hit: None, last: None, e_prev: f64::NAN, trig_last, worst: (0.0, 0.0), rejected: 0, trend: None }
    }

    /// Checks one accepted step for a crossing and locates it; stops the solve at an
    /// event, rejects a step that fails a check (type docs).
    pub fn on_step(&mut self, step: &mut StepView<'_, Segment<'a, C>, STATE_LEN>) -> Control {
        let (t_prev, t_curr) = (step.t_prev(), step.t_curr());
        let y_prev = *step.y_prev();
        let y_curr = *step.y_curr();
        let seg = self.segment;
        let e_prev = if self.e_prev.is_nan() { seg.energy(&y_prev) } else { self.e_prev };
        let (e_curr, residual, tol, trig_curr) = seg.energy_and_balance_trig(&y_prev, e_prev, &y_curr);
        // NaN breaks the balance too.
        if residual.abs() > tol || residual.is_nan() {
            self.rejected += 1;
            return Control::Reject;
        }
        let (components, f_n) = seg.end_components(t_curr, &y_curr);
        let sliding = matches!(seg.phase, Phase::Sliding(_));
        // p < 0 with b < 0 at the end of a slide: the pole of -b/p was stepped over.
        if sliding && components[1].1 < 0.0 && components[0].1 > 0.0 {
            self.rejected += 1;
            return Control::Reject;
        }
        let g_curr = nearest(components).1;
        let g_a = self.g_prev;
        // A segment that starts on its boundary (g = 0 to rounding, e.g. flight right
        // after a lift-off) and leaves its domain in the first step has no sign
        // change from a positive value: it counts as a crossing near the start.
        let from_the_boundary = g_a > -ON_BOUNDARY && g_curr < -ON_BOUNDARY;
        if ((g_a > 0.0 && g_curr <= 0.0) || from_the_boundary) && t_curr > t_prev {
            let (t_hit, y_hit) = locate_root(seg, step, (t_prev, g_a.max(f64::MIN_POSITIVE)), (t_curr, g_curr, y_curr));
            let g_hit = if t_hit.to_bits() == t_curr.to_bits() { g_curr } else { seg.nearest_boundary(t_hit, &y_hit).1 };
            let (_, r_hit, tol_hit) = seg.energy_and_balance(&y_prev, e_prev, &y_hit);
            // A crossing from the boundary may sit anywhere in (-ON_BOUNDARY, 0].
            let root = g_hit.abs() <= ROOT_TOLERANCE || (from_the_boundary && g_hit > -ON_BOUNDARY);
            if !(root && r_hit.abs() <= tol_hit) {
                self.rejected += 1;
                return Control::Reject;
            }
            self.note_balance(residual.abs().max(r_hit.abs()), (residual.abs() / tol).max(r_hit.abs() / tol_hit));
            (self.last, self.g_prev, self.e_prev, self.trig_last) = (Some((t_curr, y_curr)), g_curr, e_curr, trig_curr);
            self.hit = Some((t_hit, y_hit));
            return Control::Stop;
        }
        self.note_balance(residual.abs(), residual.abs() / tol);
        if sliding && components[1].1 >= TREND_P {
            self.trend = Some(Trend { f_n, p: components[1].1 });
        }
        (self.last, self.g_prev, self.e_prev, self.trig_last) = (Some((t_curr, y_curr)), g_curr, e_curr, trig_curr);
        Control::Continue
    }

    fn note_balance(&mut self, residual: f64, ratio: f64) {
        self.worst = (self.worst.0.max(residual), self.worst.1.max(ratio));
    }
}

/// Illinois regula falsi with bisection safeguard on the dense output:
/// the first zero of the event function in `(a, b]`, given `g(a) > 0 >= g(b)`.
fn locate_root<'a, C: Controller + ?Sized>(
    seg: &Segment<'a, C>,
    step: &mut StepView<'_, Segment<'a, C>, STATE_LEN>,
    a: (f64, f64),
    b: (f64, f64, OdeState),
) -> (f64, OdeState) {
    let t_end = b.0;
    // The iterates in the components the event function reads (it reads no
    // quadrature); strictly inside the step, so never its end, whose event
    // components `nearest_boundary` may take from the end's evaluation.
    let (t, y) = illinois_root(
        a,
        b,
        |t| {
            let y = step.interpolate_read(t);
            (seg.nearest_boundary(t, &y).1, y)
        },
        |g| g > 0.0,
        false,
    );
    // The root's state in every component: the dense output there (the step's end
    // as given when the search never moved it).
    if t.to_bits() == t_end.to_bits() { (t, y) } else { (t, step.interpolate(t)) }
}

/// Illinois regula falsi with a bisection safeguard: the crossing of `g` in
/// `(a.0, b.0]` to `1e-14 s + 1e-15 |t|`, with the state there, where `eval(t)`
/// gives `g` and the state at `t` (from a step's dense output), `a` is the end on
/// the `before(g)` side and `b` the other. With `stop_at_zero`, an exact zero
/// ends the search at once; without, the search goes on towards the first zero.
/// Used by the plant's event location and by the Poincare section.
pub fn illinois_root(
    a: (f64, f64),
    b: (f64, f64, OdeState),
    mut eval: impl FnMut(f64) -> (f64, OdeState),
    before: impl Fn(f64) -> bool,
    stop_at_zero: bool,
) -> (f64, OdeState) {
    let (mut ta, mut ga) = a;
    let (mut tb, mut gb, mut yb) = b;
    if stop_at_zero && gb == 0.0 {
        return (tb, yb);
    }
    let tol = 1e-14 + 1e-15 * tb.abs();
    let mut side = 0i8;
    for iter in 0..200 {
        if tb - ta <= tol {
            break;
        }
        // Regula falsi point, kept away from the ends; bisect every 4th iteration
        // or when the secant falls outside the bracket.
        let mut t = tb - gb * (tb - ta) / (gb - ga);
        if !(t > ta && t < tb) || iter % 4 == 3 {
            t = 0.5 * (ta + tb);
        }
        let (g, y) = eval(t);
        // Illinois rule: an end retained twice in a row has its value halved.
        if before(g) {
            ta = t;
            ga = g;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        } else {
            tb = t;
            gb = g;
            yb = y;
            if stop_at_zero && g == 0.0 {
                break;
            }
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        }
    }
    (tb, yb)
}
