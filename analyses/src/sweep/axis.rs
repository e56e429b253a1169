//! A sweep's grid axis: evenly spaced values of one parameter (`mu`, `v_belt`,
//! `e_n`), both ends included, and the checks of a user's range and step.

use serde::{Deserialize, Serialize};

/// An evenly spaced axis `start, start + step, ..., stop` (both ends included).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// First value.
    pub start: f64,
    /// Last value (`>= start`).
    pub stop: f64,
    /// Spacing (`> 0`; ignored when `start == stop`).
    pub step: f64,
}

impl Axis {
    /// Number of values: `round((stop - start) / step) + 1`.
    pub fn len(&self) -> usize {
        if self.stop == self.start { 1 } else { ((self.stop - self.start) / self.step).round() as usize + 1 }
    }

    /// Whether the axis has no values (never: it has at least `start`).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Value `i`, rounded to 1e-12 so that `0.1 + 2 * 0.1` prints as `0.3`.
    pub fn value(&self, i: usize) -> f64 {
        ((self.start + i as f64 * self.step) * 1e12).round() / 1e12
    }

    /// All values.
    pub fn values(&self) -> Vec<f64> {
        (0..self.len()).map(|i| self.value(i)).collect()
    }

    /// Checks `start <= stop`, `step > 0`, finiteness, that the step divides the
    /// range (to 1e-6 of a step) and at most `max_len` values; `flag` names the option.
    ///
    /// # Errors
    /// A message naming `flag`.
    pub fn check(&self, flag: &str, max_len: usize) -> Result<(), String> {
        if !(self.start.is_finite() && self.stop.is_finite() && self.step.is_finite()) {
            return Err(format!("--{flag}: values must be finite"));
        }
        if self.start > self.stop {
            return Err(format!("--{flag}: MIN {} > MAX {}", self.start, self.stop));
        }
        if self.start == self.stop {
            return Ok(());
        }
        if self.step <= 0.0 {
            return Err(format!("--{flag}-step must be > 0, got {}", self.step));
        }
        let n = (self.stop - self.start) / self.step;
        if (n - n.round()).abs() > 1e-6 {
            return Err(format!("--{flag}-step {} does not divide the range {}..{} ({n:.4} steps)", self.step, self.start, self.stop));
        }
        if n.round() as usize + 1 > max_len {
            return Err(format!("--{flag}: {} values, at most {max_len}", n.round() as usize + 1));
        }
        Ok(())
    }
}
