//! The page's figures: each shown as "Figure N." in the order the page shows
//! them, with a caption below it that says what it shows, its parameters (read
//! from the experiment's typed result, so the arguments it actually ran with) and
//! the paper's counterpart where there is one.

use std::fmt::Write as _;

use analyses::sweep::{SweepController, SweepSpec};
use rig::scenario::Scenario;

use super::animations::law_named;
use super::format::{given, located};
use super::outcome::Outcome;
use crate::commands::sweep::outputs::SweepSummary;

/// What a figure shows, with what, and the paper's figure it stands for.
#[derive(Debug, Clone, PartialEq)]
pub struct Caption {
    /// What the figure shows (a sentence without its full stop).
    pub what: String,
    /// The parameters of the run or runs drawn (empty when none apply).
    pub parameters: String,
    /// The paper's counterpart (`paper Fig. 3`), if there is one.
    pub paper: Option<String>,
}

impl Caption {
    /// The caption's text: what, parameters, the paper's counterpart, with the
    /// paper's symbols for the code names (`theta1_dot` as θ̇₁, `mu` as μ:
    /// [`figures::plot::symbols::prose`], the table the figures are labelled with).
    pub fn text(&self) -> String {
        let mut t = format!("{}.", self.what);
        if !self.parameters.is_empty() {
            let _ = write!(t, " {}.", self.parameters);
        }
        match &self.paper {
            Some(p) => {
                let _ = write!(t, " In the paper: {p}.");
            }
            None => t.push_str(" No counterpart in the paper."),
        }
        figures::plot::symbols::prose(&t)
    }
}

/// The figures of one page: numbered from 1 in the order shown, each referenced
/// as `prefix` + its path in the report folder.
#[derive(Debug, Clone)]
pub struct Figures {
    prefix: String,
    numbered: usize,
    shown: Vec<String>,
    /// Whether each caption links the figure's PDF (the report's folder holds them).
    pdf: bool,
}

impl Figures {
    /// No figure shown yet; `prefix` goes before each file's path in the report
    /// folder (`""` on report.md, `figures/` on docs/results.md).
    pub fn new(prefix: &str) -> Self {
        Self { prefix: prefix.to_string(), numbered: 0, shown: Vec::new(), pdf: false }
    }

    /// The same, each caption ending with a link to the figure's PDF (beside its
    /// SVG, as every command writes it: `trace.pdf` for `trace.svg`), in a build
    /// that writes PDFs (the feature `pdf`).
    pub fn with_pdf(mut self) -> Self {
        self.pdf = figures::plot::print::WRITES_PDF;
        self
    }

    /// The links to the PDFs of `files` after a caption (empty without PDFs).
    fn pdf_links(&self, files: &[&str]) -> String {
        if !self.pdf {
            return String::new();
        }
        let links: Vec<String> = files
            .iter()
            .filter(|f| f.ends_with(".svg"))
            .map(|f| format!("[PDF]({}{})", self.prefix, f.trim_end_matches(".svg").to_string() + ".pdf"))
            .collect();
        format!(" {}", links.join(", "))
    }

    /// Shows `file` (its path in the report folder) as the next figure, with `caption` below it.
    pub fn show(&mut self, md: &mut String, file: &str, caption: &Caption) {
        self.numbered += 1;
        let n = self.numbered;
        let _ = writeln!(md, "![Figure {n}: {}]({}{file})\n", alt(&caption.what), self.prefix);
        let _ = writeln!(md, "**Figure {n}.** {}{}\n", caption.text(), self.pdf_links(&[file]));
        self.shown.push(file.to_string());
    }

    /// Shows `columns` (each a heading and its files, row by row) side by side in a
    /// table as one figure, with `caption` below it.
    pub fn show_side_by_side(&mut self, md: &mut String, columns: &[(String, Vec<String>)], caption: &Caption) {
        let rows = columns.iter().map(|(_, files)| files.len()).max().unwrap_or(0);
        if rows == 0 {
            return;
        }
        self.numbered += 1;
        let n = self.numbered;
        let heads: Vec<&str> = columns.iter().map(|(head, _)| head.as_str()).collect();
        let _ = writeln!(md, "| {} |\n|{}", heads.join(" | "), "---|".repeat(columns.len()));
        for i in 0..rows {
            let cells: Vec<String> = columns
                .iter()
                .map(|(head, files)| {
                    files.get(i).map_or(String::new(), |f| {
                        self.shown.push(f.clone());
                        format!("![Figure {n}, {head}: {}]({}{f})", alt(&caption.what), self.prefix)
                    })
                })
                .collect();
            let _ = writeln!(md, "| {} |", cells.join(" | "));
        }
        let start = self.shown.len() - columns.iter().map(|(_, f)| f.len()).sum::<usize>();
        let files: Vec<&str> = self.shown[start..].iter().map(String::as_str).collect();
        let _ = writeln!(md, "\n**Figure {n}.** {}{}\n", caption.text(), self.pdf_links(&files));
    }

    /// The files shown so far (paths in the report folder), in the page's order.
    pub fn shown(&self) -> &[String] {
        &self.shown
    }
}

/// A sweep's axis in words: `mu from 0.1 to 1 by 0.1`, `v_belt from -1 to -0.1 m/s
/// by 0.05` (`unit` after the end, with its space).
fn axis_text(name: &str, axis: &analyses::sweep::Axis, unit: &str) -> String {
    format!("{name} from {} to {}{unit} by {}", given(axis.start), given(axis.stop), given(axis.step))
}

/// Alt text: the caption's first clause, in symbols, without the characters
/// Markdown reads in `[...]`.
fn alt(what: &str) -> String {
    figures::plot::symbols::prose(what.split([':', ';']).next().unwrap_or(what).replace(['[', ']', '|', '`'], "").trim())
}

/// The figures of one experiment in the order the page shows them: the order of its
/// own tables (a sweep's cases as its impact laws and `e_n` were given, maps before
/// slices; `zmax`'s rows; the sensitivity table's columns), else by name.
pub fn order<'a>(outcome: Option<&Outcome>, files: &'a [String]) -> Vec<&'a String> {
    let mut v: Vec<&String> = files.iter().filter(|f| f.ends_with(".svg") || f.ends_with(".gif")).collect();
    let rank = |file: &str| -> (usize, usize) {
        let stem = file.rsplit('/').next().unwrap_or(file).trim_end_matches(".svg").trim_end_matches(".gif");
        match outcome {
            Some(Outcome::Sweep(s)) => sweep_rank(s, file),
            Some(Outcome::Zmax(z)) => (
                z.results
                    .iter()
                    .position(|r| stem == format!("zmax-{}-x0{}-{}", r.controller.name(), r.x0.letter(), r.setting.name()))
                    .unwrap_or(usize::MAX),
                0,
            ),
            Some(Outcome::Sensitivity(_)) => (SENSITIVITY.iter().position(|s| *s == stem).unwrap_or(usize::MAX), 0),
            Some(Outcome::Poincare(_)) => (usize::from(stem != "bifurcation"), 0),
            Some(Outcome::Run(_)) => (usize::from(stem != "trace") + usize::from(stem == "animation"), 0),
            Some(Outcome::Simulate(_)) => (usize::from(stem == "animation"), 0),
            _ => (0, 0),
        }
    };
    v.sort_by_key(|f| rank(f));
    v
}

/// The sensitivity study's figures, in its table's order of columns.
const SENSITIVITY: [&str; 5] = ["critical_mu", "band_mu06_x0a", "x0d_bounces", "zt_sliding", "hybrid_closed_loop"];

/// Where a sweep's figure `file` goes among the sweep's: maps before slices, then its
/// case (impact law, `e_n`) in the order the sweep was given them.
pub fn sweep_rank(s: &SweepSummary, file: &str) -> (usize, usize) {
    let stem = file.rsplit('/').next().unwrap_or(file).trim_end_matches(".svg");
    let (kind, case) = stem.split_once('_').unwrap_or((stem, ""));
    let (law, e_n) = case.rsplit_once("_e").unwrap_or((case, ""));
    let e_n: f64 = e_n.parse().unwrap_or(f64::NAN);
    let spec = &s.spec;
    let l = spec.impact_laws.iter().position(|x| x.name() == law).unwrap_or(spec.impact_laws.len());
    let e = spec.e_n.iter().position(|x| (x - e_n).abs() < 1e-12).unwrap_or(spec.e_n.len());
    (usize::from(kind != "map"), l * (spec.e_n.len() + 1) + e)
}

/// A controller as the text names it: `PID`, `hybrid`.
fn law(kind: firmware::ControllerKind) -> &'static str {
    law_named(kind.name())
}

/// An impact law as the text names it: `Newton`, `Poisson`, `energetic`.
fn impacts(law: &str) -> String {
    match law {
        "newton" => "Newton".into(),
        "poisson" => "Poisson".into(),
        other => other.into(),
    }
}

/// The caption of `file` (its path in the report folder), a figure of the experiment
/// whose typed result is `outcome` (`None` when it failed before producing one: the
/// file's name only).
pub fn caption(outcome: Option<&Outcome>, file: &str) -> Caption {
    let Some(outcome) = outcome else { return other(file) };
    let name = file.rsplit('/').next().unwrap_or(file);
    let stem = name.strip_suffix(".svg").unwrap_or(name);
    if name == super::animations::FILE {
        return match super::animations::caption(Some(outcome), file) {
            Some((what, parameters)) => Caption { what, parameters, paper: None },
            None => other(file),
        };
    }
    let c = |what: &str, parameters: String, paper: Option<&str>| Caption {
        what: what.to_string(),
        parameters,
        paper: paper.map(str::to_string),
    };
    match outcome {
        Outcome::Modes(m) => c(
            "Contact mode at each point of the (theta1, theta1_dot) grid with the tip on the belt, with the curves b = 0, p = 0 and z_r_dot = 0",
            format!(
                "mu = {}, v_belt = {} m/s, u = 0, {}, a {} x {} grid",
                given(m.params.mu),
                given(m.params.v_belt),
                experiments::modes::branch_label(m),
                m.theta1.len(),
                m.theta1_dot.len()
            ),
            Some("Fig. 2"),
        ),
        Outcome::Admissible(a) => c(
            "p along the belt (z_n = -H) against z_t, one curve per elbow branch and slip direction: the tip can slide where p > 0",
            format!("mu = {}", given(a.params.mu)),
            Some("Table II (as numbers, no figure)"),
        ),
        Outcome::Simulate(s) => c(
            "One open-loop run against time: the tip's z_t and z_n, the normal force f_n and the contact mode",
            format!(
                "From {}, mu = {}, v_belt = {} m/s, open loop (u = 0), {} impacts with e_n = {}, {} s",
                s.initial_condition.name,
                given(s.params.mu),
                given(s.params.v_belt),
                impacts(s.sim.impact_law.name()),
                given(s.sim.e_n),
                given(s.duration_s)
            ),
            None,
        ),
        Outcome::Sweep(s) => sweep_caption(s, file, true),
        Outcome::Poincare(p) => {
            let parameters = format!(
                "From {}, mu = {}, open loop (u = 0), {} impacts with e_n = {}, v_belt from {} to {} m/s in steps of {}, a transient of {} s then {} s recorded",
                p.initial_condition.name,
                given(p.mu),
                impacts(p.sim.impact_law.name()),
                given(p.sim.e_n),
                given(p.v_belt_range[0]),
                given(p.v_belt_range[1]),
                given(p.v_step),
                given(p.transient_s),
                given(p.record_s)
            );
            match stem {
                "bifurcation" => c(
                    "theta1 at the Poincaré section (theta1_dot crossing 0 upwards) against v_belt, each belt speed coloured by its class (equilibrium, periodic, chaotic, ...)",
                    parameters,
                    Some("Fig. 4"),
                ),
                "lyapunov" => c("The Lyapunov exponent estimated for each belt speed against v_belt", parameters, None),
                _ => other(file),
            }
        }
        Outcome::Zmax(z) => {
            let row = z.results.iter().find(|r| stem == format!("zmax-{}-x0{}-{}", r.controller.name(), r.x0.letter(), r.setting.name()));
            let Some(r) = row else { return other(file) };
            let (at, target) = r.z_t_sliding_m.map_or_else(
                || {
                    (
                        "the bracket's lower end",
                        format!("z_t* = {} m (the bracket's lower end: no target passes)", super::format::position(r.bracket_lo_m)),
                    )
                },
                |v| ("its Z_t,sliding", format!("z_t* = {} m (its Z_t,sliding)", located(v, z.tol_m))),
            );
            let setting = if r.setting == analyses::zmax::Setting::Ideal {
                "The paper's ideal law (continuous time)"
            } else {
                "The sampled firmware"
            };
            let sc = &z.base_scenario;
            Caption {
                what: format!(
                    "The {} law from x0{} at {at}: z_t and z_t*, f_n, the torques and the contact mode against time",
                    law(r.controller),
                    r.x0.letter()
                ),
                parameters: format!(
                    "{setting}, a {} s move to {target}, mu = {}, v_belt = {} m/s, {} impacts with e_n = {}, {} s",
                    given(z.criteria.move_time_s),
                    given(sc.plant.mu),
                    given(sc.plant.v_belt),
                    impacts(sc.plant.impact_law.name()),
                    given(sc.plant.e_n),
                    given(z.criteria.duration_s)
                ),
                paper: Some(
                    "the Z_t,sliding of this case (docs/model.md experiments 5 and 6); Figs. 6 to 8 show runs of these laws".into(),
                ),
            }
        }
        Outcome::Sensitivity(s) => {
            let g = &s.study.grids;
            let open = format!(
                "open loop on {} and {}, {} s + {} s per run",
                axis_text("mu", &g.mu, ""),
                axis_text("v_belt", &g.v_belt, " m/s"),
                given(g.open_windows_s.0),
                given(g.open_windows_s.1)
            );
            let zmax = format!("bisection to {} m, {} s per trial", given(g.zmax_tol_m), given(g.zmax_duration_s));
            let closed = format!(
                "{}, {} s + {} s per run",
                axis_text("v_belt", &g.closed_v_belt, " m/s"),
                given(g.closed_windows_s.0),
                given(g.closed_windows_s.1)
            );
            let (what, parameters) = match stem {
                "critical_mu" => ("The critical mu from x0a and from x0d (open loop)", open),
                "band_mu06_x0a" => ("The main interval of persistent bouncing at mu = 0.6 from x0a (open loop)", open),
                "x0d_bounces" => ("Whether x0d bounces anywhere on the grid (open loop)", open),
                "zt_sliding" => ("Z_t,sliding of the four paper cases, ideal and sampled", zmax),
                "hybrid_closed_loop" => ("How the hybrid firmware's runs from x0d at mu = 0.6 ended over the belt speeds", closed),
                _ => return other(file),
            };
            Caption {
                what: format!("{what} under each choice the paper leaves open, one panel per choice, the default marked"),
                parameters: format!(
                    "The {} study: {parameters}",
                    if s.study.size == analyses::sensitivity::Size::Quick { "quick" } else { "paper-size" }
                ),
                paper: None,
            }
        }
        Outcome::Run(r) => {
            let sc = &r.scenario_used;
            match stem {
                "trace" => Caption {
                    what: format!(
                        "The {} law in the loop ({}): z_t and z_t*, f_n, the torques and the contact mode against time",
                        law_named(&r.controller),
                        r.transport
                    ),
                    parameters: scenario_parameters(sc),
                    paper: (r.pil.is_none()).then(|| "Figs. 6 to 8 (closed-loop runs of experiments 5 and 6)".to_string()),
                },
                "instructions" => Caption {
                    what: "Instructions of each control step of the MCU image in QEMU against time, with docs/hardware.md's budget".into(),
                    parameters: scenario_parameters(sc),
                    paper: None,
                },
                _ => other(file),
            }
        }
        Outcome::Bench(_) => other(file),
    }
}

/// A figure the page has no caption for: its name only.
fn other(file: &str) -> Caption {
    Caption { what: format!("`{file}`"), parameters: String::new(), paper: None }
}

/// A closed-loop scenario's parameters: the law, where from, the plant, the target, the timing.
fn scenario_parameters(sc: &Scenario) -> String {
    let c = &sc.controller;
    let law = match c.kind {
        firmware::ControllerKind::Hybrid => format!(
            "f_n* = {} N, mu_hat = {}, friction term {}",
            given(c.f_n_ref),
            given(c.mu_hat),
            serde_json::to_value(c.friction).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default()
        ),
        _ => "the paper's PID gains".to_string(),
    };
    format!(
        "Scenario {}: from x0{}, mu = {}, v_belt = {} m/s, {} impacts with e_n = {}, a {} s move to z_t* = {} m, {law}, sampled at {} Hz, {} s",
        sc.name,
        sc.plant.x0.letter(),
        given(sc.plant.mu),
        given(sc.plant.v_belt),
        impacts(sc.plant.impact_law.name()),
        given(sc.plant.e_n),
        given(c.move_time_s),
        given(c.target_z_t),
        given(sc.timing.rate_hz),
        given(sc.timing.duration_s)
    )
}

/// Who closes the loop in a sweep: open loop, or the law and how it runs.
pub fn sweep_controller(spec: &SweepSpec) -> String {
    match (spec.controller, spec.ideal) {
        (SweepController::None, _) => "open loop (u = 0)".into(),
        (k, true) => format!("the {} law as the paper's ideal law (continuous time, exact measurements)", k.kind().map_or("-", law)),
        (k, false) => {
            let rate = spec.scenario.as_ref().map_or(String::new(), |s| format!(" at {} Hz", given(s.timing.rate_hz)));
            format!("the {} law as the sampled firmware{rate}", k.kind().map_or("-", law))
        }
    }
}

/// The caption of a sweep's figure `file` (`map_<law>_e<e_n>.svg` or
/// `slices_<law>_e<e_n>.svg` in its folder).
///
/// Without `with_controller` the parameters leave out who closes the loop (the
/// side-by-side figure names it per column).
pub fn sweep_caption(s: &SweepSummary, file: &str, with_controller: bool) -> Caption {
    let name = file.rsplit('/').next().unwrap_or(file);
    let stem = name.strip_suffix(".svg").unwrap_or(name);
    let spec = &s.spec;
    let (kind, case) = stem.split_once('_').unwrap_or((stem, ""));
    let (law, e_n) = case.rsplit_once("_e").unwrap_or((case, ""));
    let ics: Vec<&str> = s.initial_conditions.iter().map(|i| i.name.as_str()).collect();
    let mut lead = Vec::new();
    if with_controller {
        lead.push(sweep_controller(spec));
    }
    match (&spec.scenario, spec.controller) {
        (Some(sc), SweepController::Hybrid) => {
            lead.push(format!("z_t* = {} m, f_n* = {} N", given(sc.controller.target_z_t), given(sc.controller.f_n_ref)));
        }
        (Some(sc), SweepController::Pid) => lead.push(format!("z_t* = {} m", given(sc.controller.target_z_t))),
        _ => {}
    }
    lead.push(format!("{} impacts with e_n = {e_n}, from {}", impacts(law), ics.join(" and ")));
    // A symbol (`z_t*`) starts the sentence as it is; words get a capital.
    let lead = if with_controller { upper_first(&lead.join(", ")) } else { lead.join(", ") };
    let parameters = format!(
        "{lead}; {}, {}; a transient of {} s then {} s recorded per run",
        axis_text("mu", &spec.mu, ""),
        axis_text("v_belt", &spec.v_belt, " m/s"),
        given(spec.transient_s),
        given(spec.record_s)
    );
    let fig = if spec.controller == SweepController::None { "Fig. 3" } else { "Fig. 9" };
    match kind {
        "map" if spec.seeds > 1 => Caption {
            what: format!(
                "The fraction of each cell's {} seeds that lift off over (v_belt, mu), one panel per initial condition; a ring marks a cell \
                 whose Wilson 95 % interval of its lift-off or its contact fraction holds one half",
                spec.seeds
            ),
            parameters: parameters.clone(),
            paper: Some(fig.into()),
        },
        "map" => Caption {
            what: "The outcome of each run over (v_belt, mu), one panel per initial condition".into(),
            parameters: parameters.clone(),
            paper: Some(fig.into()),
        },
        "slices" => Caption {
            what: "The bouncing indicator max theta1_dot over the record window against v_belt, one panel per mu, one curve per initial condition, with the threshold".into(),
            parameters,
            paper: Some(format!("the indicator behind {fig}, not drawn there")),
        },
        _ => other(file),
    }
}

/// `s` with its first letter upper-case.
pub fn upper_first(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or_else(String::new, |f| f.to_uppercase().chain(c).collect())
}

#[cfg(test)]
#[path = "captions_tests.rs"]
mod tests;
