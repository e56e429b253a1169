//! What the plant reports: the events located in an interval ([`PlantEvent`],
//! [`EventKind`]), their counts since creation ([`Counters`]), and the report of
//! one `advance` ([`StepReport`]).

use serde::Serialize;
use shared::ContactMode;

use crate::impact::Resolution;

/// What happened at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// The tip reached the belt with normal velocity `v_n_before < 0` and an impact followed.
    Touchdown,
    /// The normal reaction vanished; the tip leaves the belt.
    LiftOff,
    /// `p` reached 0 while sliding with the reaction finite (`b` reaching 0 with it);
    /// an impact without collision follows.
    PZero,
    /// A dynamic jam: `p` fell to 0+ while sliding with `b < 0`, the reaction growing
    /// without bound (to `jam_load m g`); resolved by a tangential impact
    /// ([`crate::impact::jam`], resolution `tangential_impact`).
    Jam,
    /// An impact without collision from an inconsistent sliding state.
    ImpactWithoutCollision,
    /// A slide reached the singular point `p = 0, b = 0` with a finite normal
    /// force where the event-driven step collapsed: crossed by a Moreau-Jean
    /// bridge under the singular rule ([`crate::moreau_jean::SingularRule`]).
    SingularPoint,
    /// The event-driven step collapsed away from the jam and the singular point:
    /// a stretch of Moreau-Jean time-stepping crossed the difficulty
    /// (docs/plant.md "The bridge"). Reported at the bridge's start, with the
    /// velocities before it and after it.
    Bridge,
    /// The slip stopped and the tip sticks to the belt.
    SlipToStick,
    /// The slip stopped and resumed the other way.
    SlipReversal,
    /// The friction force reached the cone's edge; the tip starts to slip.
    StickToSlip,
    /// The Zeno rule ended a bounce sequence (or a grazing touchdown): the tip stays in contact.
    ZenoEnded,
    /// A velocity projection onto the contact constraint at an event, beyond
    /// rounding (a small slip stopped at rest, the remains of an impulse): its
    /// impulse and energy change, so that the table books every impulse (issue 67).
    /// The Zeno rule's projection is booked on its `zeno_ended` row.
    VelocityProjection,
    /// One step of a bridge's Moreau-Jean time-stepping whose contact impulse is an
    /// impulse, not a force: at least [`crate::BRIDGE_IMPULSE_LOAD`] times `m g`
    /// over the step (an impact, the slip stopped at the singular point), booked as
    /// acting at the step's start with its impulse and kinetic energy change, so that the
    /// table books it (issue 81; the trace shows no force for that step).
    BridgeImpulse,
    /// An impact created energy at the contact (positive contact work; reported, not corrected).
    EnergyGain,
    /// At rest on the belt with no consistent contact force (see the crate docs).
    ConeViolation,
}

impl EventKind {
    /// snake_case name, as in `events.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Touchdown => "touchdown",
            Self::LiftOff => "lift_off",
            Self::PZero => "p_zero",
            Self::Jam => "jam",
            Self::ImpactWithoutCollision => "impact_without_collision",
            Self::SingularPoint => "singular_point",
            Self::Bridge => "bridge",
            Self::SlipToStick => "slip_to_stick",
            Self::SlipReversal => "slip_reversal",
            Self::StickToSlip => "stick_to_slip",
            Self::ZenoEnded => "zeno_ended",
            Self::VelocityProjection => "velocity_projection",
            Self::BridgeImpulse => "bridge_impulse",
            Self::EnergyGain => "energy_gain",
            Self::ConeViolation => "cone_violation",
        }
    }
}

/// An event with its exact time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlantEvent {
    /// Time, s.
    pub t: f64,
    /// What happened.
    pub kind: EventKind,
    /// Mode after the event.
    pub mode_after: ContactMode,
    /// Tip normal velocity before the event, m/s.
    pub v_n_before: f64,
    /// Tip normal velocity after the event, m/s.
    pub v_n_after: f64,
    /// Relative tangential velocity before the event, m/s.
    pub v_r_before: f64,
    /// Relative tangential velocity after the event, m/s.
    pub v_r_after: f64,
    /// Impulse `[P_t, P_n]` (N s) if the event is an impact, else zero.
    pub impulse: [f64; 2],
    /// Change of the arm's kinetic energy across the event, J (0 if not an impact;
    /// may be positive: the moving belt can feed the arm).
    pub energy_change: f64,
    /// Work of the contact impulse on the relative motion, J (<= 0 for an admissible
    /// impact; see [`impact::Impulse::contact_work`](crate::impact::Impulse::contact_work)).
    pub contact_work: f64,
    /// How the impulse was obtained, for impacts.
    pub resolution: Option<Resolution>,
}

/// Counts of events since the plant was created.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Counters {
    /// Lift-offs (the tip leaving the belt after being in contact, including after an IWC or a bounce).
    pub lift_offs: u64,
    /// Touchdowns with an impact.
    pub touchdowns: u64,
    /// Touchdowns after which the tip flew off again at once (a bounce: the tip
    /// leaves the belt without a `lift_offs` event).
    pub bounces: u64,
    /// Impacts without collision.
    pub impacts_without_collision: u64,
    /// Times `p` reached 0 while sliding with the reaction finite.
    pub p_zero: u64,
    /// Dynamic jams: times the reaction grew without bound as `p -> 0+` while
    /// sliding, each resolved by a tangential impact ([`EventKind::Jam`]).
    pub jams: u64,
    /// Of [`Counters::jams`], those detected where the integrator's step size
    /// collapsed before `f_n` reached `jam_load m g` (the slide already jamming:
    /// `p > 0`, `b < 0`, `f_n >= 10 m g`).
    pub jams_at_collapse: u64,
    /// Crossings of the singular point's neighbourhood decided by the slide's own
    /// limit (docs/plant.md "The singular point"; [`crate::segment::Crossing`]): a
    /// located `p = 0`, or a located lift-off with `p / Q_22` within 1e-6 of 0,
    /// resolved as [`Crossing::Arrested`](crate::segment::Crossing::Arrested) (the impact
    /// without collision at `p = 0`; also in [`Counters::p_zero`]).
    pub corners_arrested: u64,
    /// Such crossings resolved as a lift-off with the slip kept (the force reached 0
    /// before `p`; also in [`Counters::lift_offs`]).
    pub corners_lifted_off: u64,
    /// Such crossings resolved as the dynamic jam (the force grew without bound; also
    /// in [`Counters::jams`]).
    pub corners_jammed: u64,
    /// Singular points: slides that reached `p = 0, b = 0` with a finite normal
    /// force where the event-driven step collapsed ([`EventKind::SingularPoint`]),
    /// each crossed by a bridge (also counted in [`Counters::bridges`]).
    pub singular_points: u64,
    /// Moreau-Jean bridges: stretches of time-stepping across a collapsed
    /// event-driven step (at singular points and elsewhere).
    pub bridges: u64,
    /// Time spent in bridges, s.
    pub bridged_s: f64,
    /// Sticking phases entered.
    pub stick_phases: u64,
    /// Stick-to-slip transitions.
    pub stick_to_slip: u64,
    /// Slip reversals.
    pub slip_reversals: u64,
    /// Bounce sequences ended by the Zeno rule: a touchdown that left (or arrived
    /// with) a normal velocity below `zeno_velocity` but above rounding, removed.
    pub zeno_stops: u64,
    /// Impacts whose contact work was positive (energy created at the contact):
    /// 0 unless an impact law is broken, since the laws fall back to the energetic one.
    pub energy_gains: u64,
    /// Newton impacts whose impulse would have created energy, resolved by the
    /// energetic law instead ([`impact::Resolution::NewtonFallback`](crate::impact::Resolution::NewtonFallback)).
    pub newton_fallbacks: u64,
    /// Poisson impacts whose impulse would have created energy, resolved by the
    /// energetic law instead ([`impact::Resolution::PoissonFallback`](crate::impact::Resolution::PoissonFallback)).
    pub poisson_fallbacks: u64,
    /// Largest positive contact work in one impact, J.
    pub max_energy_gain: f64,
    /// Cone violations (crate docs, corner case).
    pub cone_violations: u64,
    /// Smooth segments integrated.
    pub segments: u64,
}

/// What `advance` reports about one interval.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepReport {
    /// Time at the end of the interval, s.
    pub t: f64,
    /// Contact mode at the end.
    pub mode: ContactMode,
    /// State `[theta1, theta1_dot, theta2, theta2_dot]` at the end (rad, rad/s).
    pub x: [f64; 4],
    /// Contact force `[f_t, f_n]` at the end (N), under the interval's torque.
    pub f: [f64; 2],
    /// Events in the interval, in time order.
    pub events: Vec<PlantEvent>,
}
