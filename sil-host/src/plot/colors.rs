//! Colours used across figures (matplotlib's `tab10`, which stays distinct for
//! most colour-vision deficiencies when paired with markers or labels).

use plotters::style::RGBColor;

/// Blue.
pub const BLUE: RGBColor = RGBColor(31, 119, 180);
/// Orange.
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
/// Green.
pub const GREEN: RGBColor = RGBColor(44, 160, 44);
/// Red.
pub const RED: RGBColor = RGBColor(214, 39, 40);
/// Purple.
pub const PURPLE: RGBColor = RGBColor(148, 103, 189);
/// Brown.
pub const BROWN: RGBColor = RGBColor(140, 86, 75);
/// Pink.
pub const PINK: RGBColor = RGBColor(227, 119, 194);
/// Grey.
pub const GREY: RGBColor = RGBColor(110, 110, 110);
/// Olive.
pub const OLIVE: RGBColor = RGBColor(188, 189, 34);
/// Cyan.
pub const CYAN: RGBColor = RGBColor(23, 190, 207);

/// The series colours in order.
pub const CYCLE: [RGBColor; 10] = [BLUE, ORANGE, GREEN, RED, PURPLE, BROWN, PINK, GREY, OLIVE, CYAN];
