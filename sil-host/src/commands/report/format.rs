//! Numbers in the report: one rule per kind of quantity, each from the quantity's
//! resolution, so that a digit on the page is a digit the experiment resolved
//! (docs/analyses.md "The report's numbers" states the same rules):
//!
//! | quantity | function | printed to |
//! |---|---|---|
//! | a parameter as given (mu, e_n, durations, tolerances, targets) | [`given`] | as typed (up to 6 significant digits; `1e-9` stays `1e-9`) |
//! | a share of a grid's points | [`share`] | the power of ten just above one point (200 x 200 points: 0.0025 %, so 0.01 %) |
//! | a value on a grid (a sweep's `v_belt`, `mu`) | [`on_grid`] | the decimals of the grid's step (every grid point exactly) |
//! | a position located to a resolution (Table II's ends, a bisection's limit) | [`located`], [`position`] | the power of ten just above the resolution (0.1 mm for Table II; 1 mm for a 1 mm bisection) |
//! | an angle located by a root finder | [`angle`] | 0.01 deg, the precision the paper prints its angles to |
//! | a tracking error | [`error_mm`] | 0.01 mm, the precision of the criteria's own texts (`5.20 mm`) |
//! | a wall time, a rate, a check's residual (measured, no resolution of its own) | [`rough`] | 3 significant digits |
//!
//! Counts are integers and print as such. A value that rounds to zero prints
//! without a sign (`0.00`, never `-0.00`).

use std::fmt::Write as _;

/// A parameter as given (an input of the experiment: `mu`, `e_n`, a duration, a
/// tolerance, a target): exact, so printed as typed, with up to 6 significant
/// digits; fixed notation for `1e-3 <= |x| < 1e6`, scientific otherwise (`1e-9`,
/// `2.5e7`); `0`, `NaN`, `inf` and `-inf` as such.
pub fn given(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if !x.is_finite() {
        return if x.is_nan() {
            "NaN".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    let a = x.abs();
    if (1e-3..1e6).contains(&a) {
        // Decimals for 6 significant digits at this magnitude.
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        trim(&format!("{x:.decimals$}"))
    } else {
        let s = format!("{x:.5e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{exponent}", trim(mantissa))
    }
}

/// A measured figure with no resolution of its own (a wall time, a rate, a
/// check's residual): 3 significant digits (`0.0291`, `15`, `571000`, `5.55e-17`).
pub fn rough(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return given(x);
    }
    let digits = 3 - 1 - x.abs().log10().floor() as i32;
    let scale = 10f64.powi(digits);
    given((x * scale).round() / scale)
}

/// The share `count / total` of a grid's points, in percent, to the power of ten
/// just above one point's share (`100 / total` %): a 200 x 200 grid's point is
/// 0.0025 %, so shares print to 0.01 % (`32.86`; no `%` sign).
pub fn share(count: usize, total: usize) -> String {
    let total = total.max(1);
    fixed(100.0 * count as f64 / total as f64, decimals_of_resolution(100.0 / total as f64))
}

/// A value on a grid of spacing `step` (a sweep's `v_belt` or `mu`): the decimals
/// of the step, so that every grid point prints exactly and none with digits the
/// grid does not have (`-0.864` on a 0.004 grid, `-0.30` on a 0.01 grid).
pub fn on_grid(x: f64, step: f64) -> String {
    fixed(x, decimals_of_step(step))
}

/// A value located to `resolution` (a bisection's limit to its tolerance, a root
/// compared at a resolution), in the unit of `x`: to the power of ten just above
/// the resolution (a 1e-3 m bisection: 3 decimals in m; 2.5e-4: 3 decimals).
pub fn located(x: f64, resolution: f64) -> String {
    fixed(x, decimals_of_resolution(resolution))
}

/// Resolution of a tip position along the belt, m: 0.1 mm. Table II's ends are
/// located to 1e-9 m but compared with the paper's 3 decimals (1 mm); 0.1 mm shows
/// a difference below its rounding.
pub const POSITION_RESOLUTION_M: f64 = 1e-4;

/// A tip position along the belt in m, to [`POSITION_RESOLUTION_M`] (`0.1827`).
pub fn position(x_m: f64) -> String {
    located(x_m, POSITION_RESOLUTION_M)
}

/// An angle in degrees located by a root finder (to machine precision): to
/// 0.01 deg, the precision the paper prints its initial angles to (`22.71`).
pub fn angle(deg: f64) -> String {
    fixed(deg, 2)
}

/// A tracking error given in m, printed in mm to 0.01 mm, the precision of the
/// closed-loop criteria's own texts (`not reached: |z_t - z_t*| up to 5.20 mm`).
pub fn error_mm(x_m: f64) -> String {
    fixed(x_m * 1e3, 2)
}

/// `+` before a difference that is not negative (`+16.2`, `-0.1`, `0.0`).
pub fn signed(s: String) -> String {
    if s.starts_with('-') || s.chars().all(|c| c == '0' || c == '.') { s } else { format!("+{s}") }
}

/// Decimals that put the last printed digit at the power of ten just above
/// `resolution` (`0.0025` -> 2, `1e-3` -> 3, `1` -> 0).
fn decimals_of_resolution(resolution: f64) -> usize {
    if !(resolution.is_finite() && resolution > 0.0) {
        return 6;
    }
    (-resolution.log10() + 1e-9).floor().max(0.0) as usize
}

/// Decimals of a grid's `step` (`0.004` -> 3, `0.05` -> 2, `1` -> 0; at most 9).
fn decimals_of_step(step: f64) -> usize {
    if !(step.is_finite() && step > 0.0) {
        return 6;
    }
    (0..=9).find(|&d| (step * 10f64.powi(d as i32) - (step * 10f64.powi(d as i32)).round()).abs() < 1e-6).unwrap_or(9)
}

/// `x` with `decimals` fixed decimals; a value that rounds to zero without a sign;
/// non-finite values as [`given`] prints them.
fn fixed(x: f64, decimals: usize) -> String {
    if !x.is_finite() {
        return given(x);
    }
    let s = format!("{x:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') { s[1..].to_string() } else { s }
}

/// Drops trailing zeros of a decimal fraction (and a bare trailing point).
fn trim(s: &str) -> String {
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s.to_string() }
}

/// A Markdown table cell: `|` escaped, newlines as spaces.
pub fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Rows shown of a long table (the files hold the rest).
pub const MAX_ROWS: usize = 60;

/// A two-column table of named values.
pub fn pairs(md: &mut String, rows: &[(&str, String)]) {
    let _ = writeln!(md, "| quantity | value |\n|---|---|");
    for (k, v) in rows {
        let _ = writeln!(md, "| {k} | {} |", cell(v));
    }
    md.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn given_values_keep_their_digits() {
        assert_eq!(given(1e-9), "1e-9");
        assert_eq!(given(1e-11), "1e-11");
        assert_eq!(given(2.5e-4), "2.5e-4");
        assert_eq!(given(0.6), "0.6");
        assert_eq!(given(-0.4), "-0.4");
        assert_eq!(given(10.0), "10");
        assert_eq!(given(0.123456789), "0.123457");
        assert_eq!(given(3.0e7), "3e7");
        assert_eq!(given(0.0), "0");
        assert_eq!(given(f64::NAN), "NaN");
    }

    #[test]
    fn every_given_value_parses_back_within_its_digits() {
        for x in [1e-12, 3.3e-9, 0.000999, 0.001, std::f64::consts::FRAC_1_SQRT_2, 42.0, 999_999.4, 1e6, -6.02e23] {
            let back: f64 = given(x).parse().unwrap();
            assert!((back - x).abs() <= 5e-6 * x.abs(), "{x} printed as {}", given(x));
        }
    }

    #[test]
    fn rough_figures_have_three_significant_digits() {
        assert_eq!(rough(0.0290574), "0.0291");
        assert_eq!(rough(15.0482), "15");
        assert_eq!(rough(1234.5), "1230");
        assert_eq!(rough(570_670.0), "571000");
        assert_eq!(rough(5.551_115e-17), "5.55e-17");
    }

    /// The example: a 200 x 200 grid resolves 0.0025 %, printed to 0.01 %.
    #[test]
    fn shares_print_to_the_grid_resolution() {
        assert_eq!(share(13_143, 40_000), "32.86");
        assert_eq!(share(986, 40_000), "2.46");
        assert_eq!(share(23_600, 40_000), "59.00");
        assert_eq!(share(0, 40_000), "0.00");
        // 400 x 400: 0.000625 % a point, 0.001 %.
        assert_eq!(share(52_572, 160_000), "32.858");
        // 10 points: 10 % a point.
        assert_eq!(share(3, 10), "30");
    }

    #[test]
    fn grid_values_print_every_grid_point_exactly() {
        assert_eq!(on_grid(-0.864, 0.004), "-0.864");
        assert_eq!(on_grid(-0.3, 0.004), "-0.300");
        assert_eq!(on_grid(-0.3, 0.01), "-0.30");
        assert_eq!(on_grid(-0.30000000000000004, 0.05), "-0.30");
        assert_eq!(on_grid(0.6, 0.1), "0.6");
        assert_eq!(on_grid(1.0, 0.1), "1.0");
        assert_eq!(on_grid(-0.0000001, 0.01), "0.00");
    }

    #[test]
    fn located_values_print_to_their_resolution() {
        assert_eq!(position(0.182_700_123), "0.1827");
        assert_eq!(position(-0.184_103), "-0.1841");
        assert_eq!(located(0.123_144, 1e-3), "0.123");
        assert_eq!(located(0.123_744, 1e-3), "0.124");
        assert_eq!(angle(22.712_9), "22.71");
        assert_eq!(error_mm(0.004_814_76), "4.81");
        assert_eq!(error_mm(2.498e-16), "0.00");
        assert_eq!(error_mm(-1e-9), "0.00");
    }

    #[test]
    fn differences_carry_their_sign() {
        assert_eq!(signed("16.2".into()), "+16.2");
        assert_eq!(signed("-0.1".into()), "-0.1");
        assert_eq!(signed("0.0".into()), "0.0");
    }
}
