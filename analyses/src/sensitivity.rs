//! The sensitivity study (`sil-host sensitivity`): the paper's headline results
//! recomputed under each choice the paper leaves open, one at a time from the
//! defaults (docs/model.md "What the paper leaves open"; docs/analyses.md
//! "Sensitivity").
//!
//! Choices ([`Choice`]): the impact law and `e_n`; the IWC rule; the hybrid law's
//! friction compensation; the reference's move time; the lift-off criterion; and
//! for the sampled firmware the control rate, the encoder resolution, the
//! load-cell noise and the mismatch of its friction estimate `mu_hat`.
//!
//! Headline results ([`ChoiceResult`]):
//! - open loop (the brute-force sweep of experiment 3 from `x0a` and `x0d`): the
//!   critical `mu` per initial condition, the belt-speed extent of persistent
//!   bouncing at `mu = 0.6` from `x0a`, and whether `x0d` ever bounces;
//! - `Z_t,sliding` (experiments 5 and 6) for the four paper cases (PID and hybrid
//!   from `x0d` and `x0u`), ideal and sampled;
//! - whether the hybrid closed loop (experiment 7, the sampled firmware from `x0d`
//!   at `mu = 0.6`) ever bounces over the belt speeds.
//!
//! A choice that does not enter a result (the controller's settings in open loop,
//! the sampled firmware's in the ideal setting, the hybrid law's friction term for
//! the PID) leaves it uncomputed (`None`): its value is the default's.
//!
//! The lift-off criterion counts a departure only when the tip rises above a gap:
//! for the sweeps from the highest tip position over the record window (taken
//! inside the integrator's steps), for `Z_t,sliding` from the samples
//! ([`crate::zmax::Criteria::lift_off_gap_m`]).

use std::sync::atomic::{AtomicBool, Ordering};

use firmware::{ControllerKind, config::FrictionCompensation};
use rayon::prelude::*;
use serde::Serialize;

use crate::AnalysisError;
use crate::sweep::{
    Axis, SweepController, SweepSpec,
    run::{self, Outcome, RunRow},
};
use crate::zmax::{self, Bisection, Combination, Criteria, Setting};
use plant::{
    Validity,
    impact::{ImpactLaw, IwcRule},
    initial::PaperX0,
};
use rig::scenario::Scenario;

/// How large the study is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Size {
    /// Coarse grids and short windows: a few minutes on 2 cores.
    Quick,
    /// The paper's resolution (experiment 3's grid, 250 s + 50 s, `Z_t,sliding` to 1 mm).
    Paper,
}

/// The grids and windows of a study size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Grids {
    /// Open loop: friction coefficients.
    pub mu: Axis,
    /// Open loop: belt speeds, m/s.
    pub v_belt: Axis,
    /// Open loop: transient and record window, s.
    pub open_windows_s: (f64, f64),
    /// Closed loop (hybrid, from `x0d`, `mu = 0.6`): belt speeds, m/s.
    pub closed_v_belt: Axis,
    /// Closed loop: transient and record window, s.
    pub closed_windows_s: (f64, f64),
    /// `Z_t,sliding`: bisection tolerance, m.
    pub zmax_tol_m: f64,
    /// `Z_t,sliding`: run length of a trial, s.
    pub zmax_duration_s: f64,
}

impl Size {
    /// The grids of this size.
    pub fn grids(self) -> Grids {
        match self {
            Self::Quick => Grids {
                mu: Axis { start: 0.1, stop: 1.0, step: 0.1 },
                v_belt: Axis { start: -1.0, stop: -0.1, step: 0.05 },
                open_windows_s: (100.0, 30.0),
                closed_v_belt: Axis { start: -1.0, stop: -0.1, step: 0.1 },
                closed_windows_s: (15.0, 10.0),
                zmax_tol_m: 4e-3,
                zmax_duration_s: 10.0,
            },
            Self::Paper => Grids {
                mu: Axis { start: 0.1, stop: 1.0, step: 0.1 },
                v_belt: Axis { start: -1.0, stop: -0.1, step: 0.005 },
                open_windows_s: (250.0, 50.0),
                closed_v_belt: Axis { start: -1.0, stop: -0.1, step: 0.02 },
                closed_windows_s: (250.0, 50.0),
                zmax_tol_m: 1e-3,
                zmax_duration_s: 10.0,
            },
        }
    }
}

/// Every open choice at one value: the defaults (the paper's set-up and ours,
/// docs/model.md and docs/hardware.md) or one of them changed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Knobs {
    /// Impact law.
    pub impact_law: ImpactLaw,
    /// Restitution coefficient.
    pub e_n: f64,
    /// Impact-without-collision rule.
    pub iwc: IwcRule,
    /// The hybrid law's friction term (sampled firmware).
    pub friction: FrictionCompensation,
    /// Duration of the reference's move, s.
    pub move_time_s: f64,
    /// Lift-off criterion: 0 for any departure, else the gap the tip must exceed, m.
    pub lift_off_gap_m: f64,
    /// Control rate of the sampled firmware, Hz.
    pub rate_hz: f64,
    /// Joint encoder resolution, bits per revolution.
    pub encoder_bits: u8,
    /// Load-cell white noise, N rms.
    pub load_noise_n: f64,
    /// Relative error of the firmware's friction estimate: `mu_hat = (1 + m) mu`.
    pub mu_hat_mismatch: f64,
}

impl Default for Knobs {
    fn default() -> Self {
        Self {
            impact_law: ImpactLaw::Newton,
            e_n: 0.2,
            iwc: IwcRule::Restitution,
            friction: FrictionCompensation::ModelCommandedNormal,
            move_time_s: 2.0,
            lift_off_gap_m: 0.0,
            rate_hz: 1000.0,
            encoder_bits: 14,
            load_noise_n: 0.02,
            mu_hat_mismatch: 0.0,
        }
    }
}

impl Knobs {
    /// `base` with these knobs: the plant's impact law, `e_n` and IWC rule, the
    /// controller's friction term, move time and `mu_hat`, the rate (the delay
    /// from sampling to the command, `delta_s`, kept the same fraction of the
    /// period), the encoders and the load-cell noise.
    pub fn scenario(&self, base: &Scenario) -> Scenario {
        let mut s = base.clone();
        s.plant.impact_law = self.impact_law;
        s.plant.e_n = self.e_n;
        s.plant.iwc = self.iwc;
        s.controller.friction = self.friction;
        s.controller.move_time_s = self.move_time_s;
        s.controller.mu_hat = base.plant.mu * (1.0 + self.mu_hat_mismatch);
        s.timing.delta_s = base.timing.delta_s * base.timing.rate_hz / self.rate_hz;
        s.timing.rate_hz = self.rate_hz;
        s.sensors.encoder_bits = self.encoder_bits;
        s.sensors.load_noise_n = self.load_noise_n;
        s
    }
}

/// Which open choice a [`Choice`] varies (the study's dimensions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Dimension {
    /// Impact law and `e_n`.
    ImpactLaw,
    /// The IWC rule.
    Iwc,
    /// The hybrid law's friction compensation.
    Friction,
    /// The reference's move time.
    MoveTime,
    /// The lift-off criterion.
    LiftOff,
    /// The sampled firmware's rate.
    Rate,
    /// Encoder resolution.
    EncoderBits,
    /// Load-cell noise.
    LoadNoise,
    /// `mu_hat` mismatch.
    MuHat,
}

impl Dimension {
    /// Every dimension, in the study's order.
    pub const ALL: [Dimension; 9] = [
        Self::ImpactLaw,
        Self::Iwc,
        Self::Friction,
        Self::MoveTime,
        Self::LiftOff,
        Self::Rate,
        Self::EncoderBits,
        Self::LoadNoise,
        Self::MuHat,
    ];

    /// A label for tables and figures.
    pub fn label(self) -> &'static str {
        match self {
            Self::ImpactLaw => "impact law, e_n",
            Self::Iwc => "IWC rule",
            Self::Friction => "hybrid friction term",
            Self::MoveTime => "move time (s)",
            Self::LiftOff => "lift-off criterion",
            Self::Rate => "control rate (Hz)",
            Self::EncoderBits => "encoder bits",
            Self::LoadNoise => "load-cell noise (N rms)",
            Self::MuHat => "mu_hat mismatch",
        }
    }

    /// Whether the choice enters the open-loop results (no controller).
    pub fn in_open_loop(self) -> bool {
        matches!(self, Self::ImpactLaw | Self::Iwc | Self::LiftOff)
    }

    /// Whether the choice enters the ideal (continuous-time, exact) controllers.
    pub fn in_ideal(self) -> bool {
        matches!(self, Self::ImpactLaw | Self::Iwc | Self::MoveTime | Self::LiftOff)
    }

    /// Whether the choice enters the controller `kind` (the friction term is the hybrid law's).
    pub fn in_controller(self, kind: ControllerKind) -> bool {
        self != Self::Friction || kind == ControllerKind::Hybrid
    }
}

/// One value of one open choice (the others at their defaults).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Choice {
    /// The dimension varied.
    pub dimension: Dimension,
    /// The value, as text (`poisson, e_n = 0.5`, `plastic`, `0.5`, ...).
    pub value: String,
    /// The value as a number where it is one (for figures), else the index in its dimension.
    pub x: f64,
    /// Whether this is the default value.
    pub is_default: bool,
    /// All knobs.
    pub knobs: Knobs,
}

/// The choices of the study, dimension by dimension, each with its default among them.
pub fn choices() -> Vec<Choice> {
    let d = Knobs::default();
    let mut v = Vec::new();
    let mut push = |dimension, value: String, x: f64, knobs: Knobs| {
        v.push(Choice { dimension, value, x, is_default: knobs == d, knobs });
    };
    let mut i = 0.0;
    for law in ImpactLaw::ALL {
        for e_n in [0.0, 0.2, 0.5] {
            push(Dimension::ImpactLaw, format!("{law}, e_n = {e_n}"), i, Knobs { impact_law: law, e_n, ..d });
            i += 1.0;
        }
    }
    for (k, iwc) in IwcRule::ALL.into_iter().enumerate() {
        push(Dimension::Iwc, iwc.to_string(), k as f64, Knobs { iwc, ..d });
    }
    let frictions = [
        (FrictionCompensation::ModelCommandedNormal, "commanded"),
        (FrictionCompensation::ModelMeasuredNormal, "measured_normal"),
        (FrictionCompensation::Measured, "measured"),
        (FrictionCompensation::None, "none"),
    ];
    for (k, (friction, name)) in frictions.into_iter().enumerate() {
        push(Dimension::Friction, name.into(), k as f64, Knobs { friction, ..d });
    }
    for t in [0.1, 0.25, 0.5, 1.0, 2.0] {
        push(Dimension::MoveTime, format!("{t}"), t, Knobs { move_time_s: t, ..d });
    }
    for (gap, name) in [(0.0, "any departure"), (1e-6, "gap > 1 um"), (1e-4, "gap > 0.1 mm")] {
        push(Dimension::LiftOff, name.into(), gap, Knobs { lift_off_gap_m: gap, ..d });
    }
    for r in [250.0, 500.0, 1000.0, 2000.0, 5000.0, 10_000.0] {
        push(Dimension::Rate, format!("{r}"), r, Knobs { rate_hz: r, ..d });
    }
    for b in 12..=16u8 {
        push(Dimension::EncoderBits, format!("{b}"), f64::from(b), Knobs { encoder_bits: b, ..d });
    }
    for n in [0.0, 0.01, 0.02, 0.05, 0.1] {
        push(Dimension::LoadNoise, format!("{n}"), n, Knobs { load_noise_n: n, ..d });
    }
    for m in [-0.2, -0.1, 0.0, 0.1, 0.2] {
        push(Dimension::MuHat, format!("{:+}%", (m * 100.0f64).round()), m, Knobs { mu_hat_mismatch: m, ..d });
    }
    v
}

/// The open-loop headline results under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpenLoop {
    /// Critical `mu` from `x0a` (the smallest `mu` of the grid with persistent bouncing).
    pub critical_mu_x0a: Option<f64>,
    /// Critical `mu` from `x0d`.
    pub critical_mu_x0d: Option<f64>,
    /// Extent `[v_min, v_max]` (m/s) of persistent bouncing at `mu = 0.6` from `x0a`.
    pub band_x0a_mu06: Option<[f64; 2]>,
    /// Grid speeds with persistent bouncing at `mu = 0.6` from `x0a`.
    pub band_points: usize,
    /// Whether `x0d` bounces persistently anywhere on the grid.
    pub x0d_bounces: bool,
    /// Runs that violate the model (left out).
    pub invalid_runs: usize,
    /// Validity summed over the runs.
    pub validity: Validity,
}

/// `Z_t,sliding` of one case under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Zmax {
    /// The case.
    pub combination: Combination,
    /// `Z_t,sliding`, m (`None` when the bracket's lower end already fails).
    pub z_t_sliding: Option<f64>,
    /// `found`, `lower_fails` or `upper_reached`.
    pub outcome: &'static str,
    /// Validity summed over the trials.
    pub validity: Validity,
}

/// The hybrid closed loop's headline under one choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClosedLoop {
    /// Whether it bounces persistently at any belt speed.
    pub bounces: bool,
    /// Belt speeds with persistent bouncing.
    pub bouncing_points: usize,
    /// Belt speeds with a result.
    pub points: usize,
    /// Runs that stopped early (failure or safe state).
    pub stopped_runs: usize,
    /// Validity summed over the runs.
    pub validity: Validity,
}

/// The headline results under one choice (`None`: the choice does not enter that result).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChoiceResult {
    /// The choice.
    pub choice: Choice,
    /// Open loop.
    pub open_loop: Option<OpenLoop>,
    /// `Z_t,sliding` per case (the cases the choice enters).
    pub zmax: Vec<Zmax>,
    /// The hybrid closed loop.
    pub closed_loop: Option<ClosedLoop>,
}

/// The whole study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Study {
    /// Its size.
    pub size: Size,
    /// Its grids.
    pub grids: Grids,
    /// The defaults every choice starts from.
    pub defaults: Knobs,
    /// One result per choice (the defaults appear once per dimension).
    pub results: Vec<ChoiceResult>,
    /// Validity summed over everything simulated.
    pub validity: Validity,
}

/// A flat row of the study's table (`sensitivity.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Dimension label.
    pub choice: &'static str,
    /// The value.
    pub value: String,
    /// Whether it is the default.
    pub is_default: bool,
    /// The headline result's name.
    pub result: String,
    /// Its value (a number, `true`/`false`, or `none`).
    pub outcome: String,
}

impl Study {
    /// The table: one row per choice and headline result computed under it.
    pub fn rows(&self) -> Vec<Row> {
        let mut rows = Vec::new();
        for r in &self.results {
            let c = &r.choice;
            let mut push = |result: String, outcome: String| {
                rows.push(Row { choice: c.dimension.label(), value: c.value.clone(), is_default: c.is_default, result, outcome });
            };
            let num = |x: Option<f64>| x.map_or("none".to_string(), |v| format!("{v}"));
            if let Some(o) = &r.open_loop {
                push("critical_mu_x0a".into(), num(o.critical_mu_x0a));
                push("critical_mu_x0d".into(), num(o.critical_mu_x0d));
                push("band_mu0.6_x0a_from".into(), num(o.band_x0a_mu06.map(|b| b[0])));
                push("band_mu0.6_x0a_to".into(), num(o.band_x0a_mu06.map(|b| b[1])));
                push("x0d_bounces".into(), o.x0d_bounces.to_string());
            }
            for z in &r.zmax {
                let k = z.combination;
                push(format!("zt_sliding_{}_x0{}_{}", k.controller, k.x0, k.setting), num(z.z_t_sliding));
            }
            if let Some(cl) = &r.closed_loop {
                push("hybrid_closed_loop_bounces".into(), cl.bounces.to_string());
            }
        }
        rows
    }
}

/// A unit of work: one sweep run, or one `Z_t,sliding` search.
enum Job {
    Sweep { spec: usize, index: usize },
    Search(usize),
}

/// Runs the study from `base` (the sampled setting's scenario and the arm's
/// parameters: the embedded default unless the caller gives another) at `size`,
/// in parallel on the current rayon pool; `progress(done, total)` after each job;
/// `stop` ends it early (an [`AnalysisError::Interrupted`]).
///
/// # Errors
/// [`AnalysisError`] for a base scenario the study cannot use, or when stopped.
pub fn run(base: &Scenario, size: Size, stop: &AtomicBool, progress: &(dyn Fn(u64, u64) + Sync)) -> Result<Study, AnalysisError> {
    base.validate()?;
    let grids = size.grids();
    let choices = choices();
    for c in &choices {
        c.knobs.scenario(base).validate()?;
    }
    // Distinct sweeps: the open loop per (law, e_n, IWC); the closed loop per choice.
    let mut specs: Vec<SweepSpec> = Vec::new();
    let mut open_of = vec![None; choices.len()];
    let mut closed_of = vec![None; choices.len()];
    for (i, c) in choices.iter().enumerate() {
        if c.dimension.in_open_loop() {
            let spec = open_spec(base, &grids, &c.knobs);
            let at = specs.iter().position(|s| *s == spec).unwrap_or_else(|| {
                specs.push(spec);
                specs.len() - 1
            });
            open_of[i] = Some(at);
        }
        let spec = closed_spec(base, &grids, &c.knobs);
        let at = specs.iter().position(|s| *s == spec).unwrap_or_else(|| {
            specs.push(spec);
            specs.len() - 1
        });
        closed_of[i] = Some(at);
    }
    let mut jobs: Vec<Job> = Vec::new();
    for (s, spec) in specs.iter().enumerate() {
        jobs.extend((0..spec.n_runs()).map(|index| Job::Sweep { spec: s, index }));
    }
    // Distinct searches: the defaults of every dimension (and any other choice that
    // gives the same knobs) share one search per case.
    let mut wanted: Vec<(Knobs, Combination)> = Vec::new();
    let mut search_of: Vec<Vec<usize>> = vec![Vec::new(); choices.len()];
    for (i, c) in choices.iter().enumerate() {
        for combination in combinations(c) {
            let at = wanted.iter().position(|w| *w == (c.knobs, combination)).unwrap_or_else(|| {
                wanted.push((c.knobs, combination));
                wanted.len() - 1
            });
            search_of[i].push(at);
        }
    }
    jobs.extend((0..wanted.len()).map(Job::Search));
    // The costly jobs first, so that the pool ends together.
    jobs.sort_by_key(|j| match j {
        Job::Search(_) => 0,
        Job::Sweep { spec, .. } => usize::from(specs[*spec].controller == SweepController::None) + 1,
    });
    let total = jobs.len() as u64;
    let done = std::sync::atomic::AtomicU64::new(0);
    let ics: Vec<_> = specs.iter().map(SweepSpec::initial_conditions).collect();
    enum Out {
        Row(usize, RunRow),
        Search(usize, Zmax),
    }
    let outs: Vec<Result<Out, AnalysisError>> = jobs
        .par_iter()
        .with_max_len(1)
        .filter_map(|job| {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            let out = match job {
                Job::Sweep { spec, index } => {
                    let key = specs[*spec].run_at(*index);
                    run::simulate(&specs[*spec], &key, &ics[*spec][key.i_ic], stop).map(|r| Ok(Out::Row(*spec, r)))
                }
                Job::Search(w) => {
                    let (knobs, combination) = &wanted[*w];
                    Some(search(base, &grids, knobs, *combination).map(|z| Out::Search(*w, z)))
                }
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            out
        })
        .collect();
    if stop.load(Ordering::Relaxed) {
        return Err(AnalysisError::Interrupted("sensitivity study stopped".into()));
    }
    let mut rows: Vec<Vec<RunRow>> = vec![Vec::new(); specs.len()];
    let mut found: Vec<Option<Zmax>> = vec![None; wanted.len()];
    for o in outs {
        match o? {
            Out::Row(s, r) => rows[s].push(r),
            Out::Search(w, z) => found[w] = Some(z),
        }
    }
    let mut validity = Validity::default();
    let results: Vec<ChoiceResult> = choices
        .into_iter()
        .enumerate()
        .map(|(i, choice)| {
            let gap = choice.knobs.lift_off_gap_m;
            let open_loop = open_of[i].map(|s| open_results(&specs[s], &rows[s], gap));
            let closed_loop = closed_of[i].map(|s| closed_results(&rows[s], gap));
            // In Combination::all()'s order, as combinations() gives them.
            let zmax = search_of[i].iter().filter_map(|&w| found[w].clone()).collect();
            ChoiceResult { choice, open_loop, zmax, closed_loop }
        })
        .collect();
    for r in &rows {
        for row in r {
            validity.add(&row.validity());
        }
    }
    for z in found.iter().flatten() {
        validity.add(&z.validity);
    }
    Ok(Study { size, grids, defaults: Knobs::default(), results, validity })
}

/// The `Z_t,sliding` cases a choice enters.
fn combinations(c: &Choice) -> Vec<Combination> {
    Combination::all()
        .into_iter()
        .filter(|k| c.dimension.in_controller(k.controller))
        .filter(|k| k.setting == Setting::Sampled || c.dimension.in_ideal())
        .collect()
}

/// Persistent bouncing under a lift-off gap: the sweep's outcome (open loop's
/// bouncing, closed loop's lift-off), and the tip above the gap in the record window.
fn bounces(r: &RunRow, gap: f64) -> bool {
    r.outcome.is_bouncing() && (gap == 0.0 || r.tip_height_max > gap)
}

fn open_spec(base: &Scenario, g: &Grids, k: &Knobs) -> SweepSpec {
    SweepSpec {
        mu: g.mu,
        v_belt: g.v_belt,
        iwc_rules: vec![k.iwc],
        impact_laws: vec![k.impact_law],
        e_n: vec![k.e_n],
        paper_ics: vec![PaperX0::A, PaperX0::D],
        transient_s: g.open_windows_s.0,
        record_s: g.open_windows_s.1,
        rtol: base.plant.rtol,
        atol: base.plant.atol,
        params: base.plant.params(),
        ..SweepSpec::paper()
    }
}

fn closed_spec(base: &Scenario, g: &Grids, k: &Knobs) -> SweepSpec {
    let mu = base.plant.mu;
    SweepSpec {
        mu: Axis { start: mu, stop: mu, step: 0.1 },
        v_belt: g.closed_v_belt,
        iwc_rules: vec![k.iwc],
        impact_laws: vec![k.impact_law],
        e_n: vec![k.e_n],
        paper_ics: vec![PaperX0::D],
        transient_s: g.closed_windows_s.0,
        record_s: g.closed_windows_s.1,
        controller: SweepController::Hybrid,
        scenario: Some(k.scenario(base)),
        rtol: base.plant.rtol,
        atol: base.plant.atol,
        params: base.plant.params(),
        mu_hat_factor: 1.0 + k.mu_hat_mismatch,
        ..SweepSpec::paper()
    }
}

fn open_results(spec: &SweepSpec, rows: &[RunRow], gap: f64) -> OpenLoop {
    let mut validity = Validity::default();
    let valid: Vec<&RunRow> = rows.iter().filter(|r| r.outcome != Outcome::Invalid).collect();
    for r in rows {
        validity.add(&r.validity());
    }
    let critical = |ic: &str| spec.mu.values().into_iter().find(|&mu| valid.iter().any(|r| r.ic == ic && r.mu == mu && bounces(r, gap)));
    let at06: Vec<f64> = valid.iter().filter(|r| r.ic == "x0a" && (r.mu - 0.6).abs() < 1e-9 && bounces(r, gap)).map(|r| r.v_belt).collect();
    let band = (!at06.is_empty()).then(|| [at06.iter().cloned().fold(f64::MAX, f64::min), at06.iter().cloned().fold(f64::MIN, f64::max)]);
    OpenLoop {
        critical_mu_x0a: critical("x0a"),
        critical_mu_x0d: critical("x0d"),
        band_x0a_mu06: band,
        band_points: at06.len(),
        x0d_bounces: valid.iter().any(|r| r.ic == "x0d" && bounces(r, gap)),
        invalid_runs: rows.len() - valid.len(),
        validity,
    }
}

fn closed_results(rows: &[RunRow], gap: f64) -> ClosedLoop {
    let mut validity = Validity::default();
    for r in rows {
        validity.add(&r.validity());
    }
    let bouncing = rows.iter().filter(|r| bounces(r, gap)).count();
    ClosedLoop {
        bounces: bouncing > 0,
        bouncing_points: bouncing,
        points: rows.iter().filter(|r| r.outcome != Outcome::Invalid).count(),
        stopped_runs: rows.iter().filter(|r| matches!(r.outcome, Outcome::Failed | Outcome::SafeState)).count(),
        validity,
    }
}

fn search(base: &Scenario, g: &Grids, k: &Knobs, combination: Combination) -> Result<Zmax, AnalysisError> {
    let s = k.scenario(base);
    let c = Criteria {
        duration_s: g.zmax_duration_s.max(k.move_time_s + 2.0),
        move_time_s: k.move_time_s,
        lift_off_gap_m: k.lift_off_gap_m,
        ..Criteria::default()
    };
    let bracket = zmax::default_bracket(&s, combination.x0)?;
    let found = zmax::search(&s, combination, bracket, g.zmax_tol_m, &c, |_| {})?;
    let mut validity = Validity::default();
    for t in &found.trials {
        validity.add(&t.validity);
    }
    let outcome = match found.bisection {
        Bisection::Found { .. } => "found",
        Bisection::LowerFails { .. } => "lower_fails",
        Bisection::UpperReached { .. } => "upper_reached",
    };
    Ok(Zmax { combination, z_t_sliding: found.z_t_sliding, outcome, validity })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_dimension_has_its_default_once_and_only_one_knob_changes() {
        let all = choices();
        let d = Knobs::default();
        for dim in Dimension::ALL {
            let of: Vec<&Choice> = all.iter().filter(|c| c.dimension == dim).collect();
            assert!(of.len() >= 2, "{dim:?}");
            assert_eq!(of.iter().filter(|c| c.is_default).count(), 1, "{dim:?}: one default");
        }
        // Each choice differs from the defaults in at most one knob (the impact
        // dimension moves the law and e_n together).
        for c in &all {
            let k = c.knobs;
            let changed = [
                k.impact_law != d.impact_law || k.e_n != d.e_n,
                k.iwc != d.iwc,
                k.friction != d.friction,
                k.move_time_s != d.move_time_s,
                k.lift_off_gap_m != d.lift_off_gap_m,
                k.rate_hz != d.rate_hz,
                k.encoder_bits != d.encoder_bits,
                k.load_noise_n != d.load_noise_n,
                k.mu_hat_mismatch != d.mu_hat_mismatch,
            ];
            assert!(changed.iter().filter(|x| **x).count() <= 1, "{c:?}");
        }
    }

    #[test]
    fn the_default_knobs_are_the_default_scenario() {
        let base = Scenario::default_scenario();
        let s = Knobs::default().scenario(&base);
        assert_eq!(s, base, "the defaults reproduce the embedded scenario");
    }

    #[test]
    fn choices_enter_only_the_results_they_change() {
        let all = choices();
        let rate = all.iter().find(|c| c.dimension == Dimension::Rate && !c.is_default).unwrap();
        assert!(!rate.dimension.in_open_loop());
        assert!(combinations(rate).iter().all(|k| k.setting == Setting::Sampled));
        let friction = all.iter().find(|c| c.dimension == Dimension::Friction && !c.is_default).unwrap();
        assert!(combinations(friction).iter().all(|k| k.controller == ControllerKind::Hybrid && k.setting == Setting::Sampled));
        let law = all.iter().find(|c| c.dimension == Dimension::ImpactLaw).unwrap();
        assert_eq!(combinations(law).len(), 8);
    }
}
