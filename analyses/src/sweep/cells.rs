//! A sweep's cells over its seeds (issue 82): per grid point and initial
//! condition (a cell), how many of its seeds lift off, stop in a safe state or
//! keep contact, each as a [`Proportion`] with its Wilson 95 % interval
//! (`cells.csv`, `summary.json`'s `cells`, the maps' shading).
//!
//! "Lifts off" is [`Outcome::is_bouncing`]: closed loop, a lift-off in the record
//! window ([`Outcome::LiftOff`]); open loop, the paper's persistent bouncing
//! ([`Outcome::Bouncing`]). A cell is **undecided** when the lift-off fraction's
//! interval or the contact fraction's holds one half (its seeds settle neither
//! whether it lifts off nor whether it keeps contact at 95 %), and
//! **on a boundary** when its seeds disagree at all (some lift off, some do not):
//! with the open loop's jitter, the outcome changes within the jitter's
//! resolution there (a band's edge, the critical `mu`).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{
    SweepSpec,
    ensemble::Proportion,
    run::{Outcome, RunRow},
};

/// One cell of `cells.csv`: a grid point and initial condition over its seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellRow {
    /// The cell's number: the run index of its seed 0 ([`SweepSpec::run_at`]).
    pub cell: usize,
    /// Impact law.
    pub impact_law: String,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Impact-without-collision rule (`restitution`, `plastic`).
    pub iwc: String,
    /// Friction coefficient (the grid's value; seeds may jitter it).
    pub mu: f64,
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Initial condition.
    pub ic: String,
    /// Seeds with a result (runs of the cell found).
    pub runs: usize,
    /// Seeds that lift off ([`Outcome::is_bouncing`]).
    pub lift_off: usize,
    /// `lift_off / runs`.
    pub lift_off_fraction: f64,
    /// Wilson 95 % interval of that fraction: lower end.
    pub lift_off_lo: f64,
    /// Upper end.
    pub lift_off_hi: f64,
    /// Seeds that stopped in a safe state ([`Outcome::SafeState`]).
    pub safe_state: usize,
    /// `safe_state / runs`.
    pub safe_state_fraction: f64,
    /// Wilson 95 % interval: lower end.
    pub safe_state_lo: f64,
    /// Upper end.
    pub safe_state_hi: f64,
    /// Seeds that kept contact ([`Outcome::Contact`]).
    pub contact: usize,
    /// `contact / runs`.
    pub contact_fraction: f64,
    /// Wilson 95 % interval: lower end.
    pub contact_lo: f64,
    /// Upper end.
    pub contact_hi: f64,
    /// Seeds with any other outcome (not reached, flight, oscillating, failed, invalid, ...).
    pub other: usize,
    /// The lift-off fraction's interval or the contact fraction's holds one half.
    pub undecided: bool,
    /// Some seeds lift off and some do not.
    pub boundary: bool,
}

// `cells.csv`: the columns serde writes, declared (CSV reader, Arrow schema, Python).
tables::declare!(CellRow {
    cell: int,
    impact_law: str,
    e_n: f64,
    iwc: str,
    mu: f64,
    v_belt: f64,
    ic: str,
    runs: int,
    lift_off: int,
    lift_off_fraction: f64,
    lift_off_lo: f64,
    lift_off_hi: f64,
    safe_state: int,
    safe_state_fraction: f64,
    safe_state_lo: f64,
    safe_state_hi: f64,
    contact: int,
    contact_fraction: f64,
    contact_lo: f64,
    contact_hi: f64,
    other: int,
    undecided: bool,
    boundary: bool,
});

impl CellRow {
    /// The lift-off proportion.
    pub fn lift_offs(&self) -> Proportion {
        Proportion::of(self.lift_off, self.runs)
    }

    /// The safe-state proportion.
    pub fn safe_states(&self) -> Proportion {
        Proportion::of(self.safe_state, self.runs)
    }

    /// The contact proportion.
    pub fn contacts(&self) -> Proportion {
        Proportion::of(self.contact, self.runs)
    }
}

/// The cells of `spec` from its `rows` (any order, any subset of seeds), by cell
/// number; a cell without any row is left out.
pub fn of(spec: &SweepSpec, rows: &[RunRow]) -> Vec<CellRow> {
    let per_seed = spec.runs_per_seed().max(1);
    let mut by_cell: BTreeMap<usize, Vec<&RunRow>> = BTreeMap::new();
    for r in rows {
        by_cell.entry(r.index % per_seed).or_default().push(r);
    }
    by_cell
        .into_iter()
        .map(|(cell, runs)| {
            let key = spec.run_at(cell);
            let count = |f: &dyn Fn(Outcome) -> bool| runs.iter().filter(|r| f(r.outcome)).count();
            let n = runs.len();
            let lift = Proportion::of(count(&|o| o.is_bouncing()), n);
            let safe = Proportion::of(count(&|o| o == Outcome::SafeState), n);
            let contact = Proportion::of(count(&|o| o == Outcome::Contact), n);
            CellRow {
                cell,
                impact_law: key.impact_law.name().into(),
                e_n: key.e_n,
                iwc: key.iwc.name().into(),
                mu: key.mu,
                v_belt: key.v_belt,
                ic: runs[0].ic.clone(),
                runs: n,
                lift_off: lift.k,
                lift_off_fraction: lift.fraction,
                lift_off_lo: lift.lo,
                lift_off_hi: lift.hi,
                safe_state: safe.k,
                safe_state_fraction: safe.fraction,
                safe_state_lo: safe.lo,
                safe_state_hi: safe.hi,
                contact: contact.k,
                contact_fraction: contact.fraction,
                contact_lo: contact.lo,
                contact_hi: contact.hi,
                other: n - lift.k - safe.k - contact.k,
                undecided: lift.straddles_half() || contact.straddles_half(),
                boundary: lift.k > 0 && lift.k < n,
            }
        })
        .collect()
}

/// The cells of one `mu` pooled (every belt speed, initial condition, law, `e_n`
/// and rule): the runs that lift off, stop safe, keep contact, as proportions of
/// all its runs; one entry per `mu` of the grid with runs, by increasing `mu`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MuFractions {
    /// Friction coefficient (the grid's).
    pub mu: f64,
    /// Runs that lift off.
    pub lift_off: Proportion,
    /// Runs that stopped in a safe state.
    pub safe_state: Proportion,
    /// Runs that kept contact.
    pub contact: Proportion,
    /// Cells whose lift-off interval holds one half.
    pub undecided_cells: usize,
    /// Cells whose seeds disagree.
    pub boundary_cells: usize,
    /// Cells.
    pub cells: usize,
}

/// [`MuFractions`] of `cells`.
pub fn per_mu(cells: &[CellRow]) -> Vec<MuFractions> {
    let mut by_mu: BTreeMap<u64, Vec<&CellRow>> = BTreeMap::new();
    for c in cells {
        // mu >= 0: the bits order as the values.
        by_mu.entry(c.mu.to_bits()).or_default().push(c);
    }
    by_mu
        .into_values()
        .map(|cs| {
            let n: usize = cs.iter().map(|c| c.runs).sum();
            let sum = |f: &dyn Fn(&CellRow) -> usize| cs.iter().map(|c| f(c)).sum::<usize>();
            MuFractions {
                mu: cs[0].mu,
                lift_off: Proportion::of(sum(&|c| c.lift_off), n),
                safe_state: Proportion::of(sum(&|c| c.safe_state), n),
                contact: Proportion::of(sum(&|c| c.contact), n),
                undecided_cells: cs.iter().filter(|c| c.undecided).count(),
                boundary_cells: cs.iter().filter(|c| c.boundary).count(),
                cells: cs.len(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::{Axis, Jitter, SweepController};
    use plant::impact::IwcRule;

    fn row(spec: &SweepSpec, index: usize, outcome: Outcome) -> RunRow {
        let key = spec.run_at(index);
        RunRow {
            index,
            impact_law: key.impact_law.name().into(),
            e_n: key.e_n,
            iwc: IwcRule::Restitution,
            mu: key.mu,
            v_belt: key.v_belt,
            ic: "x0d".into(),
            seed: key.seed,
            outcome,
            theta1_dot_over_threshold: false,
            theta1_dot_max: 0.0,
            t_theta1_dot_max: 0.0,
            lift_offs: 0,
            touchdowns: 0,
            impacts_without_collision: 0,
            z_n_max: 0.0,
            tip_height_max: 0.0,
            final_mode: "sliding".into(),
            target_error_m: 0.0,
            lift_offs_transient: 0,
            rhs_evaluations: 0,
            energy_gains: 0,
            newton_fallbacks: 0,
            poisson_fallbacks: 0,
            cone_violations: 0,
            zeno_stops: 0,
            jams: 0,
            integrator_failures: 0,
            ledger_violations: 0,
            belt_j: 0.0,
            slip_j: 0.0,
            ledger_residual_j: 0.0,
            largest_event_belt_j: 0.0,
            error: String::new(),
        }
    }

    /// Two cells, 10 seeds: the rows of a seed land in their cell (the index
    /// modulo the runs per seed), the counts and intervals are the seeds', and
    /// the flags follow the interval.
    #[test]
    fn cells_gather_their_seeds() {
        let spec = SweepSpec {
            mu: Axis { start: 0.9, stop: 0.9, step: 0.1 },
            v_belt: Axis { start: -0.6, stop: -0.5, step: 0.1 },
            paper_ics: vec![plant::initial::PaperX0::D],
            controller: SweepController::None,
            seeds: 10,
            jitter: Jitter { mu: 1e-3, ..Jitter::default() },
            ..SweepSpec::paper()
        };
        assert_eq!((spec.runs_per_seed(), spec.n_runs()), (2, 20));
        // Cell 0: 4 of 10 lift off, 6 keep contact. Cell 1: all keep contact.
        let rows: Vec<RunRow> = (0..20)
            .map(|i| {
                let o = if i % 2 == 0 && i / 2 < 4 { Outcome::Bouncing } else { Outcome::Contact };
                row(&spec, i, o)
            })
            .collect();
        let cells = of(&spec, &rows);
        assert_eq!(cells.len(), 2);
        let (a, b) = (&cells[0], &cells[1]);
        assert_eq!((a.cell, a.runs, a.lift_off, a.contact, a.other), (0, 10, 4, 6, 0));
        assert_eq!(a.lift_offs(), Proportion::of(4, 10));
        assert!(a.undecided && a.boundary);
        assert_eq!((b.cell, b.v_belt, b.lift_off, b.contact), (1, -0.5, 0, 10));
        assert!(!b.undecided && !b.boundary && b.contact_lo > 0.69);
        let m = per_mu(&cells);
        assert_eq!(m.len(), 1);
        assert_eq!((m[0].lift_off.k, m[0].lift_off.n, m[0].undecided_cells, m[0].boundary_cells), (4, 20, 1, 1));
        // The rows fill their declared columns.
        let t = tables::Table::of_rows(&cells).unwrap();
        assert_eq!(t.columns.len(), <CellRow as tables::Declared>::NAMES.len());
    }
}
