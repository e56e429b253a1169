//! The tangential reference `z_t*(t)`: a quintic move from the initial tip
//! position to the target over a set time, then a hold (docs/model.md leaves the
//! reference to us). The quintic `s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5` has zero
//! velocity and acceleration at both ends (minimum-jerk; Flash and Hogan 1985).

/// Position, velocity and acceleration of the reference at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefPoint {
    /// `z_t*`, m.
    pub pos: f32,
    /// `z_t_dot*`, m/s.
    pub vel: f32,
    /// `z_t_ddot*`, m/s^2.
    pub acc: f32,
    /// Whether the move is still under way.
    pub moving: bool,
}

/// A quintic move from `start` to `target` (m) over `duration` (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quintic {
    /// Start, m.
    pub start: f32,
    /// Target, m.
    pub target: f32,
    /// Duration, s (> 0).
    pub duration: f32,
}

impl Quintic {
    /// The reference `t` s after the start of the move (holds at the target after `duration`).
    pub fn at(&self, t: f32) -> RefPoint {
        let d = self.target - self.start;
        if t >= self.duration {
            return RefPoint { pos: self.target, vel: 0.0, acc: 0.0, moving: false };
        }
        let tau = if t > 0.0 { t / self.duration } else { 0.0 };
        let (t2, t3) = (tau * tau, tau * tau * tau);
        let s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
        let ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
        let dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2);
        RefPoint { pos: self.start + d * s, vel: d * ds / self.duration, acc: d * dds / (self.duration * self.duration), moving: true }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences_and_ends_are_at_rest() {
        let q = Quintic { start: -0.16, target: 0.1, duration: 2.0 };
        let h = 1e-3;
        for i in 1..199 {
            let t = i as f32 * 0.01;
            let (a, b, c) = (q.at(t - h), q.at(t), q.at(t + h));
            assert!(((c.pos - a.pos) / (2.0 * h) - b.vel).abs() < 1e-3);
            assert!(((c.vel - a.vel) / (2.0 * h) - b.acc).abs() < 1e-2);
        }
        let s = q.at(0.0);
        assert_eq!((s.pos, s.vel, s.acc), (-0.16, 0.0, 0.0));
        let e = q.at(2.0);
        assert_eq!((e.pos, e.vel, e.acc, e.moving), (0.1, 0.0, 0.0, false));
        assert!((q.at(1.0).pos + 0.03).abs() < 1e-6, "midpoint is halfway");
    }
}
