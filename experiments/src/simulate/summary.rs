//! The outputs of `sil-host simulate` other than the figure: the rows of `trace.csv` and `events.csv`, `summary.json` and the human summary.

use plant::initial::ProjectionInfo;
use plant::{Counters, PlantEvent, SimConfig, Validity};
use serde::Serialize;
use shared::Params;

// The CSV columns, in the structs' field order (the header the `csv` crate
// derived from them): the tests at the end check the bytes against it.
tables::table_row! {
    /// One row of `trace.csv`.
    #[derive(Debug, Clone, Serialize)]
    pub struct TraceRow {
        /// Time, s.
        pub t: f64 => f64,
        /// `theta1`, rad.
        pub theta1: f64 => f64,
        /// `theta1_dot`, rad/s.
        pub theta1_dot: f64 => f64,
        /// `theta2`, rad.
        pub theta2: f64 => f64,
        /// `theta2_dot`, rad/s.
        pub theta2_dot: f64 => f64,
        /// Tip tangential position `z_t`, m.
        pub z_t: f64 => f64,
        /// Tip normal position `z_n`, m.
        pub z_n: f64 => f64,
        /// `z_t_dot`, m/s.
        pub z_t_dot: f64 => f64,
        /// `z_n_dot`, m/s.
        pub z_n_dot: f64 => f64,
        /// Relative tangential velocity `z_r_dot = z_t_dot - v_belt`, m/s.
        pub z_r_dot: f64 => f64,
        /// Tangential contact force `f_t`, N.
        pub f_t: f64 => f64,
        /// Normal contact force `f_n`, N.
        pub f_n: f64 => f64,
        /// Contact mode (`flight`, `sliding`, `sticking`).
        pub mode: &'static str => str,
        /// Mechanical energy (kinetic + gravity + spring), J.
        pub energy: f64 => f64,
    }
}

impl TraceRow {
    /// The row of the plant sampled at `s.t` (s) with the tip's velocity `v`
    /// (`[z_t_dot, z_n_dot]`, m/s), the belt's speed `v_belt` (m/s) and the mechanical
    /// energy (J): the columns it shares with the closed loop's `trace.csv`
    /// (`rig::record::PeriodRecord::of_sample`, the same [`plant::Sample`]) mapped the
    /// same way, then the open loop's own (velocities, `z_r_dot = z_t_dot - v_belt`,
    /// energy).
    pub fn of_sample(s: &plant::Sample, v: [f64; 2], v_belt: f64, energy: f64) -> Self {
        Self {
            t: s.t,
            theta1: s.x[0],
            theta1_dot: s.x[1],
            theta2: s.x[2],
            theta2_dot: s.x[3],
            z_t: s.tip[0],
            z_n: s.tip[1],
            z_t_dot: v[0],
            z_n_dot: v[1],
            z_r_dot: v[0] - v_belt,
            f_t: s.f[0],
            f_n: s.f[1],
            mode: s.mode.name(),
            energy,
        }
    }
}

tables::table_row! {
    /// One row of `events.csv`: a plant event at its located time.
    #[derive(Debug, Clone, Serialize)]
    pub struct EventRow {
        /// Time of the event, s.
        pub t: f64 => f64,
        /// The event (`touchdown`, `lift_off`, `p_zero`, `jam`, `slip_to_stick`, ...).
        pub kind: &'static str => str,
        /// Contact mode after it (`flight`, `sliding`, `sticking`).
        pub mode_after: &'static str => str,
        /// Normal velocity of the tip before the event, m/s.
        pub v_n_before: f64 => f64,
        /// Normal velocity of the tip after the event, m/s.
        pub v_n_after: f64 => f64,
        /// Relative tangential velocity `z_r_dot` before the event, m/s.
        pub v_r_before: f64 => f64,
        /// Relative tangential velocity `z_r_dot` after the event, m/s.
        pub v_r_after: f64 => f64,
        /// Tangential impulse of an impact, N s.
        pub impulse_t: f64 => f64,
        /// Normal impulse of an impact, N s.
        pub impulse_n: f64 => f64,
        /// Change of mechanical energy at the event, J.
        pub energy_change: f64 => f64,
        /// Work of the contact impulse, J.
        pub contact_work: f64 => f64,
        /// How an impact was resolved (empty when not an impact).
        pub resolution: String => str,
    }
}

impl From<&PlantEvent> for EventRow {
    fn from(e: &PlantEvent) -> Self {
        Self {
            t: e.t,
            kind: e.kind.name(),
            mode_after: e.mode_after.name(),
            v_n_before: e.v_n_before,
            v_n_after: e.v_n_after,
            v_r_before: e.v_r_before,
            v_r_after: e.v_r_after,
            impulse_t: e.impulse[0],
            impulse_n: e.impulse[1],
            energy_change: e.energy_change,
            contact_work: e.contact_work,
            resolution: e
                .resolution
                .map(|r| serde_json::to_value(r).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default())
                .unwrap_or_default(),
        }
    }
}

// `--format mcap` (trace.mcap): the signal groups of `trace` and `events`, one
// channel each; docs/rig.md "Outputs" lists them.
impl tables::mcap::McapRows for TraceRow {
    const TABLE: &'static str = "trace";
    const GROUPS: &'static [tables::mcap::McapGroup] = &[
        tables::mcap::McapGroup {
            topic: "/state",
            schema: "painleve.State",
            columns: &["theta1", "theta1_dot", "theta2", "theta2_dot", "energy"],
        },
        tables::mcap::McapGroup {
            topic: "/contact",
            schema: "painleve.Contact",
            columns: &["mode", "f_t", "f_n", "z_t", "z_n", "z_t_dot", "z_n_dot", "z_r_dot"],
        },
    ];
}
impl tables::mcap::McapRows for EventRow {
    const TABLE: &'static str = "events";
    const GROUPS: &'static [tables::mcap::McapGroup] = &[tables::mcap::McapGroup {
        topic: "/events",
        schema: "painleve.Event",
        columns: &[
            "kind",
            "mode_after",
            "v_n_before",
            "v_n_after",
            "v_r_before",
            "v_r_after",
            "impulse_t",
            "impulse_n",
            "energy_change",
            "contact_work",
            "resolution",
        ],
    }];
}

/// The initial condition as resolved.
#[derive(Debug, Clone, Serialize)]
pub struct InitialCondition {
    /// `x0a`, `x0d`, `x0u` or `custom`.
    pub name: String,
    /// As given: `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and deg/s.
    pub given_deg: [f64; 4],
    /// Where the tip sat relative to the belt and whether it was projected onto it.
    pub projection: ProjectionInfo,
    /// The state the run starts from, before any impulse: `given_deg` with the tip
    /// projected onto the belt when `projection.projected` (the angles moved to the
    /// same `z_t` on the same elbow branch, the rates as given),
    /// `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and deg/s. What
    /// another simulator starts from to resolve `t = 0` itself (issue 67: it held
    /// the rates after the `t = 0` events, `after_startup_deg`).
    pub used_deg: [f64; 4],
    /// The state after the events at `t = 0` (`startup_events`: an impact, an
    /// impact without collision, the contact's velocity projection), the trace's
    /// first row: `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and deg/s.
    /// `used_deg` when there is none.
    pub after_startup_deg: [f64; 4],
    /// Contact mode chosen at t = 0 (after any initial impact).
    pub initial_mode: &'static str,
    /// Events at t = 0 while the initial mode was chosen (e.g. an impact without collision).
    pub startup_events: Vec<&'static str>,
}

impl InitialCondition {
    /// The initial condition `name`, given as `given_deg` (`[theta1, theta1_dot,
    /// theta2, theta2_dot]`, degrees and deg/s), of `plant` just made from it
    /// (`Plant::new` at `t = 0`, with `params`).
    ///
    /// `used_deg` takes the angles from `plant` (where its projection put them:
    /// the events at `t = 0` change the rates only, never the angles) and the
    /// rates as given (a projection moves the angles only); `after_startup_deg` is
    /// the plant's state.
    pub fn of(name: String, given_deg: [f64; 4], params: &Params<f64>, plant: &plant::Plant) -> Self {
        let x0 = plant::initial::deg_to_state(given_deg);
        let after = plant.state();
        let used = [after[0], x0[1], after[2], x0[3]];
        Self {
            name,
            given_deg,
            projection: plant::initial::describe_projection(params, x0),
            used_deg: used.map(f64::to_degrees),
            after_startup_deg: after.map(f64::to_degrees),
            initial_mode: plant.mode().name(),
            startup_events: plant.startup_events().iter().map(|e| e.kind.name()).collect(),
        }
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// `ok`, `failed` with `error`, or `stopped` (Ctrl-C or SIGTERM) with `error` saying when.
    pub status: &'static str,
    /// The error, when the run failed part way.
    pub error: Option<String>,
    /// Parameters used.
    pub params: Params<f64>,
    /// Simulator settings used.
    pub sim: SimConfig,
    /// The initial condition.
    pub initial_condition: InitialCondition,
    /// Requested simulated time, s.
    pub duration_s: f64,
    /// Simulated time reached, s.
    pub simulated_s: f64,
    /// Lift-offs: every departure of the tip from the belt (a lift-off from
    /// contact, an impact without collision into flight, a bounce at touchdown:
    /// [`analyses::lift_offs::of`]), as in every output (issue 67: it was the
    /// plant's count without the bounces, 1 for a run bouncing from `x0a`).
    pub lift_offs: u64,
    /// Touchdowns (impacts at touchdown).
    pub touchdowns: u64,
    /// Impacts without collision.
    pub impacts_without_collision: u64,
    /// Sticking phases.
    pub stick_phases: u64,
    /// Validity counters; any violation is printed as INVALID (and fails `--strict`).
    pub validity: Validity,
    /// All event counters: the plant's ([`plant::Counters`]), written with
    /// `lift_offs` every departure (as above) and the plant's own count, without
    /// the bounces, as `lift_offs_from_contact` ([`crate::counters::Published`]).
    #[serde(serialize_with = "crate::counters::published")]
    pub counters: Counters,
    /// The energy ledger (docs/plant.md "The energy ledger"): the works since
    /// `t = 0`, what they leave unexplained, the worst entry, the largest energy one
    /// event took from the belt.
    pub ledger: plant::Ledger,
    /// Final state `[theta1, theta1_dot, theta2, theta2_dot]`, rad and rad/s.
    pub final_state: [f64; 4],
    /// Final tip position `[z_t, z_n]`, m.
    pub final_tip: [f64; 2],
    /// Final contact mode.
    pub final_mode: &'static str,
    /// Wall-clock time of the simulation (without writing files), s.
    pub wall_s: f64,
    /// Simulated seconds per wall second.
    pub realtime_factor: f64,
    /// Files written.
    pub files: Vec<String>,
    /// Events written to `events.csv` (the human summary's count; not in the JSON).
    #[serde(skip)]
    pub events: usize,
}

/// An event row as the trace page takes it.
impl From<&EventRow> for figures::trace_page::PageEvent {
    fn from(e: &EventRow) -> Self {
        Self { t: e.t, kind: e.kind, impulse: [e.impulse_t, e.impulse_n] }
    }
}

/// A trace row as the trace page takes it (open loop: no reference, torques or safe state).
impl From<&TraceRow> for figures::trace_page::PageSample {
    fn from(r: &TraceRow) -> Self {
        Self {
            t: r.t,
            theta: [r.theta1, r.theta2],
            z: [r.z_t, r.z_n],
            force: [r.f_t, r.f_n],
            mode: r.mode,
            z_t_ref: f64::NAN,
            u: [f64::NAN; 2],
            safe_state: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use tables::csv::{CsvRow, push_header, push_row};

    /// `rows` through the old path (`csv::Writer::serialize`, header derived) and through [`tables::csv`].
    fn both<T: serde::Serialize + CsvRow>(rows: &[T]) -> (Vec<u8>, Vec<u8>) {
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in rows {
            w.serialize(r).unwrap();
        }
        let old = w.into_inner().unwrap();
        let mut new = Vec::new();
        push_header(&mut new, T::HEADER);
        for r in rows {
            push_row(&mut new, r);
        }
        (old, new)
    }

    fn float() -> impl Strategy<Value = f64> {
        prop_oneof![any::<u64>().prop_map(f64::from_bits), -10.0..10.0f64, Just(0.0), Just(-0.0)]
    }

    proptest! {
        #[test]
        fn trace_rows_match_the_csv_crate(v in proptest::collection::vec((proptest::array::uniform13(float()), 0..3usize), 1..6)) {
            let rows: Vec<TraceRow> = v
                .iter()
                .map(|(f, m)| TraceRow {
                    t: f[0], theta1: f[1], theta1_dot: f[2], theta2: f[3], theta2_dot: f[4], z_t: f[5], z_n: f[6],
                    z_t_dot: f[7], z_n_dot: f[8], z_r_dot: f[9], f_t: f[10], f_n: f[11],
                    mode: ["flight", "sliding", "sticking"][*m], energy: f[12],
                })
                .collect();
            let (old, new) = both(&rows);
            prop_assert_eq!(String::from_utf8(old).unwrap(), String::from_utf8(new).unwrap());
            same_table(&rows)?;
        }

        #[test]
        fn event_rows_match_the_csv_crate(f in proptest::array::uniform10(float()), resolution in "[a-z_, \"]{0,20}") {
            let row = EventRow {
                t: f[0], kind: "touchdown", mode_after: "sticking", v_n_before: f[1], v_n_after: f[2], v_r_before: f[3],
                v_r_after: f[4], impulse_t: f[5], impulse_n: f[6], energy_change: f[7], contact_work: f[8], resolution,
            };
            let rows = [row];
            let (old, new) = both(&rows);
            prop_assert_eq!(String::from_utf8(old).unwrap(), String::from_utf8(new).unwrap());
            same_table(&rows)?;
        }
    }

    /// The two ways from rows to columns agree: the declared columns (`csv_row!`,
    /// what Arrow and NumPy read for the long tables) and the serde path (the
    /// cells the `csv` crate writes), in names, types and bits.
    fn same_table<T: serde::Serialize + tables::ColumnRows>(rows: &[T]) -> Result<(), TestCaseError> {
        use tables::{Column, Table};
        let declared = Table::of_columns(rows);
        let serde = Table::of_rows(rows).unwrap();
        prop_assert_eq!(declared.columns.len(), serde.columns.len());
        for ((na, a), (nb, b)) in declared.columns.iter().zip(&serde.columns) {
            prop_assert_eq!(na, nb);
            match (a, b) {
                (Column::F64(a), Column::F64(b)) => {
                    prop_assert_eq!(a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), b.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                }
                (a, b) => prop_assert_eq!(a, b, "column {}", na),
            }
        }
        Ok(())
    }

    /// The CLI's tables: every column but `t` in exactly one group, each group's
    /// columns the table's; `add_table` accepts them.
    #[test]
    fn the_cli_tables_groups_hold_each_column_once() {
        use tables::{
            Declared,
            mcap::{McapFile, McapRows},
        };
        fn check<T: McapRows + 'static>() {
            let mut grouped: Vec<&str> = T::GROUPS.iter().flat_map(|g| g.columns.iter().copied()).collect();
            grouped.sort_unstable();
            let mut names: Vec<&str> = <T as Declared>::NAMES.iter().copied().filter(|n| *n != "t").collect();
            names.sort_unstable();
            assert_eq!(grouped, names, "{}", T::TABLE);
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("t.mcap");
            let mut f = McapFile::new(path.clone(), std::fs::File::create(&path).unwrap(), None).unwrap();
            f.add_table::<T>().unwrap();
            f.finish().unwrap();
        }
        check::<TraceRow>();
        check::<EventRow>();
        check::<rig::record::PeriodRecord>();
    }

    proptest! {
        /// The open loop's `trace.csv` row and the closed loop's are two views of one
        /// [`plant::Sample`]: every column both tables have (`t`, the angles and rates,
        /// `z_t`, `z_n`, `f_t`, `f_n`, `mode`) holds the same cell, bit for bit, and
        /// `lift_off_true` is the flight mode. A mapping that swapped two fields or read
        /// another would fail here.
        #[test]
        fn trace_rows_and_period_records_agree_on_the_columns_they_share(
            f in proptest::array::uniform12(float()),
            m in 0..5usize,
        ) {
            use shared::ContactMode::*;
            let mode = [Flight, Sliding, Sticking, Indeterminate, Inconsistent][m];
            let s = plant::Sample { t: f[0], x: [f[1], f[2], f[3], f[4]], tip: [f[5], f[6]], mode, f: [f[7], f[8]] };
            let open = tables::Table::of_columns(&[TraceRow::of_sample(&s, [f[9], f[10]], 0.1, f[11])]);
            let record = rig::record::PeriodRecord::of_sample(&s, 0.1);
            let closed = tables::Table::of_columns(&[record]);
            let bits = |c: &tables::Column| match c {
                tables::Column::F64(v) => format!("{:x?}", v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()),
                other => format!("{other:?}"),
            };
            let mut shared_columns = 0;
            for (name, column) in &open.columns {
                if let Some((_, other)) = closed.columns.iter().find(|(n, _)| n == name) {
                    prop_assert_eq!(bits(column), bits(other), "column {}", name);
                    shared_columns += 1;
                }
            }
            prop_assert_eq!(shared_columns, 10);
            prop_assert_eq!(record.lift_off_true, mode == Flight);
        }
    }
}
