//! Poincaré sections watched by the plant while it integrates: the upward
//! crossings of a hyperplane `g(x) = n . x - c = 0` of the state
//! `x = [theta1, theta1_dot, theta2, theta2_dot]`, located inside the integrator's
//! steps on its 7th-order dense output (not at samples), and the crossings made
//! by a jump of the state at an impact.
//!
//! A crossing is `g` going from negative to non-negative:
//! - in the flow, a sign change across an accepted step is refined by a bracketing
//!   root search (Illinois regula falsi with bisection) on the dense output, to
//!   `1e-14 s + 1e-15 |t|`; a step whose ends are both negative but where `g`
//!   rises then falls (`g' > 0` at the start, `< 0` at the end, from the vector
//!   field) is searched for an interior maximum (golden section on the dense
//!   output), so a brief excursion above the section inside one step is not missed;
//! - at an impact (an impulse changes `theta1_dot` at one instant), a state that
//!   was negative before and is non-negative after is a crossing at the impact
//!   time ([`CrossingKind::Jump`]).
//!
//! Hysteresis: with a depth `delta > 0` an upward crossing counts only if `g`
//! went below `-delta` since the last counted one (seen at step ends, at jumps
//! and at the minimum of a dip), so that rounding noise around an equilibrium on
//! the section (steady sliding has `theta1_dot = 0` to about 1e-11 rad/s) does
//! not make crossings.
//!
//! Not detected: three or more crossings inside one integration step (steps of the
//! plant's DOP853 are a small fraction of the arm's oscillation period at the
//! default tolerances); a jump that starts exactly on the section.
//!
//! Only the crossings of solves the plant keeps are reported: a solve that is
//! repeated with smaller steps (the plant's missed-event guard) reports its
//! crossings once.

use serde::Serialize;
use shared::ContactMode;

use plant::{
    Observer,
    dop853::DenseStep,
    segment::{OdeState, STATE_LEN, illinois_root},
};

/// The hyperplane `g(x) = normal . x - offset` of the plant state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Section {
    /// Normal `n` over `[theta1, theta1_dot, theta2, theta2_dot]`.
    pub normal: [f64; 4],
    /// Offset `c` (units of `n . x`).
    pub offset: f64,
}

impl Section {
    /// `theta1_dot = 0`, crossed from negative to positive: the section of the
    /// paper's Fig. 4 (docs/model.md experiment 4).
    pub const THETA1_DOT: Self = Self { normal: [0.0, 1.0, 0.0, 0.0], offset: 0.0 };

    /// `g(x)` of a state whose first four components are the plant state.
    #[inline]
    pub fn value(&self, x: &[f64]) -> f64 {
        self.normal.iter().zip(x).map(|(n, v)| n * v).sum::<f64>() - self.offset
    }

    /// `dg/dt` from the state's time derivative (first four components).
    #[inline]
    pub fn rate(&self, dxdt: &[f64]) -> f64 {
        self.normal.iter().zip(dxdt).map(|(n, v)| n * v).sum()
    }
}

/// How a crossing happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CrossingKind {
    /// In the smooth flow, located on the dense output.
    Flow,
    /// By the jump of the state at an impact (time of the impact, state after it).
    Jump,
}

impl CrossingKind {
    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Flow => "flow",
            Self::Jump => "jump",
        }
    }
}

/// One upward crossing of the section.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SectionCrossing {
    /// Time, s.
    pub t: f64,
    /// State `[theta1, theta1_dot, theta2, theta2_dot]` at the crossing (rad, rad/s).
    pub x: [f64; 4],
    /// Flow or jump.
    pub kind: CrossingKind,
    /// Contact mode at the crossing (after the jump for [`CrossingKind::Jump`]).
    pub mode: ContactMode,
}

/// A section and the crossings found so far: an [`Observer`] of the plant's
/// advances (`plant.advance(&Hold(u), dt, &mut watch)`).
#[derive(Debug, Clone)]
pub struct SectionWatch {
    section: Section,
    /// `g` at the last point seen (the end of the last kept solve or the last jump).
    last: Option<f64>,
    /// Hysteresis depth (units of `g`).
    depth: f64,
    /// `g` went below `-depth` since the last counted crossing.
    armed: bool,
    crossings: Vec<SectionCrossing>,
    /// The scan of the current attempt (kept by [`Observer::on_kept`]).
    pending: Option<StepScan>,
}

impl Observer for SectionWatch {
    fn on_segment_start(&mut self, t: f64, y: &OdeState, mode: ContactMode) {
        self.observe_start(t, y, mode);
    }

    fn on_attempt(&mut self) {
        self.pending = Some(self.scan());
    }

    fn on_step(&mut self, step: &mut dyn DenseStep<STATE_LEN>, stop: Option<(f64, OdeState)>, _mode: ContactMode) {
        if let Some(scan) = self.pending.as_mut() {
            scan.on_step(step, stop);
        }
    }

    fn on_kept(&mut self, y_end: &OdeState, mode: ContactMode) {
        if let Some(scan) = self.pending.take() {
            self.commit(scan, y_end, mode);
        }
    }
}

impl SectionWatch {
    /// Watches `section`, with no crossings yet and no hysteresis.
    pub fn new(section: Section) -> Self {
        Self::with_hysteresis(section, 0.0)
    }

    /// Watches `section` with hysteresis depth `depth` (>= 0, units of `g`; see the
    /// module docs): the first crossing counts only after `g < -depth` has been seen.
    pub fn with_hysteresis(section: Section, depth: f64) -> Self {
        Self { section, last: None, depth: depth.max(0.0), armed: false, crossings: Vec::new(), pending: None }
    }

    /// The watched section.
    pub fn section(&self) -> &Section {
        &self.section
    }

    /// The crossings found, in time order.
    pub fn crossings(&self) -> &[SectionCrossing] {
        &self.crossings
    }

    /// Removes and returns the crossings found so far (the watch goes on).
    pub fn take(&mut self) -> Vec<SectionCrossing> {
        std::mem::take(&mut self.crossings)
    }

    /// Forgets the last point seen: the next point is a fresh start, never the end of a jump.
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// Sees the state at the start of a smooth segment: a crossing if `g` was
    /// negative at the last point seen and is non-negative now (a jump).
    pub(super) fn observe_start(&mut self, t: f64, y: &OdeState, mode: ContactMode) {
        let g = self.section.value(y);
        if let Some(last) = self.last {
            self.armed |= last < -self.depth;
            if last < 0.0 && g >= 0.0 && self.armed {
                self.crossings.push(SectionCrossing { t, x: plant_state(y), kind: CrossingKind::Jump, mode });
                self.armed = false;
            }
        }
        self.armed |= g < -self.depth;
        self.last = Some(g);
    }

    /// A scan for one solve (its crossings are kept only by [`SectionWatch::commit`]).
    pub(super) fn scan(&self) -> StepScan {
        StepScan { section: self.section, depth: self.depth, armed: self.armed, found: Vec::new() }
    }

    /// Keeps the crossings of a solve that ended at state `y_end`.
    pub(super) fn commit(&mut self, scan: StepScan, y_end: &OdeState, mode: ContactMode) {
        self.crossings.extend(scan.found.into_iter().map(|(t, y)| SectionCrossing {
            t,
            x: plant_state(&y),
            kind: CrossingKind::Flow,
            mode,
        }));
        self.armed = scan.armed;
        self.last = Some(self.section.value(y_end));
    }
}

fn plant_state(y: &OdeState) -> [f64; 4] {
    [y[0], y[1], y[2], y[3]]
}

/// The crossings found in the accepted steps of one solve.
#[derive(Debug, Clone)]
pub(super) struct StepScan {
    section: Section,
    depth: f64,
    armed: bool,
    found: Vec<(f64, OdeState)>,
}

impl StepScan {
    /// Looks for an upward crossing in one accepted step, up to `stop` (the time and
    /// state of the event that ends the segment inside this step) or its end.
    pub(super) fn on_step(&mut self, step: &mut dyn DenseStep<STATE_LEN>, stop: Option<(f64, OdeState)>) {
        let sec = self.section;
        let t_a = step.t_prev();
        let g_a = sec.value(step.y_prev());
        let (t_b, y_b, dg_b) = match stop {
            Some((t, y)) => (t, y, None),
            None => (step.t_curr(), *step.y_curr(), Some(sec.rate(step.f_curr()))),
        };
        if t_b <= t_a {
            return;
        }
        let g_b = sec.value(&y_b);
        let dg_a = sec.rate(step.f_prev());
        self.armed |= g_a < -self.depth;
        if g_a < 0.0 && g_b >= 0.0 {
            let hit = refine(&sec, step, (t_a, g_a), (t_b, g_b, y_b));
            self.count(hit);
        } else if g_a < 0.0 && g_b < 0.0 && dg_a > 0.0 && dg_b.is_none_or(|d| d < 0.0) {
            // A hump inside the step: up and down again.
            let (t_m, g_m, y_m) = extremum(&sec, step, t_a, t_b, 1.0);
            if g_m >= 0.0 {
                let hit = refine(&sec, step, (t_a, g_a), (t_m, g_m, y_m));
                self.count(hit);
            }
        } else if g_a >= 0.0 && g_b >= 0.0 && dg_a < 0.0 && dg_b.is_none_or(|d| d > 0.0) {
            // A dip inside the step: down and up again.
            let (t_m, g_m, _) = extremum(&sec, step, t_a, t_b, -1.0);
            if g_m < 0.0 {
                self.armed |= g_m < -self.depth;
                let hit = refine(&sec, step, (t_m, g_m), (t_b, g_b, y_b));
                self.count(hit);
            }
        }
        self.armed |= g_b < -self.depth;
    }

    /// Keeps a located crossing if the hysteresis allows it, and disarms.
    fn count(&mut self, hit: (f64, OdeState)) {
        if self.armed {
            self.found.push(hit);
        }
        self.armed = false;
    }
}

/// The zero of `g` in `(a, b]` given `g(a) < 0 <= g(b)`, to `1e-14 s + 1e-15 |t|`
/// (the plant's Illinois root finder on the step's dense output).
fn refine(sec: &Section, step: &mut dyn DenseStep<STATE_LEN>, a: (f64, f64), b: (f64, f64, OdeState)) -> (f64, OdeState) {
    illinois_root(
        a,
        b,
        |t| {
            let y = step.interpolate(t);
            (sec.value(&y), y)
        },
        |g| g < 0.0,
        true,
    )
}

/// Golden-section search on the dense output over `[a, b]` for the maximum of
/// `g` (`sign = 1`) or its minimum (`sign = -1`), assumed single; stopped early
/// once `g` is on the other side of the section (`>= 0` for a maximum, `< 0` for a minimum).
fn extremum(sec: &Section, step: &mut dyn DenseStep<STATE_LEN>, a: f64, b: f64, sign: f64) -> (f64, f64, OdeState) {
    const INV_PHI: f64 = 0.618_033_988_749_894_8;
    let across = |g: f64| if sign > 0.0 { g >= 0.0 } else { g < 0.0 };
    let (mut lo, mut hi) = (a, b);
    let mut x1 = hi - INV_PHI * (hi - lo);
    let mut x2 = lo + INV_PHI * (hi - lo);
    let mut y1 = step.interpolate(x1);
    let mut y2 = step.interpolate(x2);
    let (mut g1, mut g2) = (sec.value(&y1), sec.value(&y2));
    for _ in 0..80 {
        if across(g1) {
            return (x1, g1, y1);
        }
        if across(g2) {
            return (x2, g2, y2);
        }
        if hi - lo <= 1e-13 + 1e-15 * b.abs() {
            break;
        }
        if sign * g1 > sign * g2 {
            hi = x2;
            (x2, g2, y2) = (x1, g1, y1);
            x1 = hi - INV_PHI * (hi - lo);
            y1 = step.interpolate(x1);
            g1 = sec.value(&y1);
        } else {
            lo = x1;
            (x1, g1, y1) = (x2, g2, y2);
            x2 = lo + INV_PHI * (hi - lo);
            y2 = step.interpolate(x2);
            g2 = sec.value(&y2);
        }
    }
    if sign * g1 > sign * g2 { (x1, g1, y1) } else { (x2, g2, y2) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::dop853::{Control, Dop853, OdeSystem};

    /// `y = [sin t, cos t, 0, 0, 0, 0]`-like systems: component 1 is `a cos(w t)`.
    struct Oscillator {
        a: f64,
        w: f64,
    }
    impl OdeSystem<STATE_LEN> for Oscillator {
        fn rhs(&self, t: f64, _y: &OdeState, dy: &mut OdeState) {
            *dy = [self.a * (self.w * t).cos(), -self.a * self.w * (self.w * t).sin(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        }
    }

    /// Integrates `sys` from `y0` over `[0, t_end]` and returns the crossings the scan found.
    fn scan_run(sys: &Oscillator, y0: OdeState, t_end: f64, solver: Dop853, section: Section, depth: f64) -> Vec<f64> {
        let watch = SectionWatch::with_hysteresis(section, depth);
        let mut scan = watch.scan();
        scan.armed = true;
        solver
            .solve(sys, 0.0, &y0, None, t_end, 0.0, |step| {
                scan.on_step(step, None);
                Control::Continue
            })
            .unwrap();
        scan.found.iter().map(|(t, _)| *t).collect()
    }

    /// `theta1_dot = cos t` crosses 0 upward at `t = 3 pi / 2 + 2 pi k`, to rounding.
    #[test]
    fn crossings_of_a_cosine_are_exact() {
        let sys = Oscillator { a: 1.0, w: 1.0 };
        let solver = Dop853::new(1e-10, 1e-12);
        let found = scan_run(&sys, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 20.0, solver, Section::THETA1_DOT, 0.0);
        let pi = std::f64::consts::PI;
        let exact = [1.5 * pi, 3.5 * pi, 5.5 * pi];
        assert_eq!(found.len(), exact.len(), "{found:?}");
        for (t, e) in found.iter().zip(exact) {
            assert!((t - e).abs() < 1e-9, "{t} vs {e}");
        }
    }

    /// A brief rise above the section inside one step (a hump of `cos t` above
    /// 0.999, 0.09 s wide, inside the step [6, 7] of unit steps: both ends below)
    /// is found.
    #[test]
    fn a_hump_inside_one_step_is_found() {
        let sys = Oscillator { a: 1.0, w: 1.0 };
        let section = Section { normal: [0.0, 1.0, 0.0, 0.0], offset: 0.999 };
        // Loose tolerance: every step is the 1 s cap, so one step holds the whole hump.
        let solver = Dop853 { h_max: 1.0, ..Dop853::new(1e-3, 1e-3) };
        let found = scan_run(&sys, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 7.0, solver, section, 0.0);
        // cos t = 0.999 going up at t = 2 pi - acos(0.999).
        let exact = 2.0 * std::f64::consts::PI - 0.999f64.acos();
        assert_eq!(found.len(), 1, "{found:?}");
        assert!((found[0] - exact).abs() < 1e-5, "{} vs {exact}", found[0]);
    }

    /// Rounding-size oscillations about the section are not crossings with a
    /// hysteresis deeper than them, and are without.
    #[test]
    fn hysteresis_ignores_noise_on_the_section() {
        let sys = Oscillator { a: 1e-9, w: 50.0 };
        let solver = Dop853::new(1e-12, 1e-14);
        let y0 = [0.0, 1e-9, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let deep = scan_run(&sys, y0, 1.0, solver, Section::THETA1_DOT, 1e-6);
        assert!(deep.len() <= 1, "{deep:?}");
        let plain = scan_run(&sys, y0, 1.0, solver, Section::THETA1_DOT, 0.0);
        assert_eq!(plain.len(), 8, "{plain:?}");
    }
}
