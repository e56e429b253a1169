//! How a run of a sweep ended up ([`Outcome`]: the paper's classes open loop, what
//! happened closed loop) and its row of `runs.csv` ([`RunRow`]); re-exported by
//! [`super::run`], which computes them.

use serde::{Deserialize, Serialize};
use shared::ContactMode;

use plant::{Validity, impact::IwcRule};

/// Closed loop: how far from `z_t*` (m) the tip may end and still count as having
/// reached its target ([`Outcome::TargetNotReached`] beyond it). 5 mm: five times the
/// PID's steady tracking error from `x0d` (about 1 mm, docs/results.md), far below
/// the misses it exists to name (the sampled hybrid loop at `mu = 1` ends 0.24 m short).
pub const TARGET_TOL_M: f64 = 5e-3;

/// How a run ended up in its record window.
///
/// Open loop (no controller) uses the paper's classes, built on its indicator
/// `max theta1_dot > threshold` (Fig. 3): [`Outcome::Bouncing`],
/// [`Outcome::Oscillating`], [`Outcome::LiftOffOnly`], [`Outcome::Contact`],
/// [`Outcome::Flight`]. In closed loop that indicator measures controller dither as
/// much as bouncing (a tip sliding steadily under the sampled hybrid law dithers
/// `theta1_dot` by about 9 mrad/s), so closed-loop runs say what happened instead:
/// [`Outcome::LiftOff`], [`Outcome::TargetNotReached`], [`Outcome::Contact`],
/// [`Outcome::Flight`], [`Outcome::SafeState`]. Both share
/// [`Outcome::Failed`] and [`Outcome::Invalid`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Persistent bouncing: the indicator above the threshold and the tip leaving
    /// the belt in the record window.
    Bouncing,
    /// The indicator above the threshold without any lift-off in the record window
    /// (an oscillation on the belt, or a swing in the air that never lands).
    Oscillating,
    /// Lift-offs in the record window with the indicator at or below the threshold.
    LiftOffOnly,
    /// Closed loop: the tip left the belt in the record window (a lift-off, whatever
    /// `theta1_dot` did; `tip_height_max` says how high it went).
    LiftOff,
    /// Closed loop: on the belt with no lift-off in the record window, but the tip
    /// ended more than [`TARGET_TOL_M`] from `z_t*` (`target_error_m`).
    TargetNotReached,
    /// At rest in contact (steady sliding or sticking): no bouncing. In closed
    /// loop: on the belt, no lift-off in the record window, and within
    /// [`TARGET_TOL_M`] of `z_t*`, controller dither included.
    Contact,
    /// Off the belt and at rest (the tip left it and stayed in the air).
    Flight,
    /// Closed loop: the firmware latched its safe state (the run stops there), or
    /// the ideal law met a fault (singular arm, unreachable reference) and output
    /// zero torque from then on.
    SafeState,
    /// The simulation failed (see `error`).
    Failed,
    /// The run finished but its trajectory violates the model (an energy-creating
    /// impact or a friction-cone violation; see the validity columns): never
    /// counted as bouncing or contact.
    Invalid,
}

impl Outcome {
    /// snake_case name, as in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bouncing => "bouncing",
            Self::Oscillating => "oscillating",
            Self::LiftOffOnly => "lift_off_only",
            Self::LiftOff => "lift_off",
            Self::TargetNotReached => "target_not_reached",
            Self::Contact => "contact",
            Self::Flight => "flight",
            Self::SafeState => "safe_state",
            Self::Failed => "failed",
            Self::Invalid => "invalid",
        }
    }

    /// Every outcome, in legend order.
    pub const ALL: [Outcome; 10] = [
        Self::Bouncing,
        Self::Oscillating,
        Self::LiftOffOnly,
        Self::LiftOff,
        Self::TargetNotReached,
        Self::Contact,
        Self::Flight,
        Self::SafeState,
        Self::Failed,
        Self::Invalid,
    ];

    /// The outcomes an open-loop sweep can give (its figures' legend, in order).
    pub const OPEN_LOOP: [Outcome; 8] =
        [Self::Bouncing, Self::Oscillating, Self::LiftOffOnly, Self::Contact, Self::Flight, Self::SafeState, Self::Failed, Self::Invalid];

    /// The outcomes a closed-loop sweep (sampled firmware or ideal law) can give.
    pub const CLOSED_LOOP: [Outcome; 7] =
        [Self::LiftOff, Self::TargetNotReached, Self::Contact, Self::Flight, Self::SafeState, Self::Failed, Self::Invalid];

    /// Whether the tip kept leaving the belt in the record window: open loop's
    /// [`Outcome::Bouncing`] (the paper's persistent bouncing) or closed loop's
    /// [`Outcome::LiftOff`].
    pub fn is_bouncing(self) -> bool {
        matches!(self, Self::Bouncing | Self::LiftOff)
    }
}

/// One row of `runs.csv` / `sweep.csv`: a run's result. Every field is a function
/// of the sweep's spec and the run's index (no timings), so a resumed, sharded or
/// merged sweep gives the same rows as one uninterrupted run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRow {
    /// Run index ([`SweepSpec::run_at`](super::SweepSpec::run_at)).
    pub index: usize,
    /// Impact law (`newton`, `poisson`, `energetic`).
    pub impact_law: String,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Impact-without-collision rule (`restitution`, `plastic`).
    pub iwc: IwcRule,
    /// Friction coefficient.
    pub mu: f64,
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Initial condition.
    pub ic: String,
    /// The seed's number (`0..seeds`; [`super::ensemble::Draw`]): 0 is the
    /// nominal run, the only one of a sweep of one seed.
    #[serde(default)]
    pub seed: usize,
    /// [`Outcome`] name.
    pub outcome: Outcome,
    /// The paper's open-loop indicator over its threshold, `theta1_dot_max >
    /// threshold` (the column was `bouncing`). In closed loop it measures the
    /// controller's dither as much as a bounce: whether the tip left the belt is
    /// the `outcome` and `lift_offs`.
    pub theta1_dot_over_threshold: bool,
    /// The paper's indicator: largest `theta1_dot` over the record window, rad/s.
    pub theta1_dot_max: f64,
    /// When it occurred, s.
    pub t_theta1_dot_max: f64,
    /// Times the tip left the belt in the record window: every departure, bounces
    /// included ([`crate::lift_offs::of`]).
    pub lift_offs: u64,
    /// Touchdowns (impacts) in the record window.
    pub touchdowns: u64,
    /// Impacts without collision (the Painlevé resolution) in the record window.
    pub impacts_without_collision: u64,
    /// Highest tip position `z_n` over the record window, m.
    pub z_n_max: f64,
    /// Highest tip height above the belt, `z_n_max + H`, m.
    pub tip_height_max: f64,
    /// Contact mode at the end.
    pub final_mode: String,
    /// Closed loop: `|z_t - z_t*|` at the end of the run, m (NaN in open loop, and
    /// for a run that stopped before its end).
    pub target_error_m: f64,
    /// Times the tip left the belt during the transient (every departure, as
    /// `lift_offs`).
    pub lift_offs_transient: u64,
    /// Model evaluations of the plant (a deterministic cost measure).
    pub rhs_evaluations: u64,
    /// Over the whole run: impacts that created energy (a violation).
    pub energy_gains: u64,
    /// Over the whole run: Newton impacts resolved by the energetic law.
    pub newton_fallbacks: u64,
    /// Over the whole run: Poisson impacts resolved by the energetic law.
    pub poisson_fallbacks: u64,
    /// Over the whole run: contacts held with the friction cone ignored (a violation).
    pub cone_violations: u64,
    /// Over the whole run: bounce sequences ended by the Zeno rule.
    pub zeno_stops: u64,
    /// Over the whole run: dynamic jams (`p -> 0+` with `b < 0` while sliding)
    /// resolved by a tangential impact (docs/plant.md "The jam corner"; not a violation).
    pub jams: u64,
    /// 1 if the integrator or the event handling failed (a violation; outcome `failed`).
    pub integrator_failures: u64,
    /// Over the whole run: energy-ledger entries whose balance refinement could not
    /// mend (a violation; docs/plant.md "The energy ledger").
    pub ledger_violations: u64,
    /// Over the whole run: the energy the moving belt put in, J.
    pub belt_j: f64,
    /// Over the whole run: the contact's work in the belt's frame (dissipated), J.
    pub slip_j: f64,
    /// Over the whole run: what the ledger leaves unexplained, J.
    pub ledger_residual_j: f64,
    /// The largest energy one event took from the belt, J.
    pub largest_event_belt_j: f64,
    /// Why the run failed (empty if it did not).
    pub error: String,
}

// `runs.csv` and `sweep.csv`: the columns serde writes, declared (CSV reader, Arrow schema).
tables::declare!(RunRow {
    index: int,
    impact_law: str,
    e_n: f64,
    iwc: str,
    mu: f64,
    v_belt: f64,
    ic: str,
    seed: int,
    outcome: str,
    theta1_dot_over_threshold: bool,
    theta1_dot_max: f64,
    t_theta1_dot_max: f64,
    lift_offs: int,
    touchdowns: int,
    impacts_without_collision: int,
    z_n_max: f64,
    tip_height_max: f64,
    final_mode: str,
    target_error_m: f64,
    lift_offs_transient: int,
    rhs_evaluations: int,
    energy_gains: int,
    newton_fallbacks: int,
    poisson_fallbacks: int,
    cone_violations: int,
    zeno_stops: int,
    jams: int,
    integrator_failures: int,
    ledger_violations: int,
    belt_j: f64,
    slip_j: f64,
    ledger_residual_j: f64,
    largest_event_belt_j: f64,
    error: str,
});

impl Outcome {
    /// The outcome of a run: `stopped` says whether it stopped early (`Some(true)`
    /// in the firmware's safe state or an ideal-law fault, `Some(false)` on a
    /// failure); a finished run with a model violation (`validity`) is
    /// [`Outcome::Invalid`] whatever it did; otherwise the paper's flag
    /// (`bouncing`), the lift-offs in the record window and the final `mode` decide.
    pub fn of(stopped: Option<bool>, validity: &Validity, bouncing: bool, lift_offs: u64, mode: ContactMode) -> Self {
        match stopped {
            Some(true) => Self::SafeState,
            Some(false) => Self::Failed,
            None if !validity.is_valid() => Self::Invalid,
            None => match (bouncing, lift_offs > 0) {
                (true, true) => Self::Bouncing,
                (true, false) => Self::Oscillating,
                (false, true) => Self::LiftOffOnly,
                (false, false) if mode == ContactMode::Flight => Self::Flight,
                (false, false) => Self::Contact,
            },
        }
    }
}

impl Outcome {
    /// The outcome of a closed-loop run: `stopped` and `validity` as in
    /// [`Outcome::of`]; then a lift-off in the record window is [`Outcome::LiftOff`],
    /// a tip that ended more than [`TARGET_TOL_M`] from `z_t*` (`target_error`, m)
    /// [`Outcome::TargetNotReached`], a tip in the air [`Outcome::Flight`], and the
    /// rest [`Outcome::Contact`].
    pub fn of_closed_loop(stopped: Option<bool>, validity: &Validity, lift_offs: u64, target_error: f64, mode: ContactMode) -> Self {
        match stopped {
            Some(true) => Self::SafeState,
            Some(false) => Self::Failed,
            None if !validity.is_valid() => Self::Invalid,
            None if lift_offs > 0 => Self::LiftOff,
            None if mode == ContactMode::Flight => Self::Flight,
            None if target_error.is_nan() || target_error > TARGET_TOL_M => Self::TargetNotReached,
            None => Self::Contact,
        }
    }
}

impl RunRow {
    /// The run's validity counters ([`plant::Validity`]); the rows do not carry the
    /// singular points and bridges (0 here: a column would change the row layout,
    /// `FORMAT`).
    pub fn validity(&self) -> Validity {
        Validity {
            energy_gains: self.energy_gains,
            newton_fallbacks: self.newton_fallbacks,
            poisson_fallbacks: self.poisson_fallbacks,
            cone_violations: self.cone_violations,
            zeno_stops: self.zeno_stops,
            integrator_failures: self.integrator_failures,
            ledger_violations: self.ledger_violations,
            ..Validity::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_violation_is_invalid_never_bouncing_or_contact() {
        let clean = Validity { zeno_stops: 3, newton_fallbacks: 2, ..Validity::default() };
        let cone = Validity { cone_violations: 1, ..Validity::default() };
        let energy = Validity { energy_gains: 1, ..Validity::default() };
        assert_eq!(Outcome::of(None, &clean, true, 4, ContactMode::Flight), Outcome::Bouncing);
        assert_eq!(Outcome::of(None, &clean, false, 0, ContactMode::Sliding), Outcome::Contact);
        for v in [cone, energy] {
            assert_eq!(Outcome::of(None, &v, true, 4, ContactMode::Flight), Outcome::Invalid);
            assert_eq!(Outcome::of(None, &v, false, 0, ContactMode::Sliding), Outcome::Invalid);
        }
        // A run that stopped keeps its own outcome (its failure is the violation).
        let failed = Validity { integrator_failures: 1, ..Validity::default() };
        assert_eq!(Outcome::of(Some(false), &failed, false, 0, ContactMode::Sliding), Outcome::Failed);
        assert_eq!(Outcome::of(Some(true), &clean, false, 0, ContactMode::Sliding), Outcome::SafeState);
    }

    #[test]
    fn closed_loop_outcomes_say_what_happened() {
        let clean = Validity { zeno_stops: 3, ..Validity::default() };
        let cone = Validity { cone_violations: 1, ..Validity::default() };
        let of = Outcome::of_closed_loop;
        // Steady sliding with dither, on target: contact (never "oscillating").
        assert_eq!(of(None, &clean, 0, 1e-3, ContactMode::Sliding), Outcome::Contact);
        assert_eq!(of(None, &clean, 0, 0.24, ContactMode::Sliding), Outcome::TargetNotReached);
        assert_eq!(of(None, &clean, 0, f64::NAN, ContactMode::Sticking), Outcome::TargetNotReached);
        assert_eq!(of(None, &clean, 3, 1e-3, ContactMode::Sliding), Outcome::LiftOff);
        assert_eq!(of(None, &clean, 0, 1e-3, ContactMode::Flight), Outcome::Flight);
        assert_eq!(of(Some(true), &clean, 3, 0.2, ContactMode::Flight), Outcome::SafeState);
        assert_eq!(of(Some(false), &clean, 0, 0.0, ContactMode::Sliding), Outcome::Failed);
        assert_eq!(of(None, &cone, 3, 0.2, ContactMode::Flight), Outcome::Invalid);
        assert!(Outcome::LiftOff.is_bouncing() && Outcome::Bouncing.is_bouncing());
        assert!(!Outcome::Oscillating.is_bouncing() && !Outcome::TargetNotReached.is_bouncing());
    }
}
