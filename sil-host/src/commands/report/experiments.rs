//! The tables of the experiments' sections: each drawn from its typed result.

use super::format::{MAX_ROWS, angle, cell, error_mm, given, located, on_grid, pairs, position, rough, share};
use crate::commands::{
    admissible::summary::fmt_intervals, poincare::summary::Summary as PoincareSummary, simulate::summary::Summary as SimulateSummary,
    sweep::outputs::SweepSummary, zmax::summary::ZmaxSummary,
};
use analyses::{admissible::AdmissibleReport, modes::ModeMap};
use shared::{ElbowBranch, SlipDirection};
use std::fmt::Write as _;

pub(crate) fn modes(md: &mut String, m: &ModeMap) {
    let total = m.points.len();
    let _ = writeln!(md, "| mode | grid points | share |\n|---|---|---|");
    for (mode, n) in m.counts() {
        let _ = writeln!(md, "| {} | {n} | {} % |", mode.name(), share(n, total));
    }
    md.push('\n');
    for z in &m.p_zero {
        let dir = analyses::modes::dir_name(z.dir);
        let _ = writeln!(md, "- `p = 0` for {dir} at theta1 = {} deg", angle(z.theta1_deg));
    }
    md.push('\n');
}

pub(crate) fn admissible(md: &mut String, a: &AdmissibleReport) {
    let _ = writeln!(
        md,
        "`z_t` (m) on the belt where `p > 0` (`*`: end of the reachable belt, |z_t| <= {} m), mu = {}:\n",
        position(a.reach),
        given(a.params.mu)
    );
    let _ = writeln!(md, "| slip direction | elbow up | elbow down |\n|---|---|---|");
    for (label, dir) in
        [("z_r_dot > 0 (the paper's Table II)", SlipDirection::Positive), ("z_r_dot < 0 (mirror image)", SlipDirection::Negative)]
    {
        let _ = writeln!(
            md,
            "| {label} | {} | {} |",
            fmt_intervals(a.intervals(ElbowBranch::Up, dir)),
            fmt_intervals(a.intervals(ElbowBranch::Down, dir))
        );
    }
    let _ = writeln!(md, "\nMirror check: largest end mismatch {} m.\n", a.mirror_max_diff.map_or_else(|| "-".into(), rough));
}

pub(crate) fn simulate(md: &mut String, s: &SimulateSummary) {
    let c = &s.counters;
    pairs(
        md,
        &[
            ("status", s.status.to_string()),
            ("initial condition", s.initial_condition.name.clone()),
            ("mu, v_belt (m/s)", format!("{}, {}", given(s.params.mu), given(s.params.v_belt))),
            ("impact law, e_n", format!("{}, {}", s.sim.impact_law.name(), given(s.sim.e_n))),
            ("rtol, atol", format!("{}, {}", given(s.sim.rtol), given(s.sim.atol))),
            ("simulated (s)", given(s.simulated_s)),
            ("lift-offs (every departure from the belt)", s.lift_offs.to_string()),
            ("touchdowns (bounces)", format!("{} ({})", c.touchdowns, c.bounces)),
            ("impacts without collision", c.impacts_without_collision.to_string()),
            ("stick phases, stick-to-slip", format!("{}, {}", c.stick_phases, c.stick_to_slip)),
            ("impact without collision rule", iwc_cell(s.sim.iwc)),
            ("validity", validity_cell(&s.validity)),
            ("energy ledger", s.ledger.to_string()),
            ("final mode, z_t (m)", format!("{}, {}", s.final_mode, position(s.final_tip[0]))),
        ],
    );
}

/// The impact-without-collision rule for a table cell: the default,
/// `restitution`, with the rule to compare with a Moreau-Jean code (issue 67,
/// docs/plant.md "The impact without collision").
fn iwc_cell(iwc: plant::impact::IwcRule) -> String {
    if matches!(iwc, plant::impact::IwcRule::Restitution) {
        format!(
            "{iwc} (it throws the tip off the belt; Moreau-Jean codes such as Siconos leave it on: compare with them under `--iwc plastic`)"
        )
    } else {
        iwc.to_string()
    }
}

/// A validity line for a table cell: every counter, violations first in words, then
/// what each counter that is not zero but no violation means (a reader sees `Zeno stops
/// 46 844` under "valid" and asks why).
pub(crate) fn validity_cell(v: &plant::Validity) -> String {
    let counts = format!(
        "energy gains {}, Newton fallbacks {}, Poisson fallbacks {}, cone violations {}, Zeno stops {}, integrator failures {}, energy-ledger violations {}",
        v.energy_gains,
        v.newton_fallbacks,
        v.poisson_fallbacks,
        v.cone_violations,
        v.zeno_stops,
        v.integrator_failures,
        v.ledger_violations
    );
    let line = if v.is_valid() { format!("valid ({counts})") } else { format!("**INVALID: {}** ({counts})", v.describe_violations()) };
    let mut why = Vec::new();
    if v.zeno_stops > 0 {
        why.push(
            "a Zeno stop ends a sequence of ever smaller bounces: a last bounce slower than 1e-4 m/s is made plastic and the \
             tip stays on the belt (docs/plant.md \"The Zeno rule\"), part of the model, not an error",
        );
    }
    if v.newton_fallbacks > 0 || v.poisson_fallbacks > 0 {
        why.push(
            "a fallback is an impact where Newton's or Poisson's law with friction would create energy, resolved by the \
             energetic law with the same coefficient instead (docs/plant.md \"Fallback: no impact creates energy\"), \
             so that no impact creates energy",
        );
    }
    if why.is_empty() { line } else { format!("{line}; {}", why.join("; ")) }
}

/// The sweep's cells over their seeds: per `mu`, the fractions of all its runs
/// that lift off, stop in a safe state, keep contact, with their Wilson 95 %
/// intervals, and the cells the seeds leave undecided.
pub(crate) fn ensemble(md: &mut String, s: &SweepSummary, e: &crate::commands::sweep::EnsembleResults) {
    let mu_step = s.spec.mu.step;
    let _ = writeln!(
        md,
        "Over the seeds ({} per cell; jitter: {}): the runs at each `mu` (every belt speed and seed) that lift off, stop in a safe \
         state or keep contact, as fractions with their Wilson 95 % intervals; a cell is undecided when the interval of its lift-off or \
         its contact fraction holds one half:\n",
        s.samples.seeds, s.samples.jitter
    );
    let _ =
        writeln!(md, "| mu | lift off | safe state | contact | undecided cells | cells whose seeds disagree |\n|---|---|---|---|---|---|");
    for m in &e.per_mu {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} of {} | {} of {} |",
            on_grid(m.mu, mu_step),
            m.lift_off.describe(),
            m.safe_state.describe(),
            m.contact.describe(),
            m.undecided_cells,
            m.cells,
            m.boundary_cells,
            m.cells
        );
    }
    md.push('\n');
}

pub(crate) fn sweep(md: &mut String, s: &SweepSummary) {
    let r = &s.results;
    let outcomes: Vec<String> = r.outcomes.iter().map(|(k, v)| format!("{k} {v}")).collect();
    pairs(
        md,
        &[
            ("runs (missing)", format!("{} ({})", r.runs, r.missing)),
            ("resumed runs (found in the output folder, not run again)", s.resumed_runs.to_string()),
            ("outcomes", outcomes.join(", ")),
            ("validity (all runs)", validity_cell(&r.validity)),
            ("dynamic jams (tangential impacts)", r.jams.to_string()),
            ("indicator threshold (rad/s)", given(r.threshold)),
            ("rtol, atol", format!("{}, {}", given(s.spec.rtol), given(s.spec.atol))),
            ("runs per cell", s.samples.note.clone()),
        ],
    );
    if let Some(e) = &s.ensemble {
        ensemble(md, s, e);
    }
    if !r.invalid.is_empty() {
        let _ = writeln!(md, "Runs that violate the model (outcome `invalid`, left out of the bands below):\n");
        let _ = writeln!(
            md,
            "| run | impact law | e_n | IWC | mu | v_belt (m/s) | initial condition | violations |\n|---|---|---|---|---|---|---|---|"
        );
        for i in r.invalid.iter().take(MAX_ROWS) {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} |",
                i.index,
                i.impact_law,
                given(i.e_n),
                i.iwc,
                on_grid(i.mu, s.spec.mu.step),
                on_grid(i.v_belt, s.spec.v_belt.step),
                i.ic,
                cell(&i.violations)
            );
        }
        if r.invalid.len() > MAX_ROWS {
            let _ = writeln!(md, "\n({} more in summary.json)", r.invalid.len() - MAX_ROWS);
        }
        md.push('\n');
    }
    let _ = writeln!(md, "Persistent bouncing, by impact law, `e_n` and IWC rule:\n");
    let _ = writeln!(
        md,
        "| impact law | e_n | IWC | initial condition | critical mu | bands of v_belt (m/s) per mu |\n|---|---|---|---|---|---|"
    );
    let (mu_step, v_step) = (s.spec.mu.step, s.spec.v_belt.step);
    for case in &r.cases {
        for ic in &case.ics {
            let per_mu: Vec<String> = ic
                .per_mu
                .iter()
                .filter(|m| !m.bands.is_empty())
                .map(|m| {
                    let bands: Vec<String> =
                        m.bands.iter().map(|b| format!("[{}, {}]", on_grid(b.v_min, v_step), on_grid(b.v_max, v_step))).collect();
                    format!("{}: {}", on_grid(m.mu, mu_step), bands.join(" "))
                })
                .collect();
            let bands = if per_mu.is_empty() { "none".to_string() } else { per_mu.join("; ") };
            let critical = ic.critical_mu.map_or_else(|| "none".to_string(), |c| on_grid(c, mu_step));
            let _ = writeln!(md, "| {} | {} | {} | {} | {critical} | {bands} |", case.impact_law, given(case.e_n), case.iwc, ic.ic);
        }
    }
    md.push('\n');
}

pub(crate) fn poincare(md: &mut String, p: &PoincareSummary) {
    let c = &p.counts;
    pairs(
        md,
        &[
            ("mu, initial condition", format!("{}, {}", given(p.mu), p.initial_condition.name)),
            ("v_belt (m/s)", format!("{} to {} in steps of {}", given(p.v_belt_range[0]), given(p.v_belt_range[1]), given(p.v_step))),
            ("transient, record (s)", format!("{}, {}", given(p.transient_s), given(p.record_s))),
            ("rtol, atol", format!("{}, {}", given(p.sim.rtol), given(p.sim.atol))),
            (
                "classes",
                format!(
                    "equilibrium {}, settling {}, periodic {}, chaotic {}, aperiodic {}, failed {}, invalid {}",
                    c.equilibrium, c.settling, c.periodic, c.chaotic, c.aperiodic, c.failed, c.invalid
                ),
            ),
            ("section points", p.section_points.to_string()),
            ("validity (all belt speeds)", validity_cell(&p.validity)),
        ],
    );
    let _ = writeln!(md, "| class | period | v_belt from (m/s) | to (m/s) | points |\n|---|---|---|---|---|");
    for b in p.bands.iter().take(MAX_ROWS) {
        let period = b.period.map_or_else(|| "-".into(), |n| n.to_string());
        let _ = writeln!(
            md,
            "| {} | {period} | {} | {} | {} |",
            b.class.name(),
            on_grid(b.v_belt_min, p.v_step),
            on_grid(b.v_belt_max, p.v_step),
            b.points
        );
    }
    if p.bands.len() > MAX_ROWS {
        let _ = writeln!(md, "\n({} more bands in the files)", p.bands.len() - MAX_ROWS);
    }
    md.push('\n');
}

/// A limit found by bisection to `tol` (m), as the zmax table prints it: the value to
/// the tolerance, `< lo` when the bracket's lower end already fails, `>= v` when the
/// upper end passes (the bracket's ends are tip positions: [`position`]).
pub(crate) fn limit(outcome: &str, value: Option<f64>, lo: f64, hi: f64, tol: f64) -> String {
    match (outcome, value) {
        ("lower_fails", _) => format!("< {}", position(lo)),
        ("upper_reached", v) => format!(">= {}", position(v.unwrap_or(hi))),
        (_, Some(v)) => located(v, tol),
        (_, None) => "-".into(),
    }
}

pub(crate) fn zmax(md: &mut String, z: &ZmaxSummary) {
    let tol = z.tol_m;
    let _ = writeln!(md, "{}\n", z.definition);
    let _ = writeln!(
        md,
        "| controller | x0 | setting | Z_t,sliding (m) | paper (m) | error there (mm) | first with lift-off (m) | why | tracking limit (m) | first not reached (m) | why | trials |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in &z.results {
        let paper = match analyses::paper::z_t_sliding(r.controller, r.x0) {
            Some(Some(v)) => given(v),
            Some(None) => "none (lifts off)".into(),
            None => "-".into(),
        };
        let _ = writeln!(
            md,
            "| {} | x0{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.controller,
            r.x0,
            r.setting,
            limit(r.outcome, r.z_t_sliding_m, r.bracket_lo_m, r.bracket_hi_m, tol),
            paper,
            r.error_at_limit_m.map_or("-".into(), error_mm),
            r.first_failing_m.map_or("-".into(), |v| located(v, tol)),
            cell(r.why_failing.as_deref().unwrap_or("-")),
            limit(r.tracking_outcome, r.z_t_tracking_m, r.bracket_lo_m, r.bracket_hi_m, tol),
            r.tracking_first_failing_m.map_or("-".into(), |v| located(v, tol)),
            cell(r.tracking_why_failing.as_deref().unwrap_or("-")),
            r.trials
        );
    }
    let _ = writeln!(
        md,
        "\nBisection tolerance {} m; settle tolerance {} mm over the last {} s of a {} s run. Compare with {}.\n",
        given(z.tol_m),
        given(z.criteria.settle_tol_m * 1e3),
        given(z.criteria.settle_window_s),
        given(z.criteria.duration_s),
        z.paper
    );
    let _ = writeln!(md, "Samples: {}.\n", z.samples);
    if !z.distributions.is_empty() {
        let _ = writeln!(
            md,
            "Over the seeds (the sampled cases; one bisection per seed; \"none\": the bracket's lower end already fails):\n\n\
             | controller | x0 | seeds | Z_t,sliding median (m) | quartiles (m) | range (m) | seeds with none | tracking limit median (m) | range (m) |\n\
             |---|---|---|---|---|---|---|---|---|"
        );
        let m = |x: Option<f64>| x.map_or("none".to_string(), |v| located(v, tol));
        for d in &z.distributions {
            let (a, b) = (&d.z_t_sliding, &d.z_t_tracking);
            let _ = writeln!(
                md,
                "| {} | x0{} | {} | {} | {} to {} | {} to {} | {} | {} | {} to {} |",
                d.controller,
                d.x0,
                d.seeds,
                m(a.median_m),
                m(a.q1_m),
                m(a.q3_m),
                m(a.min_m),
                m(a.max_m),
                a.none,
                m(b.median_m),
                m(b.min_m),
                m(b.max_m)
            );
        }
        md.push('\n');
    }
    let _ = writeln!(md, "Validity over every trial: {}.\n", validity_cell(&z.validity));
}

/// The band at `mu = 0.6` from `x0a` of the study's open loop: `[from, to]` on the
/// study's grid of `v_belt` (spacing `step`), then `+ v` for each bouncing speed
/// outside it; `none`.
fn band_text(o: &analyses::sensitivity::OpenLoop, step: f64) -> String {
    let Some(b) = o.band_x0a_mu06 else { return "none".into() };
    let mut t = format!("[{}, {}]", on_grid(b[0], step), on_grid(b[1], step));
    for v in &o.band_outside {
        let _ = write!(t, " + {}", on_grid(*v, step));
    }
    t
}

pub(crate) fn sensitivity(md: &mut String, st: &analyses::sensitivity::Study) {
    use analyses::zmax::{Combination, Setting};
    let _ = writeln!(
        md,
        "Each open choice varied alone from the defaults (starred). `.`: the choice does not enter that result. \
         Bouncing band: the longest run of neighbouring belt speeds that bounce, then `+ v` for each other speed that does. \
         Z_t,sliding (the largest target the tip slides to within 5 mm with no lift-off) and the tracking limit (also settled within 1 mm), in mm, \
         in the order PID x0d, PID x0u, hybrid x0d, hybrid x0u; `< lo: why`: the bracket's lower end already fails, and why \
         (`lift_off`, `safe_state`, `failure`, `not_reached`, `not_settled`, `invalid`). \
         Closed loop: how the hybrid firmware's runs from x0d at mu = 0.6 ended over the belt speeds (a lift-off counts only above the lift-off criterion). \
         Validity over everything simulated: {}.\n",
        validity_cell(&st.validity)
    );
    let _ = writeln!(
        md,
        "| choice | value | critical mu x0a | critical mu x0d | bouncing at mu = 0.6 from x0a (m/s) | x0d bounces | Z_t,sliding ideal | Z_t,sliding sampled | tracking limit sampled | hybrid closed loop |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    let opt_num = |x: Option<f64>| x.map_or_else(|| "none".to_string(), |mu| on_grid(mu, st.grids.mu.step));
    for r in &st.results {
        let c = &r.choice;
        let (a, d, band, x0d) = match &r.open_loop {
            Some(o) => (
                opt_num(o.critical_mu_x0a),
                opt_num(o.critical_mu_x0d),
                band_text(o, st.grids.v_belt.step),
                if o.x0d_bounces { "yes".to_string() } else { "no".to_string() },
            ),
            None => (".".to_string(), ".".to_string(), ".".to_string(), ".".to_string()),
        };
        let z = |setting: Setting, tracking: bool| {
            Combination::all()
                .into_iter()
                .filter(|k| k.setting == setting)
                .map(|k| match r.zmax.iter().find(|z| z.combination == k) {
                    Some(z) => z.cell_text(tracking),
                    None => ".".to_string(),
                })
                .collect::<Vec<String>>()
                .join(", ")
        };
        let closed = r.closed_loop.as_ref().map_or_else(|| ".".to_string(), |cl| cl.text());
        let _ = writeln!(
            md,
            "| {} | {}{} | {a} | {d} | {} | {x0d} | {} | {} | {} | {} |",
            c.dimension.label(),
            cell(&c.value),
            if c.is_default { " *" } else { "" },
            cell(&band),
            cell(&z(Setting::Ideal, false)),
            cell(&z(Setting::Sampled, false)),
            cell(&z(Setting::Sampled, true)),
            cell(&closed)
        );
    }
    md.push('\n');
}
