//! A slide's approach to the singular point `p = b = 0` (issue 81; docs/plant.md
//! "The singular point: the slide's own limit"), and the rule that decides the
//! crossing from it.
//!
//! Near the point the slide's normal dynamics is `p_dot = A` and `b_dot = alpha +
//! beta f_n`, with `f_n = -b/p` (Génot and Brogliato, "New results on Painlevé
//! paradoxes", Eur. J. Mech. A/Solids 18, 1999, sec. 4). With `tau = t* - t` and `A < 0`
//! (`p` falling, `p = |A| tau`) this is `db/dtau = -alpha + k b / tau` with the order
//! `k = beta / |A|`, whose solutions are
//!
//! ```text
//! b = alpha / (k - 1) tau + C tau^k,   f_n = -b/p = f_inf - (C / |A|) tau^(k - 1),
//! f_inf = -alpha / (beta - |A|).
//! ```
//!
//! - `k > 1`: the `tau^(k-1)` term vanishes; the force tends to `f_inf` whatever `C`. With
//!   `f_inf > 0` (`alpha < 0`) the slide is **attracted** into the point with a finite force,
//!   and `b` reaches 0 only with `p` (a located `b = 0` there is the integration's
//!   residue): the impact without collision stops the slip. With `f_inf <= 0` the force
//!   reaches 0 before `p` does: a **lift-off**, the slip kept.
//! - `k < 1`: the `tau^(k-1)` term grows without bound unless `C = 0`: the force reaches 0
//!   first (`C > 0`: a lift-off, the slip kept) or grows without bound (`C < 0`: the
//!   dynamic **jam**, the tangential impact), and the side of `f_inf` the force is on as
//!   the slide approaches says which (`f_n - f_inf` keeps its sign). `C = 0` is a slide held at a finite force (a law that regulates `f_n`, as the
//!   paper's hybrid law does in continuous time): attracted, as above. The slide's force
//!   on its approach (the trend, [`super::TREND_P`]) tells `C = 0` from the rest: it equals
//!   `f_inf` down to [`HELD_P`].

use nalgebra::Vector2;
use shared::Arm;

use super::{OdeState, Phase, Segment, Trend, split};
use crate::controller::Controller;

/// The `p / Q_22` below which a slide's force can no longer be told from its limit:
/// a slide of order `k < 1` whose force would depart from its limit `f_inf` by `f_inf`
/// only below this `p` (reaching 0 there, a lift-off, or doubling, towards the jam) is
/// held at its finite force as far as the integration resolves, and is arrested. The
/// integration's residue in `b` is about 1e-9 to 1e-8 m/s^2 (issue 53: `f_n = -b/p`
/// 1.4e3 N at `p / Q_22 = 6.5e-13`), which is a newton of force at `p` of order 1e-9
/// of `Q_22` (1 to 20 /kg over the envelope).
pub const HELD_P: f64 = 1e-9;

/// The time step of the central differences along the flow, s: `|q_dot| h` is at most
/// 1e-5 rad for the envelope's 10 rad/s, so the truncation (`h^2` times the third
/// derivative) and the rounding (`1e-16 |b| / h`) are both below 1e-9 of the terms.
const FLOW_STEP: f64 = 1e-6;

/// The slide's normal dynamics at a state near the singular point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Approach {
    /// `A = dp/dt` along the flow, 1/(kg s) (`p` is the paper's eq. 7, in 1/kg).
    pub p_dot: f64,
    /// `alpha = db/dt` with no normal force, m/s^3.
    pub alpha: f64,
    /// `beta = d(db/dt)/d f_n`, m/(s^3 N): the change of `b_dot` per newton of normal
    /// force (the friction `-mu s f_n` with it).
    pub beta: f64,
}

/// How a crossing of the singular point's neighbourhood is resolved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crossing {
    /// The slide reaches `p = 0` with a finite force: the impact without collision at
    /// `p = 0` stops the slip (`impact::at_p_zero`).
    Arrested,
    /// The force reaches 0 before `p` does: a lift-off with the slip kept.
    LiftOff,
    /// The force grows without bound as `p -> 0`: the dynamic jam, resolved by the
    /// tangential impact (`impact::jam`; at `p = 0` the same impulse as `Arrested`'s).
    Jam,
}

impl Approach {
    /// The order `k = beta / |A|` of the approach (dimensionless; NaN or infinite when
    /// `A = 0`).
    pub fn order(&self) -> f64 {
        self.beta / self.p_dot.abs()
    }

    /// The force's limit `f_inf = -alpha / (beta - |A|)`, N: the limit as `p -> 0` when
    /// [`Approach::order`] exceeds 1, the force a held slide keeps otherwise.
    pub fn limit_force(&self) -> f64 {
        -self.alpha / (self.beta - self.p_dot.abs())
    }

    /// The crossing (module docs). `trend`: the slide's force on its approach
    /// ([`super::EventLocator::trend`]; `None` when the slide started within
    /// [`super::TREND_P`] of the point); `located_lift_off`: whether the located root was
    /// `b = 0` (else `p = 0`, or the step's collapse at the point).
    ///
    /// - order `k > 1`: arrested where the limit `f_inf` is positive, else a lift-off;
    /// - `k < 1`: arrested where the force stays at its limit down to [`HELD_P`]; else a
    ///   lift-off where the force falls below its limit on the approach, the jam where it
    ///   rises above it, whichever root was located; with no trend, the located root
    ///   (`b = 0` a lift-off, `p = 0` the jam);
    /// - `p` not falling (a tangent approach) or a model that is not finite: the located
    ///   root (a lift-off, or the impact without collision at `p = 0`).
    pub fn crossing(&self, trend: Option<Trend>, located_lift_off: bool) -> Crossing {
        let (k, f_inf) = (self.order(), self.limit_force());
        if !(self.p_dot < 0.0 && k.is_finite() && f_inf.is_finite()) {
            return if located_lift_off { Crossing::LiftOff } else { Crossing::Arrested };
        }
        if k > 1.0 {
            return if f_inf > 0.0 { Crossing::Arrested } else { Crossing::LiftOff };
        }
        match trend {
            Some(tr) if f_inf > 0.0 && departure_scale(tr, f_inf, k) <= HELD_P => Crossing::Arrested,
            // The force departs from its limit monotonically (`C tau^(k - 1)`): the side it
            // was on during the approach is the side it leaves by, whichever root the
            // locator met (a `b = 0` located with the force rising is `b = -f_n p` at a
            // `p` within the locator's tolerance).
            Some(tr) if tr.f_n < f_inf => Crossing::LiftOff,
            Some(_) => Crossing::Jam,
            None if located_lift_off => Crossing::LiftOff,
            None => Crossing::Jam,
        }
    }
}

/// The `p / Q_22` below which a slide of order `k < 1` departs from its limit `f_inf`
/// (N) by more than `f_inf` itself, from its force on the approach: `f_n - f_inf`
/// grows like `p^(k - 1)`, so `p_c = p_trend (|f_trend - f_inf| / f_inf)^(1 / (1 - k))`
/// (0 for a slide held exactly at its limit).
fn departure_scale(trend: Trend, f_inf: f64, k: f64) -> f64 {
    trend.p * ((trend.f_n - f_inf).abs() / f_inf).powf(1.0 / (1.0 - k))
}

impl<C: Controller + ?Sized> Segment<'_, C> {
    /// The slide's [`Approach`] at `(t, y)`, by central differences along the flow
    /// (step [`FLOW_STEP`]): `p` at `q -+ h q_dot`; `b` at the state moved by `-+ h`
    /// times its rate with the normal force 0 and 1 N (and the friction with it), the
    /// law's torque evaluated there (a held torque stays). `None` outside a slide.
    pub fn approach(&self, t: f64, y: &OdeState) -> Option<Approach> {
        let Phase::Sliding(dir) = self.phase else { return None };
        let arm: &Arm<f64> = self.arm;
        let (q, qd) = split(y);
        let mut xi_dot = [0.0; 2];
        let (td, _, _) = self.evaluate(t, y, &mut xi_dot);
        let h = FLOW_STEP;
        let p_at = |q: Vector2<f64>| arm.p(&q, dir);
        let p_dot = (p_at(q + qd * h) - p_at(q - qd * h)) / (2.0 * h);
        let unit = Vector2::new(-arm.params.mu * dir.sign::<f64>(), 1.0);
        let b_rate = |f_n: f64| {
            let qdd = td.qdd_with_force(&(unit * f_n));
            let b_at = |s: f64| {
                let (qs, qds) = (q + qd * (s * h), qd + qdd * (s * h));
                let x = [qs[0], qds[0], qs[1], qds[1]];
                let xi = [y[4] + s * h * xi_dot[0], y[5] + s * h * xi_dot[1]];
                let motor = self.ctrl.torque_in(self.phase, t + s * h, &x, &xi, &mut [0.0; 2]);
                arm.b(&qs, &qds, &Arm::generalised_torque(&Vector2::new(motor[0], motor[1])))
            };
            (b_at(1.0) - b_at(-1.0)) / (2.0 * h)
        };
        let alpha = b_rate(0.0);
        let beta = b_rate(1.0) - alpha;
        Some(Approach { p_dot, alpha, beta })
    }
}
