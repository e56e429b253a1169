//! One accepted step of a solve ([`super::Dop853::solve`]) and its 7th-order dense
//! output: [`StepView`], as the solve's callback sees it, and [`DenseStep`], the
//! same step as an object for an observer.

use super::{OdeSystem, State, stages::dense_coefficients};

/// One accepted step, as [`Dop853::solve`](super::Dop853::solve) reports it: its ends and its dense output.
pub struct StepView<'a, S: ?Sized, const N: usize> {
    pub(super) sys: &'a S,
    pub(super) t_prev: f64,
    pub(super) t_curr: f64,
    pub(super) h: f64,
    pub(super) y_prev: &'a State<N>,
    pub(super) y_curr: &'a State<N>,
    /// Stages 1 to 12 (`k[0]` = f at the start).
    pub(super) k: &'a [State<N>],
    /// Stage 13: f at the end.
    pub(super) k_end: &'a State<N>,
    /// The dense output's coefficients, once computed.
    pub(super) cont: Option<[State<N>; 8]>,
}

impl<S: OdeSystem<N> + ?Sized, const N: usize> StepView<'_, S, N> {
    /// Start of the step, s.
    pub fn t_prev(&self) -> f64 {
        self.t_prev
    }

    /// End of the step, s.
    pub fn t_curr(&self) -> f64 {
        self.t_curr
    }

    /// State at the start.
    pub fn y_prev(&self) -> &State<N> {
        self.y_prev
    }

    /// State at the end.
    pub fn y_curr(&self) -> &State<N> {
        self.y_curr
    }

    /// `f` at the start of the step (its first stage).
    pub fn f_prev(&self) -> &State<N> {
        &self.k[0]
    }

    /// `f` at the end of the step (the FSAL stage).
    pub fn f_curr(&self) -> &State<N> {
        self.k_end
    }

    /// The 7th-order dense output at `t` (s) in `[t_prev, t_curr]` (Hairer, Nørsett
    /// and Wanner, sec. II.10, `dop853`'s `CONTD8`): `y(t)` to `O(h^8)`.
    ///
    /// The first call for a step evaluates its three extra stages.
    pub fn interpolate(&mut self, t: f64) -> State<N> {
        self.interpolate_first(t, N)
    }

    /// [`StepView::interpolate`] in the components `f` reads alone
    /// ([`OdeSystem::READ_LEN`]; the same bits there), the others left at 0: for a
    /// function of the state that reads no other, such as the plant's event function
    /// in a root search, whose iterates need no quadratures (the energy ledger's four
    /// works, 4 of the plant's 10 components).
    pub fn interpolate_read(&mut self, t: f64) -> State<N> {
        self.interpolate_first(t, S::READ_LEN.min(N))
    }

    /// The dense output at `t` in the first `n` components, the others 0.
    #[inline(always)]
    fn interpolate_first(&mut self, t: f64, n: usize) -> State<N> {
        if self.cont.is_none() {
            self.cont = Some(dense_coefficients(self.sys, self.t_prev, self.h, self.y_prev, self.y_curr, self.k, self.k_end));
        }
        let c = self.cont.as_ref().expect("just computed");
        let s = (t - self.t_prev) / self.h;
        let s1 = 1.0 - s;
        let mut y = [0.0; N];
        for i in 0..n {
            let conpar = c[4][i] + s * (c[5][i] + s1 * (c[6][i] + s * c[7][i]));
            y[i] = c[0][i] + s * (c[1][i] + s1 * (c[2][i] + s * (c[3][i] + s1 * conpar)));
        }
        y
    }
}

/// One accepted step with its dense output, as an object: what an observer of a
/// solve sees ([`StepView`] without its system type).
pub trait DenseStep<const N: usize> {
    /// Start of the step, s.
    fn t_prev(&self) -> f64;
    /// End of the step, s.
    fn t_curr(&self) -> f64;
    /// State at the start.
    fn y_prev(&self) -> &State<N>;
    /// State at the end.
    fn y_curr(&self) -> &State<N>;
    /// Derivative at the start.
    fn f_prev(&self) -> &State<N>;
    /// Derivative at the end.
    fn f_curr(&self) -> &State<N>;
    /// The 7th-order dense output at `t` within the step.
    fn interpolate(&mut self, t: f64) -> State<N>;
}

impl<S: OdeSystem<N> + ?Sized, const N: usize> DenseStep<N> for StepView<'_, S, N> {
    fn t_prev(&self) -> f64 {
        StepView::t_prev(self)
    }
    fn t_curr(&self) -> f64 {
        StepView::t_curr(self)
    }
    fn y_prev(&self) -> &State<N> {
        StepView::y_prev(self)
    }
    fn y_curr(&self) -> &State<N> {
        StepView::y_curr(self)
    }
    fn f_prev(&self) -> &State<N> {
        StepView::f_prev(self)
    }
    fn f_curr(&self) -> &State<N> {
        StepView::f_curr(self)
    }
    fn interpolate(&mut self, t: f64) -> State<N> {
        StepView::interpolate(self, t)
    }
}
