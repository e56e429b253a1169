//! The outputs of `sil-host sweep` and `sil-host merge`: `sweep.csv`, `summary.json`, the figures and the human summary.

use crate::{error::CliError, output::OutputSet, sweep::figures};
use analyses::sweep::{
    SweepController,
    run::RunRow,
    summary::{self},
};
use experiments::sweep::store::{self, Manifest};
pub use experiments::sweep::summary::{SweepSummary, Timing, cpu_seconds, summary_of};
use std::{collections::BTreeMap, io::Write, path::Path};

/// Writes the outputs of the folder from its rows: `sweep.csv`, `summary.json` and
/// the figures (all or nothing, [`OutputSet`]).
pub(crate) fn finish(
    dir: &Path,
    m: &Manifest,
    mut rows: Vec<RunRow>,
    timing: Option<Timing>,
    resumed: usize,
    interrupted: bool,
) -> Result<SweepSummary, CliError> {
    rows.sort_by_key(|r| r.index);
    let missing = store::missing(m, &rows).len();
    let results = summary::results(&m.spec, &rows, missing);
    let mut out = OutputSet::new(dir)?;
    let csv_tmp = out.stage("sweep.csv")?;
    store::write_rows(&csv_tmp, &rows)?;
    // Figures per impact law and e_n.
    let mut by_case: BTreeMap<(String, u64), Vec<&RunRow>> = BTreeMap::new();
    for r in &rows {
        by_case.entry((r.impact_law.clone(), r.e_n.to_bits())).or_default().push(r);
    }
    let mut files = vec![dir.join("sweep.csv")];
    // Several seeds per cell: the cells' fractions (cells.csv) and the maps shaded by them.
    let cells = (m.spec.seeds > 1).then(|| analyses::sweep::cells::of(&m.spec, &rows));
    if let Some(cells) = &cells {
        let tmp = out.stage("cells.csv")?;
        store::write_table(&tmp, cells)?;
        files.push(dir.join("cells.csv"));
    }
    for law in &m.spec.impact_laws {
        for &e_n in &m.spec.e_n {
            let empty = Vec::new();
            let case_rows = by_case.get(&(law.name().to_string(), e_n.to_bits())).unwrap_or(&empty);
            let suffix = figures::case_suffix(law.name(), e_n);
            let map = format!("map_{suffix}.svg");
            let slices = format!("slices_{suffix}.svg");
            match &cells {
                Some(cells) => {
                    let of_case: Vec<&analyses::sweep::cells::CellRow> =
                        cells.iter().filter(|c| c.impact_law == law.name() && c.e_n.to_bits() == e_n.to_bits()).collect();
                    figures::draw_probability_map(&out.stage_figure(&map)?, &m.spec, law.name(), e_n, &of_case)?;
                }
                None => figures::draw_map(&out.stage_figure(&map)?, &m.spec, law.name(), e_n, case_rows)?,
            }
            figures::draw_slices(&out.stage_figure(&slices)?, &m.spec, law.name(), e_n, case_rows)?;
            for figure in [map, slices] {
                files.push(dir.join(&figure));
                if ::figures::plot::print::WRITES_PDF {
                    files.push(dir.join(figure.replace(".svg", ".pdf")));
                }
            }
        }
    }
    files.push(dir.join("summary.json"));
    let files = files.iter().map(|p| p.display().to_string()).collect();
    let summary = summary_of(m, results, missing, timing, resumed, interrupted, files).with_cells(cells.as_deref());
    out.write_json("summary.json", &summary)?;
    out.commit()?;
    Ok(summary)
}

pub(crate) fn report(s: &SweepSummary, json: bool) {
    if json {
        outln!("{}", serde_json::to_string_pretty(s).unwrap_or_default());
        return;
    }
    let mut o = crate::stdout::out();
    let ctrl = match (s.spec.controller, s.spec.ideal) {
        (SweepController::None, _) => "open loop (u = 0)".to_string(),
        (c, true) => format!("closed loop, {} (ideal continuous-time)", c.name()),
        (c, false) => format!("closed loop, {} firmware in-process at the scenario's rate", c.name()),
    };
    let _ = writeln!(
        o,
        "sweep: {}, mu {}..{} ({} values), v_belt {}..{} m/s ({} values), transient {} s + record {} s, {} initial conditions",
        ctrl,
        s.spec.mu.start,
        s.spec.mu.stop,
        s.spec.mu.len(),
        s.spec.v_belt.start,
        s.spec.v_belt.stop,
        s.spec.v_belt.len(),
        s.spec.transient_s,
        s.spec.record_s,
        s.initial_conditions.len()
    );
    for ic in &s.initial_conditions {
        let deg = ic.x0.map(f64::to_degrees);
        let _ = writeln!(
            o,
            "  {}: [{:.4}, {:.1}, {:.4}, {:.1}] deg (elbow {}), tip {:.3} mm {} the belt{}",
            ic.name,
            deg[0],
            deg[1],
            deg[2],
            deg[3],
            ic.branch.name(),
            ic.height_above_belt.abs() * 1e3,
            if ic.height_above_belt < 0.0 { "inside" } else { "above" },
            if ic.height_above_belt <= 1e-12 { ": projected onto it" } else { "" }
        );
    }
    let _ = writeln!(
        o,
        "samples: {}{}",
        s.samples.note,
        if s.samples.seeds > 1 { format!(" (jitter: {})", s.samples.jitter) } else { String::new() }
    );
    summary::print_table(&mut o, &s.results);
    if let Some(e) = &s.ensemble {
        let _ = writeln!(o, "\nover the seeds, per mu (every cell pooled; fraction [Wilson 95 % interval]):");
        let _ = writeln!(o, "  {:>6}  {:<26} {:<26} {:<26} undecided / boundary cells", "mu", "lift off", "safe state", "contact");
        for m in &e.per_mu {
            let _ = writeln!(
                o,
                "  {:>6}  {:<26} {:<26} {:<26} {} / {} of {}",
                m.mu,
                m.lift_off.describe(),
                m.safe_state.describe(),
                m.contact.describe(),
                m.undecided_cells,
                m.boundary_cells,
                m.cells
            );
        }
        let _ = writeln!(
            o,
            "undecided cells (the lift-off or the contact interval holds 1/2): {} of {}; every cell in cells.csv",
            e.undecided.len(),
            e.cells
        );
    }
    if let Some(t) = &s.timing
        && t.runs_computed > 0
    {
        let _ = writeln!(
            o,
            "speed: {} runs in {:.1} s on {} threads: {:.0} simulated s per wall s per core ({:.0} per CPU s); a grid of the paper's size (3620 runs x 300 s) would take {:.1} min at this rate",
            t.runs_computed,
            t.wall_s,
            t.threads,
            t.simulated_s_per_wall_s_per_core,
            t.simulated_s_per_cpu_s,
            t.paper_grid_projection_s / 60.0
        );
    }
    let _ = writeln!(o, "status: {}; wrote {}", s.status, s.files.join(", "));
}
