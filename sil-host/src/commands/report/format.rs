//! Numbers in the report: every value with its significant digits, whatever its
//! magnitude (a tolerance of `1e-9` prints as `1e-9`, never as `0`), and the
//! small tables they sit in.

use std::fmt::Write as _;

/// `x` with up to 6 significant digits: fixed notation for `1e-3 <= |x| < 1e6`,
/// scientific otherwise (`1e-9`, `2.5e7`); `0`, `NaN`, `inf` and `-inf` as such.
pub fn number(x: f64) -> String {
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

/// A duration or other rough figure with 3 significant digits (`0.0291`, `15`).
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return number(x);
    }
    let digits = 3 - 1 - x.abs().log10().floor() as i32;
    let scale = 10f64.powi(digits);
    number((x * scale).round() / scale)
}

/// An optional number; `-` when absent.
pub fn opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".into(), number)
}

/// A length given in m, printed in mm with [`number`]'s digits.
pub fn mm(x_m: f64) -> String {
    number(x_m * 1e3)
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
    fn tolerances_keep_their_digits() {
        assert_eq!(number(1e-9), "1e-9");
        assert_eq!(number(1e-11), "1e-11");
        assert_eq!(number(1e-7), "1e-7");
        assert_eq!(number(2.5e-4), "2.5e-4");
    }

    #[test]
    fn ordinary_values_have_six_significant_digits() {
        assert_eq!(number(0.6), "0.6");
        assert_eq!(number(-0.4), "-0.4");
        assert_eq!(number(10.0), "10");
        assert_eq!(number(0.123456789), "0.123457");
        assert_eq!(number(1234.56789), "1234.57");
        assert_eq!(number(0.00123456789), "0.00123457");
        assert_eq!(number(3.0e7), "3e7");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(f64::NAN), "NaN");
    }

    #[test]
    fn short_figures_have_three_significant_digits() {
        assert_eq!(short(0.0290574), "0.0291");
        assert_eq!(short(15.0482), "15");
        assert_eq!(short(1234.5), "1230");
    }

    #[test]
    fn every_printed_value_parses_back_within_its_digits() {
        for x in [1e-12, 3.3e-9, 0.000999, 0.001, std::f64::consts::FRAC_1_SQRT_2, 42.0, 999_999.4, 1e6, -6.02e23] {
            let back: f64 = number(x).parse().unwrap();
            assert!((back - x).abs() <= 5e-6 * x.abs(), "{x} printed as {}", number(x));
        }
    }
}
