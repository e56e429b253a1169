//! DOP853: the explicit Runge-Kutta method of order 8 of Dormand and Prince with
//! an error estimator of orders 5 and 3 and a dense output of order 7, as given by
//! Hairer, Nørsett and Wanner, "Solving Ordinary Differential Equations I.
//! Nonstiff Problems", 2nd ed., Springer 1993, sec. II.10 (and their Fortran code
//! `dop853`, whose coefficients, error norm and step-size control this follows).
//!
//! Generic over the size `N` of a fixed-size state ([`State`]`<N>`; the plant's
//! has six components) and free of any plant type: the stages live on the stack, nothing is allocated per step or per solve, the last
//! stage of an accepted step (the derivative at its end) is the first stage of the
//! next one (FSAL), and the three extra stages of the dense output are evaluated
//! only when [`StepView::interpolate`] is first called for a step (most steps of
//! the plant have no event to locate). The stiffness detection of `dop853` is
//! omitted. Integration runs forward in time only.

/// A state of `N` components (the plant's: `N = 6`).
pub type State<const N: usize> = [f64; N];

/// The step ratio after the caller rejects a step ([`Control::Reject`]): a quarter.
pub const REJECT_FACTOR: f64 = 0.25;

/// A system `y' = f(t, y)` on [`State`]`<N>`.
pub trait OdeSystem<const N: usize> {
    /// Writes `f(t, y)` into `dy` (`t` in s; units of `y` per second).
    fn rhs(&self, t: f64, y: &State<N>, dy: &mut State<N>);

    /// `f(t, y)` at the end of an accepted step (the FSAL stage, evaluated just
    /// before [`Dop853::solve`] reports the step). The same value as
    /// [`OdeSystem::rhs`]; a system may override it to keep by-products for its
    /// event functions at that point.
    #[inline]
    fn rhs_step_end(&self, t: f64, y: &State<N>, dy: &mut State<N>) {
        self.rhs(t, y, dy);
    }

    /// How many leading components the error norm measures (all `N` by default).
    /// The others are carried along (integrated by the same stages, with the same
    /// dense output) but set no step: quadratures of the solution, such as the
    /// plant's energy ledger, that must not change the path they measure.
    const NORM_LEN: usize = N;

    /// How many leading components [`OdeSystem::rhs`] reads (all `N` by default).
    /// The others must be quadratures of the solution: `f` never reads them, so
    /// the stages' intermediate states are formed for the first `READ_LEN`
    /// components only (the others hold the step's start values there), and the
    /// others are summed in the step's solution, its error norm and its dense
    /// output alone. The plant's energy ledger: four of its ten components, about
    /// 4/10 of the stage sums (issue 56). Must be at least [`OdeSystem::NORM_LEN`]
    /// for the quadratures to set no step.
    const READ_LEN: usize = N;
}

/// What the step callback of [`Dop853::solve`] asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Go on integrating.
    Continue,
    /// End the solve after this step (e.g. an event was located in it).
    Stop,
    /// Do not accept this step after all (a check of the caller's that the error
    /// estimate cannot make, e.g. a balance the step breaks): it is taken again from
    /// the same point at a quarter of its size, and counted as rejected.
    Reject,
}

/// Why a solve failed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// More steps than [`Dop853::max_steps`] (accepted and rejected).
    #[error("more than {max_steps} steps")]
    MaxSteps {
        /// Time reached, s.
        t: f64,
        /// The limit.
        max_steps: usize,
    },
    /// The step size fell below the rounding level of `t` (`0.1 |h| <= |t| u`, as `dop853`).
    #[error("step size {h} s too small at t = {t} s")]
    StepSizeTooSmall {
        /// Time reached, s.
        t: f64,
        /// The step size, s.
        h: f64,
    },
}

/// The end of a solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solved<const N: usize> {
    /// Time of the last accepted step's end, s (`t_end` unless the callback stopped the solve).
    pub t: f64,
    /// State at [`Solved::t`].
    pub y: State<N>,
    /// Whether the callback stopped the solve.
    pub stopped: bool,
    /// The step size the controller proposes after the last accepted step, s
    /// (`dop853`'s returned `H`; a good first step for a continuation).
    pub h_next: f64,
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps.
    pub rejected: usize,
}

/// DOP853's settings (Hairer, Nørsett and Wanner, sec. II.4 and II.10; the
/// defaults are those of the Fortran code `dop853`).
///
/// The local error of a step is measured in the norm
/// `err = |h| E5 / sqrt(N (E5 + 0.01 E3))` with `E_k = sum_i (e_k,i / sk_i)^2`, the
/// 5th- and 3rd-order estimates `e_5`, `e_3` and `sk_i = atol + rtol max(|y0_i|, |y1_i|)`;
/// a step is accepted when `err <= 1`, and the next step is
/// `h_new = h / max(1/fac_max, min(1/fac_min, err^(1/8 - 0.2 beta) / (err_old^beta safety)))`
/// (Lund stabilisation with `beta`, sec. IV.2; `beta = 0` is the plain controller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dop853 {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (units of the state).
    pub atol: f64,
    /// Largest step size, s.
    pub h_max: f64,
    /// Largest number of steps (accepted and rejected) in one solve.
    pub max_steps: usize,
    /// Safety factor of the step-size prediction (`dop853`: 0.9).
    pub safety: f64,
    /// Smallest ratio `h_new / h` (`dop853`'s `FAC1`: 0.333).
    pub fac_min: f64,
    /// Largest ratio `h_new / h` (`dop853`'s `FAC2`: 6).
    pub fac_max: f64,
    /// Lund stabilisation exponent `beta` (`dop853`: 0; at most 0.04 makes sense).
    pub beta: f64,
}

impl Dop853 {
    /// The method with tolerances `rtol`, `atol` and `dop853`'s other defaults
    /// (no step-size limit, 100 000 steps).
    pub fn new(rtol: f64, atol: f64) -> Self {
        Self { rtol, atol, h_max: f64::INFINITY, max_steps: 100_000, safety: 0.9, fac_min: 0.333, fac_max: 6.0, beta: 0.0 }
    }

    /// Integrates `sys` from `(t0, y0)` to `t_end` (s, `t_end >= t0`), starting with
    /// the step `h0` (s; `<= 0` to let Hairer's `HINIT` choose it). `f0` is
    /// `f(t0, y0)` if the caller already has it (it is evaluated otherwise).
    ///
    /// After every accepted step `on_step` sees the step ([`StepView`]: its ends
    /// and dense output) and may stop the solve.
    ///
    /// # Errors
    /// [`SolveError::MaxSteps`], [`SolveError::StepSizeTooSmall`] (also what a
    /// non-finite derivative leads to: its steps are rejected until then).
    #[allow(clippy::too_many_arguments)]
    pub fn solve<const N: usize, S, F>(
        &self,
        sys: &S,
        t0: f64,
        y0: &State<N>,
        f0: Option<&State<N>>,
        t_end: f64,
        h0: f64,
        mut on_step: F,
    ) -> Result<Solved<N>, SolveError>
    where
        S: OdeSystem<N> + ?Sized,
        F: FnMut(&mut StepView<'_, S, N>) -> Control,
    {
        let mut t = t0;
        let mut y = *y0;
        // k[0] is f at the step's start; k[1..12] the other stages; k[12] f at its end.
        let mut k = [[0.0; N]; 13];
        match f0 {
            Some(f) => k[0] = *f,
            None => sys.rhs(t, &y, &mut k[0]),
        }
        let mut done = Solved { t, y, stopped: false, h_next: h0, accepted: 0, rejected: 0 };
        if t_end <= t0 {
            return Ok(done);
        }
        let h_max = self.h_max.min(t_end - t0);
        let mut h = if h0 > 0.0 { h0 } else { self.initial_step(sys, t, &y, &k[0], h_max) };
        h = h.min(h_max);
        let expo1 = 0.125 - self.beta * 0.2;
        let (facc1, facc2) = (1.0 / self.fac_min, 1.0 / self.fac_max);
        let mut fac_old: f64 = 1e-4;
        let mut reject = false;
        let mut steps = 0usize;
        let mut y_new = [0.0; N];
        loop {
            if steps >= self.max_steps {
                return Err(SolveError::MaxSteps { t, max_steps: self.max_steps });
            }
            if 0.1 * h.abs() <= t.abs() * f64::EPSILON {
                return Err(SolveError::StepSizeTooSmall { t, h });
            }
            let last = t + 1.01 * h - t_end > 0.0;
            if last {
                h = t_end - t;
            }
            steps += 1;
            let err = stages(sys, t, &y, h, &mut k, self.atol, self.rtol, &mut y_new);
            // Step-size prediction (dop853); err^(1/8) as three square roots (the
            // default beta = 0), a fraction of the cost of `powf`.
            let (fac11, fac) = if self.beta == 0.0 {
                let r = err.sqrt().sqrt().sqrt();
                (r, r)
            } else {
                let r = err.powf(expo1);
                (r, r / fac_old.powf(self.beta))
            };
            let fac = facc2.max(facc1.min(fac / self.safety));
            let mut h_new = h / fac;
            if err <= 1.0 {
                fac_old = err.max(1e-4);
                let t_new = if last { t_end } else { t + h };
                let (k_end, k_rest) = k.split_last_mut().expect("13 stages");
                sys.rhs_step_end(t_new, &y_new, k_end);
                h_new = h_new.min(self.h_max);
                if reject {
                    h_new = h_new.min(h);
                }
                reject = false;
                let control = {
                    let mut view = StepView { sys, t_prev: t, t_curr: t_new, h, y_prev: &y, y_curr: &y_new, k: k_rest, k_end, cont: None };
                    on_step(&mut view)
                };
                if control == Control::Reject {
                    // k[0] is still f(t, y); k[12] is evaluated again at the next end.
                    h *= REJECT_FACTOR;
                    reject = true;
                    done.rejected += 1;
                    continue;
                }
                done.accepted += 1;
                k[0] = k[12];
                t = t_new;
                y = y_new;
                done.t = t;
                done.y = y;
                done.h_next = h_new;
                if control == Control::Stop {
                    done.stopped = true;
                    return Ok(done);
                }
                if last {
                    return Ok(done);
                }
            } else {
                h_new = h / facc1.min(fac11 / self.safety);
                reject = true;
                done.rejected += 1;
            }
            h = h_new;
        }
    }

    /// Hairer's `HINIT` (sec. II.4): a first step from the sizes of `y0`, `f0` and
    /// a difference estimate of `y''`, for an order-8 method.
    fn initial_step<const N: usize, S: OdeSystem<N> + ?Sized>(&self, sys: &S, t0: f64, y0: &State<N>, f0: &State<N>, h_max: f64) -> f64 {
        let mut dnf = 0.0;
        let mut dny = 0.0;
        let mut sk = [0.0; N];
        let norm_len = S::NORM_LEN.min(N);
        for i in 0..norm_len {
            sk[i] = self.atol + self.rtol * y0[i].abs();
            dnf += (f0[i] / sk[i]).powi(2);
            dny += (y0[i] / sk[i]).powi(2);
        }
        let mut h = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
        h = h.min(h_max);
        let mut y1 = [0.0; N];
        for i in 0..N {
            y1[i] = y0[i] + h * f0[i];
        }
        let mut f1 = [0.0; N];
        sys.rhs(t0 + h, &y1, &mut f1);
        let der2 = (0..norm_len).map(|i| ((f1[i] - f0[i]) / sk[i]).powi(2)).sum::<f64>().sqrt() / h;
        let der12 = der2.abs().max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 { (h.abs() * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / 8.0) };
        (100.0 * h.abs()).min(h1).min(h_max)
    }
}

mod stages;
mod step;
// The Butcher tableau: the coefficients, in `dop853/tableau.rs`.
mod tableau;

pub use step::{DenseStep, StepView};

use stages::stages;

#[cfg(test)]
#[path = "dop853_tests.rs"]
mod tests;
