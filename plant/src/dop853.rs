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
}

/// What the step callback of [`Dop853::solve`] asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Go on integrating.
    Continue,
    /// End the solve after this step (e.g. an event was located in it).
    Stop,
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
                done.accepted += 1;
                let control = {
                    let mut view = StepView { sys, t_prev: t, t_curr: t_new, h, y_prev: &y, y_curr: &y_new, k: k_rest, k_end, cont: None };
                    on_step(&mut view)
                };
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
        for i in 0..N {
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
        let der2 = (0..N).map(|i| ((f1[i] - f0[i]) / sk[i]).powi(2)).sum::<f64>().sqrt() / h;
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
    for i in 0..N {
        let inc =
            B1 * k[0][i] + B6 * k[5][i] + B7 * k[6][i] + B8 * k[7][i] + B9 * k[8][i] + B10 * k[9][i] + B11 * k[10][i] + B12 * k[11][i];
        y_new[i] = y[i] + h * inc;
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
    let inv = 1.0 / (N as f64 * deno);
    if inv.is_finite() {
        h.abs() * err5 * inv.sqrt()
    } else {
        // `deno` underflowed to a subnormal (a state at rest: every stage equal to
        // within ~1e-160); `0 * inf` would make the error NaN and reject every step.
        // err5 <= deno, so this quotient is finite.
        h.abs() * err5 / (N as f64 * deno).sqrt()
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

/// The coefficients of DOP853 (Hairer, Nørsett and Wanner, sec. II.10, and the
/// Fortran code `dop853`), to 30 digits where they are irrational. Stage `i`
/// is evaluated at `t + c_i h` from `y + h sum_j a_ij k_j`; stage 12 at `c = 1`;
/// stage 13 is `f` at the new point.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
mod tableau {
    pub const C2: f64 = 0.526001519587677318785587544488e-01;
    pub const C3: f64 = 0.789002279381515978178381316732e-01;
    pub const C4: f64 = 0.118350341907227396726757197510e+00;
    pub const C5: f64 = 0.281649658092772603273242802490e+00;
    pub const C6: f64 = 0.333333333333333333333333333333e+00;
    pub const C7: f64 = 0.25e+00;
    pub const C8: f64 = 0.307692307692307692307692307692e+00;
    pub const C9: f64 = 0.651282051282051282051282051282e+00;
    pub const C10: f64 = 0.6e+00;
    pub const C11: f64 = 0.857142857142857142857142857142e+00;
    pub const C14: f64 = 0.1e+00;
    pub const C15: f64 = 0.2e+00;
    pub const C16: f64 = 0.777777777777777777777777777778e+00;

    /// Weights of the 8th-order solution (stages 1, 6 to 12; the others are 0).
    pub const B1: f64 = 5.42937341165687622380535766363e-2;
    pub const B6: f64 = 4.45031289275240888144113950566e0;
    pub const B7: f64 = 1.89151789931450038304281599044e0;
    pub const B8: f64 = -5.8012039600105847814672114227e0;
    pub const B9: f64 = 3.1116436695781989440891606237e-1;
    pub const B10: f64 = -1.52160949662516078556178806805e-1;
    pub const B11: f64 = 2.01365400804030348374776537501e-1;
    pub const B12: f64 = 4.47106157277725905176885569043e-2;

    /// The 3rd-order estimate `b - bhh` (stages 1, 9, 12).
    pub const BHH1: f64 = 0.244094488188976377952755905512e+00;
    pub const BHH2: f64 = 0.733846688281611857341361741547e+00;
    pub const BHH3: f64 = 0.220588235294117647058823529412e-01;

    /// The 5th-order error estimate (stages 1, 6 to 12).
    pub const ER1: f64 = 0.1312004499419488073250102996e-01;
    pub const ER6: f64 = -0.1225156446376204440720569753e+01;
    pub const ER7: f64 = -0.4957589496572501915214079952e+00;
    pub const ER8: f64 = 0.1664377182454986536961530415e+01;
    pub const ER9: f64 = -0.3503288487499736816886487290e+00;
    pub const ER10: f64 = 0.3341791187130174790297318841e+00;
    pub const ER11: f64 = 0.8192320648511571246570742613e-01;
    pub const ER12: f64 = -0.2235530786388629525884427845e-01;

    pub const A21: f64 = 5.26001519587677318785587544488e-2;
    pub const A31: f64 = 1.97250569845378994544595329183e-2;
    pub const A32: f64 = 5.91751709536136983633785987549e-2;
    pub const A41: f64 = 2.95875854768068491816892993775e-2;
    pub const A43: f64 = 8.87627564304205475450678981324e-2;
    pub const A51: f64 = 2.41365134159266685502369798665e-1;
    pub const A53: f64 = -8.84549479328286085344864962717e-1;
    pub const A54: f64 = 9.24834003261792003115737966543e-1;
    pub const A61: f64 = 3.7037037037037037037037037037e-2;
    pub const A64: f64 = 1.70828608729473871279604482173e-1;
    pub const A65: f64 = 1.25467687566822425016691814123e-1;
    pub const A71: f64 = 3.7109375e-2;
    pub const A74: f64 = 1.70252211019544039314978060272e-1;
    pub const A75: f64 = 6.02165389804559606850219397283e-2;
    pub const A76: f64 = -1.7578125e-2;
    pub const A81: f64 = 3.70920001185047927108779319836e-2;
    pub const A84: f64 = 1.70383925712239993810214054705e-1;
    pub const A85: f64 = 1.07262030446373284651809199168e-1;
    pub const A86: f64 = -1.53194377486244017527936158236e-2;
    pub const A87: f64 = 8.27378916381402288758473766002e-3;
    pub const A91: f64 = 6.24110958716075717114429577812e-1;
    pub const A94: f64 = -3.36089262944694129406857109825e0;
    pub const A95: f64 = -8.68219346841726006818189891453e-1;
    pub const A96: f64 = 2.75920996994467083049415600797e1;
    pub const A97: f64 = 2.01540675504778934086186788979e1;
    pub const A98: f64 = -4.34898841810699588477366255144e1;
    pub const A101: f64 = 4.77662536438264365890433908527e-1;
    pub const A104: f64 = -2.48811461997166764192642586468e0;
    pub const A105: f64 = -5.90290826836842996371446475743e-1;
    pub const A106: f64 = 2.12300514481811942347288949897e1;
    pub const A107: f64 = 1.52792336328824235832596922938e1;
    pub const A108: f64 = -3.32882109689848629194453265587e1;
    pub const A109: f64 = -2.03312017085086261358222928593e-2;
    pub const A111: f64 = -9.3714243008598732571704021658e-1;
    pub const A114: f64 = 5.18637242884406370830023853209e0;
    pub const A115: f64 = 1.09143734899672957818500254654e0;
    pub const A116: f64 = -8.14978701074692612513997267357e0;
    pub const A117: f64 = -1.85200656599969598641566180701e1;
    pub const A118: f64 = 2.27394870993505042818970056734e1;
    pub const A119: f64 = 2.49360555267965238987089396762e0;
    pub const A1110: f64 = -3.0467644718982195003823669022e0;
    pub const A121: f64 = 2.27331014751653820792359768449e0;
    pub const A124: f64 = -1.05344954667372501984066689879e1;
    pub const A125: f64 = -2.00087205822486249909675718444e0;
    pub const A126: f64 = -1.79589318631187989172765950534e1;
    pub const A127: f64 = 2.79488845294199600508499808837e1;
    pub const A128: f64 = -2.85899827713502369474065508674e0;
    pub const A129: f64 = -8.87285693353062954433549289258e0;
    pub const A1210: f64 = 1.23605671757943030647266201528e1;
    pub const A1211: f64 = 6.43392746015763530355970484046e-1;

    // The three extra stages of the dense output (stage 13 is f at the new point).
    pub const A141: f64 = 5.61675022830479523392909219681e-2;
    pub const A147: f64 = 2.53500210216624811088794765333e-1;
    pub const A148: f64 = -2.46239037470802489917441475441e-1;
    pub const A149: f64 = -1.24191423263816360469010140626e-1;
    pub const A1410: f64 = 1.5329179827876569731206322685e-1;
    pub const A1411: f64 = 8.20105229563468988491666602057e-3;
    pub const A1412: f64 = 7.56789766054569976138603589584e-3;
    pub const A1413: f64 = -8.298e-3;
    pub const A151: f64 = 3.18346481635021405060768473261e-2;
    pub const A156: f64 = 2.83009096723667755288322961402e-2;
    pub const A157: f64 = 5.35419883074385676223797384372e-2;
    pub const A158: f64 = -5.49237485713909884646569340306e-2;
    pub const A1511: f64 = -1.08347328697249322858509316994e-4;
    pub const A1512: f64 = 3.82571090835658412954920192323e-4;
    pub const A1513: f64 = -3.40465008687404560802977114492e-4;
    pub const A1514: f64 = 1.41312443674632500278074618366e-1;
    pub const A161: f64 = -4.28896301583791923408573538692e-1;
    pub const A166: f64 = -4.69762141536116384314449447206e0;
    pub const A167: f64 = 7.68342119606259904184240953878e0;
    pub const A168: f64 = 4.06898981839711007970213554331e0;
    pub const A169: f64 = 3.56727187455281109270669543021e-1;
    pub const A1613: f64 = -1.39902416515901462129418009734e-3;
    pub const A1614: f64 = 2.9475147891527723389556272149e0;
    pub const A1615: f64 = -9.15095847217987001081870187138e0;

    /// Rows 4 to 7 of the dense output, over stages 1, 6, 7, ..., 16.
    pub const D: [[f64; 12]; 4] = [
        [
            -0.84289382761090128651353491142e+01,
            0.56671495351937776962531783590e+00,
            -0.30689499459498916912797304727e+01,
            0.23846676565120698287728149680e+01,
            0.21170345824450282767155149946e+01,
            -0.87139158377797299206789907490e+00,
            0.22404374302607882758541771650e+01,
            0.63157877876946881815570249290e+00,
            -0.88990336451333310820698117400e-01,
            0.18148505520854727256656404962e+02,
            -0.91946323924783554000451984436e+01,
            -0.44360363875948939664310572000e+01,
        ],
        [
            0.10427508642579134603413151009e+02,
            0.24228349177525818288430175319e+03,
            0.16520045171727028198505394887e+03,
            -0.37454675472269020279518312152e+03,
            -0.22113666853125306036270938578e+02,
            0.77334326684722638389603898808e+01,
            -0.30674084731089398182061213626e+02,
            -0.93321305264302278729567221706e+01,
            0.15697238121770843886131091075e+02,
            -0.31139403219565177677282850411e+02,
            -0.93529243588444783865713862664e+01,
            0.35816841486394083752465898540e+02,
        ],
        [
            0.19985053242002433820987653617e+02,
            -0.38703730874935176555105901742e+03,
            -0.18917813819516756882830838328e+03,
            0.52780815920542364900561016686e+03,
            -0.11573902539959630126141871134e+02,
            0.68812326946963000169666922661e+01,
            -0.10006050966910838403183860980e+01,
            0.77771377980534432092869265740e+00,
            -0.27782057523535084065932004339e+01,
            -0.60196695231264120758267380846e+02,
            0.84320405506677161018159903784e+02,
            0.11992291136182789328035130030e+02,
        ],
        [
            -0.25693933462703749003312586129e+02,
            -0.15418974869023643374053993627e+03,
            -0.23152937917604549567536039109e+03,
            0.35763911791061412378285349910e+03,
            0.93405324183624310003907691704e+02,
            -0.37458323136451633156875139351e+02,
            0.10409964950896230045147246184e+03,
            0.29840293426660503123344363579e+02,
            -0.43533456590011143754432175058e+02,
            0.96324553959188282948394950600e+02,
            -0.39177261675615439165231486172e+02,
            -0.14972683625798562581422125276e+03,
        ],
    ];
}

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
