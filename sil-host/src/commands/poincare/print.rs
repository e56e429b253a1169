//! `sil-host poincare`'s human summary.

use std::io::Write;

use experiments::poincare::summary::*;

pub(crate) fn print_human(s: &Summary) {
    let mut o = crate::stdout::out();
    let ic = &s.initial_condition;
    let _ = writeln!(
        o,
        "Poincare section theta1_dot = 0 (upward), open loop u = 0, mu = {}, from {} (tip {}), v_belt in [{}, {}] m/s step {} ({} points)",
        s.mu,
        ic.name,
        if ic.projection.projected { "projected onto the belt" } else { "as given" },
        s.v_belt_range[0],
        s.v_belt_range[1],
        s.v_step,
        s.grid_points
    );
    let _ = writeln!(o, "transient {} s, record {} s; {} section points", s.transient_s, s.record_s, s.section_points);
    let c = &s.counts;
    let _ = writeln!(
        o,
        "classes: periodic {} | chaotic {} | aperiodic {} | settling {} | equilibrium {} | failed {} | invalid {}",
        c.periodic, c.chaotic, c.aperiodic, c.settling, c.equilibrium, c.failed, c.invalid
    );
    let _ = writeln!(o, "validity: {}", s.validity);
    if c.invalid > 0 {
        let _ = writeln!(o, "INVALID: {} belt speeds violate the model (class `invalid` in classes.csv)", c.invalid);
    }
    let _ = writeln!(o, "bands (v_belt from, to, points):");
    for b in &s.bands {
        let _ = writeln!(o, "  {:>8.4} .. {:>8.4} m/s  {:<12} ({} points)", b.v_belt_min, b.v_belt_max, band_name(b), b.points);
    }
    let _ = writeln!(o, "wall {:.1} s on {} threads (median {:.3} s per belt speed)", s.wall_s, s.threads, s.median_point_wall_s);
    let _ = writeln!(o, "wrote {}", s.files.join(", "));
}
