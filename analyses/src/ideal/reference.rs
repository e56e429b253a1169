//! The tangential reference of the ideal laws: the firmware's minimum-jerk
//! quintic move of `z_t*`, in `f64`.

use serde::Serialize;

/// One point of the tangential reference: `z_t*` (m), `z_t_dot*` (m/s), `z_t_ddot*` (m/s^2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RefPoint {
    /// `z_t*`, m.
    pub pos: f64,
    /// `z_t_dot*`, m/s.
    pub vel: f64,
    /// `z_t_ddot*`, m/s^2.
    pub acc: f64,
}

/// The tangential reference `z_t*(t)` of the firmware (`firmware::reference::Quintic`),
/// in `f64`: the minimum-jerk quintic `s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5`
/// (Flash and Hogan 1985) from `start` to `target` (m) over `duration` (s, > 0),
/// then held at the target. Negative times give the start.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reference {
    /// Start of the move, m.
    pub start: f64,
    /// Target `z_t*`, m.
    pub target: f64,
    /// Duration of the move, s.
    pub duration: f64,
}

impl Reference {
    /// The reference at time `t` (s).
    pub fn at(&self, t: f64) -> RefPoint {
        let d = self.target - self.start;
        if t >= self.duration {
            return RefPoint { pos: self.target, vel: 0.0, acc: 0.0 };
        }
        let tau = if t > 0.0 { t / self.duration } else { 0.0 };
        let t2 = tau * tau;
        let s = t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2);
        let ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
        let dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2);
        RefPoint { pos: self.start + d * s, vel: d * ds / self.duration, acc: d * dds / (self.duration * self.duration) }
    }
}
