//! The figures' colours: the Okabe-Ito palette (Okabe and Ito, "Color Universal
//! Design", 2008; Wong, Nature Methods 8, 441, 2011), whose eight colours stay
//! distinct under protanopia, deuteranopia and tritanopia. Every figure takes its
//! colours from here, and pairs them with a line style or a marker shape where
//! two series could meet, so that no reading depends on colour alone.

use plotters::style::RGBColor;

/// Blue (Okabe-Ito).
pub const BLUE: RGBColor = RGBColor(0, 114, 178);
/// Orange (Okabe-Ito).
pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
/// Bluish green (Okabe-Ito).
pub const GREEN: RGBColor = RGBColor(0, 158, 115);
/// Vermillion (Okabe-Ito): limits, impacts, what went wrong.
pub const RED: RGBColor = RGBColor(213, 94, 0);
/// Reddish purple (Okabe-Ito).
pub const PURPLE: RGBColor = RGBColor(204, 121, 167);
/// Sky blue (Okabe-Ito).
pub const SKY: RGBColor = RGBColor(86, 180, 233);
/// Yellow (Okabe-Ito): for areas, too light for lines.
pub const YELLOW: RGBColor = RGBColor(240, 228, 66);
/// Grey: references, the belt, settling.
pub const GREY: RGBColor = RGBColor(110, 110, 110);
/// Light grey: a background class (settling transients).
pub const LIGHT_GREY: RGBColor = RGBColor(190, 190, 190);
/// Black (Okabe-Ito): what violates the model.
pub const BLACK: RGBColor = RGBColor(0, 0, 0);

/// The series colours in order, those that read as lines on white.
pub const CYCLE: [RGBColor; 6] = [BLUE, RED, GREEN, PURPLE, ORANGE, SKY];

#[cfg(test)]
mod tests {
    use super::*;

    /// The series colours differ pairwise by at least 60 in RGB distance, in colour
    /// vision and under deuteranopia (Viénot, Brettel and Mollon's 1999 projection
    /// in linear RGB, approximated on the sRGB values): no two series look alike.
    #[test]
    fn the_cycle_stays_distinct_under_deuteranopia() {
        let deut = |c: RGBColor| {
            let (r, g, b) = (c.0 as f64, c.1 as f64, c.2 as f64);
            (0.29275 * r + 0.70725 * g, 0.29275 * r + 0.70725 * g, -0.02234 * r + 0.02234 * g + b)
        };
        let d = |a: (f64, f64, f64), b: (f64, f64, f64)| ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2) + (a.2 - b.2).powi(2)).sqrt();
        for (i, a) in CYCLE.iter().enumerate() {
            for b in &CYCLE[i + 1..] {
                let plain = d((a.0 as f64, a.1 as f64, a.2 as f64), (b.0 as f64, b.1 as f64, b.2 as f64));
                assert!(plain > 60.0, "{a:?} {b:?}");
                assert!(d(deut(*a), deut(*b)) > 60.0, "{a:?} and {b:?} under deuteranopia: {}", d(deut(*a), deut(*b)));
            }
        }
    }
}
