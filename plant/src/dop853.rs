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

/// One accepted step, as [`Dop853::solve`] reports it: its ends and its dense output.
pub struct StepView<'a, S: ?Sized, const N: usize> {
    sys: &'a S,
    t_prev: f64,
    t_curr: f64,
    h: f64,
    y_prev: &'a State<N>,
    y_curr: &'a State<N>,
    /// Stages 1 to 12 (`k[0]` = f at the start).
    k: &'a [State<N>],
    /// Stage 13: f at the end.
    k_end: &'a State<N>,
    /// The dense output's coefficients, once computed.
    cont: Option<[State<N>; 8]>,
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
        if self.cont.is_none() {
            self.cont = Some(dense_coefficients(self.sys, self.t_prev, self.h, self.y_prev, self.y_curr, self.k, self.k_end));
        }
        let c = self.cont.as_ref().expect("just computed");
        let s = (t - self.t_prev) / self.h;
        let s1 = 1.0 - s;
        let mut y = [0.0; N];
        for i in 0..N {
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

/// `y + h sum_j a_j k_j` over the given `(a_j, k_j)`.
#[inline(always)]
fn combine<const M: usize, const N: usize>(y: &State<N>, h: f64, terms: [(f64, &State<N>); M]) -> State<N> {
    let mut out = [0.0; N];
    for i in 0..N {
        let mut acc = 0.0;
        for (a, k) in terms.iter() {
            acc += a * k[i];
        }
        out[i] = y[i] + h * acc;
    }
    out
}

/// Stages 2 to 12 of a step of size `h` from `(t, y)` with `k[0] = f(t, y)`;
/// writes the 8th-order solution into `y_new` and returns the error norm.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn stages<const N: usize, S: OdeSystem<N> + ?Sized>(
    sys: &S,
    t: f64,
    y: &State<N>,
    h: f64,
    k: &mut [State<N>; 13],
    atol: f64,
    rtol: f64,
    y_new: &mut State<N>,
) -> f64 {
    use tableau::*;
    let mut s = combine(y, h, [(A21, &k[0])]);
    sys.rhs(t + C2 * h, &s, &mut k[1]);
    s = combine(y, h, [(A31, &k[0]), (A32, &k[1])]);
    sys.rhs(t + C3 * h, &s, &mut k[2]);
    s = combine(y, h, [(A41, &k[0]), (A43, &k[2])]);
    sys.rhs(t + C4 * h, &s, &mut k[3]);
    s = combine(y, h, [(A51, &k[0]), (A53, &k[2]), (A54, &k[3])]);
    sys.rhs(t + C5 * h, &s, &mut k[4]);
    s = combine(y, h, [(A61, &k[0]), (A64, &k[3]), (A65, &k[4])]);
    sys.rhs(t + C6 * h, &s, &mut k[5]);
    s = combine(y, h, [(A71, &k[0]), (A74, &k[3]), (A75, &k[4]), (A76, &k[5])]);
    sys.rhs(t + C7 * h, &s, &mut k[6]);
    s = combine(y, h, [(A81, &k[0]), (A84, &k[3]), (A85, &k[4]), (A86, &k[5]), (A87, &k[6])]);
    sys.rhs(t + C8 * h, &s, &mut k[7]);
    s = combine(y, h, [(A91, &k[0]), (A94, &k[3]), (A95, &k[4]), (A96, &k[5]), (A97, &k[6]), (A98, &k[7])]);
    sys.rhs(t + C9 * h, &s, &mut k[8]);
    s = combine(y, h, [(A101, &k[0]), (A104, &k[3]), (A105, &k[4]), (A106, &k[5]), (A107, &k[6]), (A108, &k[7]), (A109, &k[8])]);
    sys.rhs(t + C10 * h, &s, &mut k[9]);
    s = combine(
        y,
        h,
        [(A111, &k[0]), (A114, &k[3]), (A115, &k[4]), (A116, &k[5]), (A117, &k[6]), (A118, &k[7]), (A119, &k[8]), (A1110, &k[9])],
    );
    sys.rhs(t + C11 * h, &s, &mut k[10]);
    s = combine(
        y,
        h,
        [
            (A121, &k[0]),
            (A124, &k[3]),
            (A125, &k[4]),
            (A126, &k[5]),
            (A127, &k[6]),
            (A128, &k[7]),
            (A129, &k[8]),
            (A1210, &k[9]),
            (A1211, &k[10]),
        ],
    );
    sys.rhs(t + h, &s, &mut k[11]);
    // The 8th-order solution, and the 5th- and 3rd-order error estimates.
    let (mut err5, mut err3) = (0.0, 0.0);
    let norm_len = S::NORM_LEN.min(N);
    for i in 0..N {
        let inc =
            B1 * k[0][i] + B6 * k[5][i] + B7 * k[6][i] + B8 * k[7][i] + B9 * k[8][i] + B10 * k[9][i] + B11 * k[10][i] + B12 * k[11][i];
        y_new[i] = y[i] + h * inc;
        if i >= norm_len {
            continue;
        }
        let sk = atol + rtol * y[i].abs().max(y_new[i].abs());
        let e3 = inc - BHH1 * k[0][i] - BHH2 * k[8][i] - BHH3 * k[11][i];
        err3 += (e3 / sk) * (e3 / sk);
        let e5 = ER1 * k[0][i]
            + ER6 * k[5][i]
            + ER7 * k[6][i]
            + ER8 * k[7][i]
            + ER9 * k[8][i]
            + ER10 * k[9][i]
            + ER11 * k[10][i]
            + ER12 * k[11][i];
        err5 += (e5 / sk) * (e5 / sk);
    }
    let mut deno = err5 + 0.01 * err3;
    if deno <= 0.0 {
        deno = 1.0;
    }
    let inv = 1.0 / (norm_len as f64 * deno);
    if inv.is_finite() {
        h.abs() * err5 * inv.sqrt()
    } else {
        // `deno` underflowed to a subnormal (a state at rest: every stage equal to
        // within ~1e-160); `0 * inf` would make the error NaN and reject every step.
        // err5 <= deno, so this quotient is finite.
        h.abs() * err5 / (norm_len as f64 * deno).sqrt()
    }
}

/// The eight coefficient vectors of the dense output of a step (`dop853`'s `CONT`),
/// evaluating stages 14 to 16.
fn dense_coefficients<const N: usize, S: OdeSystem<N> + ?Sized>(
    sys: &S,
    t: f64,
    h: f64,
    y: &State<N>,
    y_new: &State<N>,
    k: &[State<N>],
    k13: &State<N>,
) -> [State<N>; 8] {
    use tableau::*;
    let s = combine(
        y,
        h,
        [(A141, &k[0]), (A147, &k[6]), (A148, &k[7]), (A149, &k[8]), (A1410, &k[9]), (A1411, &k[10]), (A1412, &k[11]), (A1413, k13)],
    );
    let mut k14 = [0.0; N];
    sys.rhs(t + C14 * h, &s, &mut k14);
    let s = combine(
        y,
        h,
        [(A151, &k[0]), (A156, &k[5]), (A157, &k[6]), (A158, &k[7]), (A1511, &k[10]), (A1512, &k[11]), (A1513, k13), (A1514, &k14)],
    );
    let mut k15 = [0.0; N];
    sys.rhs(t + C15 * h, &s, &mut k15);
    let s = combine(
        y,
        h,
        [(A161, &k[0]), (A166, &k[5]), (A167, &k[6]), (A168, &k[7]), (A169, &k[8]), (A1613, k13), (A1614, &k14), (A1615, &k15)],
    );
    let mut k16 = [0.0; N];
    sys.rhs(t + C16 * h, &s, &mut k16);
    let mut c = [[0.0; N]; 8];
    // Stages 1, 6..16 in the order of the rows of D.
    let ks: [&State<N>; 12] = [&k[0], &k[5], &k[6], &k[7], &k[8], &k[9], &k[10], &k[11], k13, &k14, &k15, &k16];
    for i in 0..N {
        let ydiff = y_new[i] - y[i];
        let bspl = h * k[0][i] - ydiff;
        c[0][i] = y[i];
        c[1][i] = ydiff;
        c[2][i] = bspl;
        c[3][i] = ydiff - h * k13[i] - bspl;
        for (row, d) in D.iter().enumerate() {
            let mut acc = 0.0;
            for (dj, kj) in d.iter().zip(ks.iter()) {
                acc += dj * kj[i];
            }
            c[4 + row][i] = h * acc;
        }
    }
    c
}

// The Butcher tableau: the coefficients, in `dop853/tableau.rs`.
mod tableau;

#[cfg(test)]
mod tests {
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
}
