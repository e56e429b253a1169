//! The stages of a step from the Butcher tableau (`tableau.rs`): stages 2 to 12
//! with the 8th-order solution and its error norm, and the three extra stages of
//! the dense output with its coefficients.

use super::{OdeSystem, State, tableau};

/// `y + h sum_j a_j k_j` over the given `(a_j, k_j)` in the first `read` components
/// (those `f` reads, [`OdeSystem::READ_LEN`]); the others keep `y`'s values.
#[inline(always)]
fn combine<const M: usize, const N: usize>(y: &State<N>, h: f64, terms: [(f64, &State<N>); M], read: usize) -> State<N> {
    let mut out = *y;
    for i in 0..read.min(N) {
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
pub(super) fn stages<const N: usize, S: OdeSystem<N> + ?Sized>(
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
    let read = S::READ_LEN.min(N);
    let mut s = combine(y, h, [(A21, &k[0])], read);
    sys.rhs(t + C2 * h, &s, &mut k[1]);
    s = combine(y, h, [(A31, &k[0]), (A32, &k[1])], read);
    sys.rhs(t + C3 * h, &s, &mut k[2]);
    s = combine(y, h, [(A41, &k[0]), (A43, &k[2])], read);
    sys.rhs(t + C4 * h, &s, &mut k[3]);
    s = combine(y, h, [(A51, &k[0]), (A53, &k[2]), (A54, &k[3])], read);
    sys.rhs(t + C5 * h, &s, &mut k[4]);
    s = combine(y, h, [(A61, &k[0]), (A64, &k[3]), (A65, &k[4])], read);
    sys.rhs(t + C6 * h, &s, &mut k[5]);
    s = combine(y, h, [(A71, &k[0]), (A74, &k[3]), (A75, &k[4]), (A76, &k[5])], read);
    sys.rhs(t + C7 * h, &s, &mut k[6]);
    s = combine(y, h, [(A81, &k[0]), (A84, &k[3]), (A85, &k[4]), (A86, &k[5]), (A87, &k[6])], read);
    sys.rhs(t + C8 * h, &s, &mut k[7]);
    s = combine(y, h, [(A91, &k[0]), (A94, &k[3]), (A95, &k[4]), (A96, &k[5]), (A97, &k[6]), (A98, &k[7])], read);
    sys.rhs(t + C9 * h, &s, &mut k[8]);
    s = combine(y, h, [(A101, &k[0]), (A104, &k[3]), (A105, &k[4]), (A106, &k[5]), (A107, &k[6]), (A108, &k[7]), (A109, &k[8])], read);
    sys.rhs(t + C10 * h, &s, &mut k[9]);
    s = combine(
        y,
        h,
        [(A111, &k[0]), (A114, &k[3]), (A115, &k[4]), (A116, &k[5]), (A117, &k[6]), (A118, &k[7]), (A119, &k[8]), (A1110, &k[9])],
        read,
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
        read,
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
pub(super) fn dense_coefficients<const N: usize, S: OdeSystem<N> + ?Sized>(
    sys: &S,
    t: f64,
    h: f64,
    y: &State<N>,
    y_new: &State<N>,
    k: &[State<N>],
    k13: &State<N>,
) -> [State<N>; 8] {
    use tableau::*;
    let read = S::READ_LEN.min(N);
    let s = combine(
        y,
        h,
        [(A141, &k[0]), (A147, &k[6]), (A148, &k[7]), (A149, &k[8]), (A1410, &k[9]), (A1411, &k[10]), (A1412, &k[11]), (A1413, k13)],
        read,
    );
    let mut k14 = [0.0; N];
    sys.rhs(t + C14 * h, &s, &mut k14);
    let s = combine(
        y,
        h,
        [(A151, &k[0]), (A156, &k[5]), (A157, &k[6]), (A158, &k[7]), (A1511, &k[10]), (A1512, &k[11]), (A1513, k13), (A1514, &k14)],
        read,
    );
    let mut k15 = [0.0; N];
    sys.rhs(t + C15 * h, &s, &mut k15);
    let s = combine(
        y,
        h,
        [(A161, &k[0]), (A166, &k[5]), (A167, &k[6]), (A168, &k[7]), (A169, &k[8]), (A1613, k13), (A1614, &k14), (A1615, &k15)],
        read,
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
