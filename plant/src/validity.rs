//! The validity counters of a simulation: what says whether its result can be
//! trusted, carried by every command's summary, sweep row, `Z_t,sliding` trial
//! and Poincaré point (docs/plant.md "Validity").
//!
//! A *violation* is a result the model's laws do not allow: an impact that created
//! energy (never expected: the laws fall back to the energetic one), a contact held
//! with the friction cone ignored (the documented corner case), or a run the
//! integrator could not finish. Fallbacks, Zeno stops, singular points and bridges
//! are documented modelling rules, not violations, and are counted so a reader can
//! judge how often they act.

use serde::{Deserialize, Serialize};

use crate::{error::SimError, events::Counters, ledger::Ledger};

/// Validity counters of one run (or a sum over runs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Validity {
    /// Impacts whose contact work was positive (energy created at the contact).
    pub energy_gains: u64,
    /// Newton impacts resolved by the energetic law (their own impulse would have created energy).
    pub newton_fallbacks: u64,
    /// Poisson impacts resolved by the energetic law.
    pub poisson_fallbacks: u64,
    /// Contacts held stuck with the friction cone ignored (episodes).
    pub cone_violations: u64,
    /// Bounce sequences ended by the Zeno rule.
    pub zeno_stops: u64,
    /// Runs the integrator or the event handling could not finish ([`SimError::is_integrator_failure`]).
    pub integrator_failures: u64,
    /// Singular points `p = b = 0` crossed under the singular rule (a documented
    /// rule; written only when not 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub singular_points: u64,
    /// Moreau-Jean bridges across a collapsed step (a documented rule, singular
    /// points included; written only when not 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub bridges: u64,
    /// Energy-ledger entries (an integration step, an impact or a bridge) whose
    /// balance refinement could not mend (docs/plant.md "The energy ledger"): a
    /// violation, written only when not 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub ledger_violations: u64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

impl Validity {
    /// The counters of a plant (`counters`) and how its run ended (`failure`).
    pub fn of(counters: &Counters, ledger: &Ledger, failure: Option<&SimError>) -> Self {
        Self {
            energy_gains: counters.energy_gains,
            newton_fallbacks: counters.newton_fallbacks,
            poisson_fallbacks: counters.poisson_fallbacks,
            cone_violations: counters.cone_violations,
            zeno_stops: counters.zeno_stops,
            integrator_failures: u64::from(failure.is_some_and(SimError::is_integrator_failure)),
            singular_points: counters.singular_points,
            bridges: counters.bridges,
            ledger_violations: ledger.violations,
        }
    }

    /// Violations: energy-creating impacts, cone violations and integrator failures.
    pub fn violations(&self) -> u64 {
        self.energy_gains + self.cone_violations + self.integrator_failures + self.ledger_violations
    }

    /// Whether the run has no violation.
    pub fn is_valid(&self) -> bool {
        self.violations() == 0
    }

    /// Adds another run's counters (for totals over many runs).
    pub fn add(&mut self, other: &Validity) {
        self.energy_gains += other.energy_gains;
        self.newton_fallbacks += other.newton_fallbacks;
        self.poisson_fallbacks += other.poisson_fallbacks;
        self.cone_violations += other.cone_violations;
        self.zeno_stops += other.zeno_stops;
        self.integrator_failures += other.integrator_failures;
        self.singular_points += other.singular_points;
        self.bridges += other.bridges;
        self.ledger_violations += other.ledger_violations;
    }

    /// The violations in words (`"2 cone violations, 1 integrator failure"`), empty if none.
    pub fn describe_violations(&self) -> String {
        let plural = |n: u64, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        let mut parts = Vec::new();
        if self.energy_gains > 0 {
            parts.push(plural(self.energy_gains, "energy-creating impact", "energy-creating impacts"));
        }
        if self.cone_violations > 0 {
            parts.push(plural(self.cone_violations, "friction-cone violation", "friction-cone violations"));
        }
        if self.integrator_failures > 0 {
            parts.push(plural(self.integrator_failures, "integrator failure", "integrator failures"));
        }
        if self.ledger_violations > 0 {
            parts.push(plural(self.ledger_violations, "energy-ledger violation", "energy-ledger violations"));
        }
        parts.join(", ")
    }
}

impl std::fmt::Display for Validity {
    /// One line: `energy-creating impacts 0 | Newton fallbacks 0 | Poisson fallbacks 0 |
    /// cone violations 0 | Zeno stops 3 | integrator failures 0`, then `| singular
    /// points 1 | bridges 2` where a bridge acted.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "energy-creating impacts {} | Newton fallbacks {} | Poisson fallbacks {} | cone violations {} | Zeno stops {} | integrator failures {}",
            self.energy_gains,
            self.newton_fallbacks,
            self.poisson_fallbacks,
            self.cone_violations,
            self.zeno_stops,
            self.integrator_failures
        )?;
        if self.bridges > 0 || self.singular_points > 0 {
            write!(f, " | singular points {} | bridges {}", self.singular_points, self.bridges)?;
        }
        if self.ledger_violations > 0 {
            write!(f, " | energy-ledger violations {}", self.ledger_violations)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn violations_are_energy_cone_and_integrator_only() {
        let mut v = Validity { newton_fallbacks: 4, poisson_fallbacks: 1, zeno_stops: 9, ..Validity::default() };
        assert!(v.is_valid(), "fallbacks and Zeno stops are modelling rules");
        v.add(&Validity { cone_violations: 2, integrator_failures: 1, ..Validity::default() });
        assert_eq!(v.violations(), 3);
        assert_eq!(v.describe_violations(), "2 friction-cone violations, 1 integrator failure");
        assert_eq!(v.zeno_stops, 9);
        let failed = Validity::of(&Counters::default(), &Ledger::default(), Some(&SimError::MissedEvent { t: 1.0, mode: "sliding" }));
        assert_eq!(failed.integrator_failures, 1);
        let bad_input = Validity::of(&Counters::default(), &Ledger::default(), Some(&SimError::BadStep(-1.0)));
        assert_eq!(bad_input.integrator_failures, 0, "bad input is not an integrator failure");
    }

    /// Singular points and bridges are rules, not violations; they show in the line
    /// and the JSON only where they acted, so a run without them reads as before.
    #[test]
    fn singular_points_and_bridges_show_where_they_acted() {
        let quiet = Validity::default();
        assert!(!quiet.to_string().contains("bridges"));
        assert!(!serde_json::to_string(&quiet).unwrap().contains("bridges"));
        let counters = Counters { singular_points: 1, bridges: 3, ..Counters::default() };
        let acted = Validity::of(&counters, &Ledger::default(), None);
        assert!(acted.is_valid());
        assert!(acted.to_string().ends_with(" | singular points 1 | bridges 3"), "{acted}");
        let json = serde_json::to_string(&acted).unwrap();
        assert!(json.contains("\"singular_points\":1") && json.contains("\"bridges\":3"), "{json}");
        assert_eq!(serde_json::from_str::<Validity>(&json).unwrap(), acted);
    }
}
