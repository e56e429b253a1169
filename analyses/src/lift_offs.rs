//! What `lift_offs` counts, in every output (issue 67: one name, one meaning):
//! every departure of the tip from the belt.
//!
//! The plant counts departures in two counters ([`plant::Counters`]):
//! `lift_offs`, the departures of a tip that was in contact (the reaction
//! vanishing while sliding, an impact without collision or a jam that throws the
//! tip off, a singular point left into flight, flight chosen after a touchdown
//! whose bounce sequence ended), and `bounces`, the touchdowns after which the
//! tip flew off at once. A run bouncing from `x0a` has one of the first (its
//! impact without collision at `t = 0`) and all the rest of the second. The
//! outputs (`simulate`'s `summary.json` and printed summary, `sweep.csv`,
//! `poincare`'s `classes.csv`, `zmax`'s `trials.csv`, the report, the Python
//! package) publish their sum as `lift_offs`; where the plant's own split is
//! published, its `lift_offs` is `lift_offs_from_contact` (docs/plant.md
//! "Counting lift-offs").

use plant::Counters;

/// Every departure of the tip from the belt counted in `c`, the `lift_offs` of
/// every output: the plant's `lift_offs` (departures of a tip in contact) plus
/// its `bounces` (departures at a touchdown's rebound); the two never count the
/// same departure (docs/plant.md "Counting lift-offs").
pub fn of(c: &Counters) -> u64 {
    c.lift_offs + c.bounces
}

#[cfg(test)]
mod tests {
    use plant::{Hold, NoObserver, Plant, SimConfig, impact::IwcRule};
    use shared::{ContactMode, Params};

    /// Every departure counted once: the flights the plant enters by an event (a
    /// lift-off, a singular point left into flight, an impact, an impact without
    /// collision or a jam that leaves the tip faster than the Zeno rule's
    /// velocity), counted from the events, are the published count. On the bounce from `x0a` (its impact
    /// without collision at `t = 0`, then rebounds: the plant's `lift_offs` 1, the
    /// rest `bounces`), on the same start at `e_n = 0` under the plastic rule
    /// (departures from contact only, then a slide) and on issue 53's arm at
    /// `mu` 0.422, whose orbit passes the singular point under the plastic rule.
    #[test]
    fn every_departure_is_counted_once() {
        let paper = Params::<f64> { mu: 0.6, v_belt: -0.5, ..Params::paper() };
        let x0a = plant::initial::deg_to_state(plant::initial::PaperX0::A.condition().deg);
        let issue53 = Params::<f64> { m: 0.15, l: 0.23, sigma: 0.008, k: 1.0, h: 0.40, alpha0: 0.2, mu: 0.422, v_belt: -0.5, ..paper };
        let x53 = [34.53531701873741f64.to_radians(), 0.0, 23.744016380660902f64.to_radians(), 0.0];
        let runs = [
            ("x0a", paper, 0.2, IwcRule::Restitution, x0a, 50),
            ("x0a, e_n = 0", paper, 0.0, IwcRule::Plastic, x0a, 5),
            ("issue 53", issue53, 0.2, IwcRule::Plastic, x53, 50),
        ];
        for (name, params, e_n, iwc, x0, at_least) in runs {
            let sim = SimConfig { e_n, iwc, ..SimConfig::default() };
            let mut p = Plant::new(params, sim, x0, 0.0, [0.0, 0.0]).unwrap();
            let mut events = p.startup_events().to_vec();
            events.extend(p.advance(&Hold([0.0, 0.0]), 20.0, &mut NoObserver).unwrap().events);
            let c = p.counters();
            use plant::EventKind::*;
            let into_flight = events
                .iter()
                .filter(|e| match e.kind {
                    LiftOff => e.mode_after == ContactMode::Flight,
                    SingularPoint => e.mode_after == ContactMode::Flight,
                    // An impact leaves the tip in flight when it leaves it faster
                    // than the Zeno rule's velocity (its event may be written
                    // before the contact mode is chosen: the velocity says).
                    Touchdown | ImpactWithoutCollision | Jam => e.v_n_after > sim.zeno_velocity,
                    _ => false,
                })
                .count() as u64;
            assert!(super::of(c) >= at_least, "{name}: {c:?}");
            assert!(name != "issue 53" || c.singular_points > 0, "the orbit passes the singular point: {c:?}");
            assert_eq!(super::of(c), into_flight, "{name}: {c:?}");
        }
    }
}
