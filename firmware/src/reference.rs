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

/// A quintic move from `start` to `target` (m) over `duration` (s), made by
/// [`Quintic::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quintic {
    start: f32,
    target: f32,
    duration: f32,
    /// `1 / duration`, 1/s: the step multiplies by it (a `VDIV.F32` is 14 cycles on
    /// the Cortex-M4F, a multiply 1; exact for a power-of-two duration such as
    /// the defaults, 2 s and 0.25 s).
    rate: f32,
}

impl Quintic {
    /// The move from `start` to `target` (m) over `duration` (s, > 0: the
    /// configuration checks it).
    pub fn new(start: f32, target: f32, duration: f32) -> Self {
        Self::with_rate(start, target, duration, 1.0 / duration)
    }

    /// [`Quintic::new`] with `rate = 1 / duration` (1/s) given: a caller that
    /// starts moves of one duration derives it once. The same reference when
    /// `rate` is `1.0 / duration`.
    #[inline]
    pub fn with_rate(start: f32, target: f32, duration: f32, rate: f32) -> Self {
        Self { start, target, duration, rate }
    }

    /// The reference `t` s after the start of the move (holds at the target after `duration`).
    pub fn at(&self, t: f32) -> RefPoint {
        self.at_with(t, true)
    }

    /// [`Quintic::at`], its acceleration only when `with_acc` (else 0): the PID
    /// uses none, and its step saves the products (issue 56). Position, velocity
    /// and `moving` have the bits of [`Quintic::at`] either way.
    #[inline(always)]
    pub fn at_with(&self, t: f32, with_acc: bool) -> RefPoint {
        let d = self.target - self.start;
        if t >= self.duration {
            return RefPoint { pos: self.target, vel: 0.0, acc: 0.0, moving: false };
        }
        let tau = if t > 0.0 { t * self.rate } else { 0.0 };
        let (t2, t3) = (tau * tau, tau * tau * tau);
        let s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
        let ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
        let acc = if with_acc { d * (60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2)) * (self.rate * self.rate) } else { 0.0 };
        RefPoint { pos: self.start + d * s, vel: d * ds * self.rate, acc, moving: true }
    }

    /// The position of [`Quintic::at`] alone (the same bits), m: the force ramp
    /// uses no derivative, and the step saves computing them.
    #[inline]
    pub fn pos_at(&self, t: f32) -> f32 {
        if t >= self.duration {
            return self.target;
        }
        let tau = if t > 0.0 { t * self.rate } else { 0.0 };
        let (t2, t3) = (tau * tau, tau * tau * tau);
        self.start + (self.target - self.start) * (t3 * (10.0 - 15.0 * tau + 6.0 * t2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences_and_ends_are_at_rest() {
        let q = Quintic::new(-0.16, 0.1, 2.0);
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

    /// Multiplying by `1 / duration` agrees with dividing by it to a few roundings
    /// of the peak velocity, and exactly for a power-of-two duration.
    #[test]
    fn the_position_alone_has_the_bits_of_the_whole_point() {
        for (start, target, duration) in [(-0.16f32, 0.1f32, 2.0f32), (3.0, 10.0, 0.25), (10.0, 0.0, 0.3), (0.05, -0.12, 1.7)] {
            let q = Quintic::new(start, target, duration);
            for i in -10..=1100 {
                let t = duration * i as f32 / 1000.0;
                assert_eq!(q.pos_at(t).to_bits(), q.at(t).pos.to_bits(), "{start} to {target} over {duration} s at {t} s");
            }
        }
    }

    /// Without the acceleration (the PID's reference) the position, velocity and
    /// `moving` keep [`Quintic::at`]'s bits; the acceleration is then 0.
    #[test]
    fn the_point_without_acceleration_keeps_the_others_bits() {
        for (start, target, duration) in [(-0.16f32, 0.1f32, 2.0f32), (3.0, 10.0, 0.25), (10.0, 0.0, 0.3), (0.05, -0.12, 1.7)] {
            let q = Quintic::new(start, target, duration);
            for i in -10..=1100 {
                let t = duration * i as f32 / 1000.0;
                let (a, b) = (q.at(t), q.at_with(t, false));
                assert_eq!((a.pos.to_bits(), a.vel.to_bits(), a.moving), (b.pos.to_bits(), b.vel.to_bits(), b.moving), "{t} s");
                assert_eq!(b.acc, 0.0);
                assert_eq!(q.at_with(t, true), a);
            }
        }
    }

    #[test]
    fn the_rate_is_the_division_to_rounding() {
        let exact = |q: &Quintic, t: f32| {
            let tau = t / q.duration;
            let d = q.target - q.start;
            let t2 = tau * tau;
            let ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
            d * ds / q.duration
        };
        for duration in [2.0f32, 0.25, 0.3, 1.7] {
            let q = Quintic::new(0.05, -0.12, duration);
            for i in 1..100 {
                let t = duration * i as f32 / 100.0;
                let (v, e) = (q.at(t).vel, exact(&q, t));
                if duration == 2.0 || duration == 0.25 {
                    assert_eq!(v.to_bits(), e.to_bits(), "duration {duration}, t {t}");
                } else {
                    // Both within a few roundings of the peak velocity 1.875 |d| / duration.
                    let peak = 1.875 * 0.17 / duration;
                    assert!((v - e).abs() <= 16.0 * f32::EPSILON * peak, "duration {duration}, t {t}: {v} against {e}");
                }
            }
        }
    }
}
