//! The open-loop run (`u = 0`) of the arm on the belt (docs/model.md experiment
//! 3): the settings' check and the plant at `t = 0` ([`prepare`]), the sampling
//! loop both fronts run ([`OpenLoop`]), the trace and events rows and the summary.

use crate::{error::Error, settings::SimulateArgs};
use plant::initial::{self, PaperX0};
use plant::{Plant, SimConfig, SimError};

pub mod summary;
use summary::*;

/// The initial condition of `--x0` or, when given, `--x0-deg`: its name and
/// `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and degrees per second.
///
/// # Errors
/// [`crate::error::Error::Analysis`] for a malformed `--x0-deg`.
pub fn chosen_initial_condition(x0: PaperX0, x0_deg: Option<&crate::settings::NumberList>) -> Result<(String, [f64; 4]), Error> {
    Ok(match x0_deg {
        Some(s) => ("custom".to_string(), parse_x0_deg(s)?),
        None => {
            let ic = x0.condition();
            (ic.name.to_string(), ic.deg)
        }
    })
}

/// The initial condition of `--x0-deg th1,th1dot,th2,th2dot` (degrees, deg/s).
///
/// # Errors
/// [`crate::error::Error::Analysis`] unless it is four finite numbers.
pub fn parse_x0_deg(s: &crate::settings::NumberList) -> Result<[f64; 4], Error> {
    match s.0.as_slice() {
        [a, b, c, d] if s.0.iter().all(|x| x.is_finite()) => Ok([*a, *b, *c, *d]),
        _ => Err(Error::bad_input(format!("--x0-deg expects four finite numbers th1,th1dot,th2,th2dot (degrees, deg/s), got `{s}`"))),
    }
}

/// Checks the run-length options (`--duration`, `--sample-dt`) and returns the
/// number of samples after the first, `round(duration / sample_dt)` (at least 1).
///
/// # Errors
/// [`crate::error::Error::Analysis`] naming the option.
pub fn check_times(duration: f64, sample_dt: f64) -> Result<usize, Error> {
    if !(duration.is_finite() && duration > 0.0 && duration <= 1e6) {
        return Err(Error::bad_input(format!("--duration must be in (0, 1e6] s, got {duration}")));
    }
    if !(sample_dt.is_finite() && sample_dt > 0.0 && sample_dt <= duration) {
        return Err(Error::bad_input(format!("--sample-dt must be in (0, duration] s, got {sample_dt}")));
    }
    let n = (duration / sample_dt).round();
    if n > 5e7 {
        return Err(Error::bad_input(format!("--duration / --sample-dt gives {n} trace rows (at most 5e7); raise --sample-dt")));
    }
    Ok((n as usize).max(1))
}

/// The `trace.csv` row of the plant's current state, with the contact force `f`
/// (`[f_t, f_n]`, N) of the step that led there.
pub fn trace_row(plant: &Plant, f: [f64; 2]) -> TraceRow {
    let z = plant.tip();
    let v = plant.tip_velocity();
    let s = plant::Sample { t: plant.time(), x: plant.state(), tip: [z[0], z[1]], mode: plant.mode(), f };
    TraceRow::of_sample(&s, [v[0], v[1]], plant.arm().params.v_belt, plant.energy())
}

/// A simulation checked and set up, before anything is written: what
/// [`prepare`] returns.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The arm's parameters (paper Table I with `--set`, `--mu`, `--v-belt`).
    pub params: shared::Params<f64>,
    /// The simulator's settings.
    pub sim: SimConfig,
    /// Samples after the first ([`check_times`]).
    pub steps: usize,
    /// The initial condition as given and as used.
    pub initial_condition: InitialCondition,
    /// The plant at `t = 0` (projected onto the belt, initial mode chosen).
    pub plant: Plant,
}

/// Checks `sil-host simulate`'s options and sets the plant up at `t = 0`.
///
/// # Errors
/// [`crate::error::Error::Analysis`]
/// (exit 2) for bad options or initial conditions.
pub fn prepare(args: &SimulateArgs) -> Result<Prepared, Error> {
    let params = crate::arm::arm_params(&args.set, "simulate", &[], args.mu, args.v_belt)?;
    let sim = SimConfig {
        rtol: args.rtol,
        atol: args.atol,
        impact_law: args.impact_law,
        e_n: args.e_n,
        iwc: args.iwc,
        max_step: args.max_step,
        singular: args.singular,
        ..SimConfig::default()
    };
    sim.validate()?;
    let steps = check_times(args.duration, args.sample_dt)?;
    let (name, given_deg) = chosen_initial_condition(args.x0, args.x0_deg.as_ref())?;
    let plant = Plant::new(params, sim, initial::deg_to_state(given_deg), 0.0, [0.0, 0.0])?;
    let initial_condition = InitialCondition::of(name, given_deg, &params, &plant);
    Ok(Prepared { params, sim, steps, initial_condition, plant })
}

/// Advances the open loop (`u = 0`) to sample `k + 1`, at exactly
/// `(k + 1) sample_dt` s (no accumulated drift): one row of `trace.csv`.
///
/// # Errors
/// The plant's [`SimError`] when the step fails.
pub fn sample_step(plant: &mut Plant, k: usize, sample_dt: f64) -> Result<plant::StepReport, SimError> {
    let target = (k + 1) as f64 * sample_dt;
    plant.advance(&plant::Hold([0.0, 0.0]), target - plant.time(), &mut plant::NoObserver)
}

/// The row of `trace.csv` of a [`plant::Sample`] read inside an advance of `plant`.
pub fn sample_row(plant: &Plant, s: &plant::Sample) -> TraceRow {
    let (energy, v) = plant.energy_and_tip_velocity_of(&s.x);
    TraceRow::of_sample(s, v, plant.arm().params.v_belt, energy)
}

/// The open-loop sampling loop, the one both fronts run: the plant advanced with
/// its steps set by the tolerances (at most [`OpenLoop::max_step`], from the arm's
/// dynamics), each sample at
/// `(k + 1) sample_dt` s exactly read from the dense output of the step that covers
/// it (`Plant::advance_sampling`; issue 43), its [`TraceRow`] and the events
/// appended for the caller, who writes them, shows progress or stops between calls
/// of [`OpenLoop::advance`].
///
/// The integration does not depend on the sampling period nor on the duration
/// (issue 53): the plant is advanced in chunks that end at multiples of
/// [`OpenLoop::CHUNK_S`] s, whatever the samples, and the last chunk too is
/// integrated to its whole end, its samples past the duration dropped; the plant is
/// then taken back to the chunk's start and advanced to the last sample, for the
/// final state. A Moreau-Jean bridge gives its samples from its steps (linear
/// between their ends). Only a chunk that fails is advanced again sample by sample
/// ([`sample_step`]), so that the rows up to the failure are kept.
#[derive(Debug)]
pub struct OpenLoop {
    /// The plant, at the last sample taken.
    pub plant: Plant,
    /// Samples taken after the first (the row of `t = 0`).
    pub k: usize,
    /// Samples to take after the first ([`check_times`]).
    pub steps: usize,
    /// The sampling period, s.
    pub sample_dt: f64,
    /// The largest integrator step, s, whatever the sampling period (issue 53: the
    /// path must not depend on it): the configuration's `max_step` where given,
    /// else [`plant::time_scale::dense_max_step`] of the arm, 0.12 rad of its
    /// fastest mode (2.0 ms for the paper's arm, 0.22 ms for issue 67's short arm;
    /// docs/architecture.md "The accuracy contract").
    pub max_step: f64,
}

impl OpenLoop {
    /// The loop of a prepared simulation, with the first trace row (`t = 0`, the
    /// contact force of the initial mode) and the start-up events (the projection's
    /// touchdown, an impact at `t = 0`).
    pub fn start(prepared: Prepared, sample_dt: f64) -> (Self, TraceRow, Vec<EventRow>) {
        let Prepared { plant, steps, .. } = prepared;
        let row = trace_row(&plant, plant.contact_force([0.0, 0.0]));
        let events = plant.startup_events().iter().map(EventRow::from).collect();
        // An explicit `max_step` (`--max-step`, `plant.max_step`) is the cap, larger or
        // smaller than the arm's (issue 81: a run without the cap, its steps set by the
        // tolerances alone, for the path's contract).
        let max_step = plant.config().max_step.unwrap_or_else(|| plant::time_scale::dense_max_step(&plant.arm().params));
        (Self { plant, k: 0, steps, sample_dt, max_step }, row, events)
    }

    /// Whether every sample is taken.
    pub fn finished(&self) -> bool {
        self.k >= self.steps
    }

    /// Takes the samples up to `end` (at most [`OpenLoop::steps`]), rounded up to a
    /// whole chunk of [`OpenLoop::CHUNK_S`] s, appending one row per sample to
    /// `rows` and the events located on the way to `events`.
    ///
    /// # Errors
    /// The plant's [`SimError`] when a step fails: the samples before it are
    /// appended, [`OpenLoop::k`] counts them, and the loop is not advanced further.
    pub fn advance(&mut self, end: usize, rows: &mut Vec<TraceRow>, events: &mut Vec<EventRow>) -> Result<(), SimError> {
        let end = end.min(self.steps);
        while self.k < end {
            self.advance_chunk(rows, events)?;
        }
        Ok(())
    }

    /// The length of a chunk, s: the plant's solves end at its multiples whatever
    /// the sampling and the duration, so the path does not depend on them (issue
    /// 53); at most `0.25 / sample_dt` rows wait in memory.
    pub const CHUNK_S: f64 = 0.25;

    /// The time of sample `k`, s.
    fn sample_time(&self, k: usize) -> f64 {
        k as f64 * self.sample_dt
    }

    fn advance_chunk(&mut self, rows: &mut Vec<TraceRow>, events: &mut Vec<EventRow>) -> Result<(), SimError> {
        // The chunk after the plant's time: its end at a multiple of CHUNK_S.
        let t0 = self.plant.time();
        let mut chunk_end = ((t0 / Self::CHUNK_S).floor() + 1.0) * Self::CHUNK_S;
        if chunk_end <= t0 {
            chunk_end += Self::CHUNK_S;
        }
        // The samples in (t0, chunk_end], at most the last one of the run.
        let mut last = self.k;
        while last < self.steps && self.sample_time(last + 1) <= chunk_end {
            last += 1;
        }
        let before = self.plant.checkpoint();
        let grid = plant::SampleGrid { dt: self.sample_dt, next: self.k as u64 + 1, last: last as u64, max_step: self.max_step };
        let mut samples = vec![None; last - self.k];
        let sampled = self.plant.advance_sampling(&plant::Hold([0.0, 0.0]), chunk_end - t0, grid, &mut samples, &mut plant::NoObserver);
        match sampled {
            Ok(new) if samples.iter().all(Option::is_some) => {
                let t_last = self.sample_time(last);
                rows.extend(samples.iter().flatten().map(|s| sample_row(&self.plant, s)));
                if last == self.steps && t_last < self.plant.time() {
                    // The run ends inside this chunk: its events up to the end, and
                    // the plant taken back and advanced to the last sample.
                    events.extend(new.iter().filter(|e| e.t <= t_last).map(EventRow::from));
                    self.plant.restore(before);
                    if t_last > self.plant.time() {
                        self.plant.advance(&plant::Hold([0.0, 0.0]), t_last - self.plant.time(), &mut plant::NoObserver)?;
                    }
                } else {
                    events.extend(new.iter().map(EventRow::from));
                }
                self.k = last;
                Ok(())
            }
            // A failure somewhere in the chunk (or a sample no step covered):
            // sample by sample, so the rows up to a failure are kept.
            _ => {
                self.plant.restore(before);
                while self.k < last {
                    let report = sample_step(&mut self.plant, self.k, self.sample_dt)?;
                    events.extend(report.events.iter().map(EventRow::from));
                    rows.push(trace_row(&self.plant, report.f));
                    self.k += 1;
                }
                Ok(())
            }
        }
    }
}
/// `summary.json` of a simulation that ended with `plant` (after `failure`, if it
/// failed), which took `wall_s` s and wrote `files` with `events` events.
pub fn summary(
    args: &SimulateArgs,
    prepared: (shared::Params<f64>, SimConfig, InitialCondition),
    plant: &Plant,
    failure: Option<&SimError>,
    wall_s: f64,
    files: Vec<String>,
    events: usize,
) -> Summary {
    let (params, sim, initial_condition) = prepared;
    let counters = *plant.counters();
    let simulated_s = plant.time();
    Summary {
        status: if failure.is_some() { "failed" } else { "ok" },
        error: failure.map(|e| e.to_string()),
        params,
        sim,
        initial_condition,
        duration_s: args.duration,
        simulated_s,
        lift_offs: analyses::lift_offs::of(&counters),
        touchdowns: counters.touchdowns,
        impacts_without_collision: counters.impacts_without_collision,
        stick_phases: counters.stick_phases,
        validity: plant.validity(failure),
        counters,
        ledger: plant.ledger(),
        final_state: plant.state(),
        final_tip: [plant.tip()[0], plant.tip()[1]],
        final_mode: plant.mode().name(),
        wall_s,
        realtime_factor: simulated_s / wall_s.max(1e-9),
        files,
        events,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::initial::PaperX0;

    /// The loop of an open-loop run of `params` from `x0` (rad, rad/s) for `duration` s
    /// sampled every `dt` s.
    fn open_loop(params: shared::Params<f64>, sim: SimConfig, x0: [f64; 4], duration: f64, dt: f64) -> (OpenLoop, TraceRow, Vec<EventRow>) {
        let plant = Plant::new(params, sim, x0, 0.0, [0.0, 0.0]).unwrap();
        let steps = check_times(duration, dt).unwrap();
        let initial_condition = summary::InitialCondition::of(String::new(), x0.map(f64::to_degrees), &params, &plant);
        OpenLoop::start(Prepared { params, sim, steps, initial_condition, plant }, dt)
    }

    fn start(x0: PaperX0, duration: f64) -> (OpenLoop, TraceRow, Vec<EventRow>) {
        let x = plant::initial::deg_to_state(x0.condition().deg);
        open_loop(shared::Params::<f64>::paper(), SimConfig::default(), x, duration, 1e-3)
    }

    /// The trace does not depend on how a caller splits the run (the CLI asks for
    /// one sample at a time, Python too, a caller for all at once): the loop's
    /// solves end at whole chunks only. And the dense-output trace agrees with the
    /// plant stopped at every sample to the integrator's tolerance.
    #[test]
    fn the_trace_does_not_depend_on_how_the_run_is_split() {
        let runs: Vec<(Vec<TraceRow>, Vec<EventRow>)> = [1, 64, 5000]
            .iter()
            .map(|&n| {
                let (mut l, first, mut events) = start(PaperX0::A, 3.0);
                let mut rows = vec![first];
                while !l.finished() {
                    l.advance(l.k + n, &mut rows, &mut events).unwrap();
                }
                (rows, events)
            })
            .collect();
        let bits = |r: &[TraceRow]| {
            r.iter().map(|r| (r.t.to_bits(), r.theta1.to_bits(), r.theta2_dot.to_bits(), r.f_n.to_bits())).collect::<Vec<_>>()
        };
        assert_eq!(runs[0].0.len(), 3001);
        for (rows, events) in &runs[1..] {
            assert_eq!(bits(rows), bits(&runs[0].0));
            assert_eq!(events.len(), runs[0].1.len());
        }
        // Against the plant stopped at each sample (the old path): in tolerances, to 0.5 s.
        let (mut stopped, ..) = start(PaperX0::A, 3.0);
        let mut worst: f64 = 0.0;
        for (k, row) in runs[0].0.iter().enumerate().skip(1).take(500) {
            sample_step(&mut stopped.plant, k - 1, 1e-3).unwrap();
            let x = stopped.plant.state();
            for (a, b) in [row.theta1, row.theta1_dot, row.theta2, row.theta2_dot].iter().zip(x) {
                worst = worst.max((a - b).abs() / (1e-11 + 1e-9 * b.abs()));
            }
        }
        assert!(worst < 100.0, "{worst} tolerances from the plant stopped at each sample");
    }

    /// A whole open-loop run of `params` from `x0` (rad, rad/s) for `duration` s
    /// sampled every `dt` s: its rows, events and counters.
    fn whole_run(
        params: shared::Params<f64>,
        sim: SimConfig,
        x0: [f64; 4],
        duration: f64,
        dt: f64,
    ) -> (Vec<TraceRow>, Vec<EventRow>, plant::Counters) {
        let (mut l, first, mut events) = open_loop(params, sim, x0, duration, dt);
        let mut rows = vec![first];
        l.advance(l.steps, &mut rows, &mut events).unwrap();
        let counters = *l.plant.counters();
        (rows, events, counters)
    }

    fn row_bits(r: &TraceRow) -> [u64; 6] {
        [r.t.to_bits(), r.theta1.to_bits(), r.theta1_dot.to_bits(), r.theta2.to_bits(), r.theta2_dot.to_bits(), r.f_n.to_bits()]
    }

    fn event_bits(e: &EventRow) -> String {
        format!("{e:?}")
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 24, ..proptest::prelude::ProptestConfig::default() })]

        /// Issue 53: on random arms around issue 53's (each of `m`, `l`, `sigma`, `k`,
        /// `alpha0` within 1 %, `H` putting the start on the belt), from random starts
        /// within 0.2 deg of its start, at random `mu` across its singular-point band
        /// (0.414 to 0.428) and belt speeds within 0.02 m/s of its, under both IWC rules
        /// (runs through located `p = 0` passages and singular points among them): the
        /// events do not depend on the sample period (10 ms or 100 ms), a sample at the
        /// same instant is the same row to the bit, and a 30 s run is the first 30 s
        /// of a 60 s run.
        #[test]
        fn the_open_loop_path_depends_on_neither_the_sample_period_nor_the_duration_on_random_arms(
            f in proptest::array::uniform5(0.99f64..1.01),
            dq in proptest::array::uniform2(-0.2f64..0.2),
            mu in 0.414f64..0.428,
            v_belt in -0.52f64..-0.48,
            plastic in proptest::bool::ANY,
        ) {
            let mut params = shared::Params::<f64>::paper();
            (params.m, params.l, params.sigma, params.k, params.alpha0) = (0.15 * f[0], 0.23 * f[1], 0.008 * f[2], 1.0 * f[3], 0.20 * f[4]);
            let (q1, q2) = ((34.53531701873741 + dq[0]).to_radians(), (23.744016380660902 + dq[1]).to_radians());
            params.h = params.l * (q1.cos() + q2.cos());
            (params.mu, params.v_belt) = (mu, v_belt);
            let iwc = if plastic { plant::impact::IwcRule::Plastic } else { plant::impact::IwcRule::Restitution };
            let sim = SimConfig { iwc, ..SimConfig::default() };
            let x0 = [q1, 0.0, q2, 0.0];
            let (fine, fine_events, _) = whole_run(params, sim, x0, 60.0, 0.01);
            let (coarse, coarse_events, _) = whole_run(params, sim, x0, 60.0, 0.1);
            proptest::prop_assert_eq!(fine_events.iter().map(event_bits).collect::<Vec<_>>(), coarse_events.iter().map(event_bits).collect::<Vec<_>>());
            for (k, row) in coarse.iter().enumerate() {
                let other = &fine[10 * k];
                if row.t.to_bits() == other.t.to_bits() {
                    proptest::prop_assert_eq!(row_bits(row), row_bits(other), "t = {}", row.t);
                }
            }
            let (short, short_events, _) = whole_run(params, sim, x0, 30.0, 0.01);
            proptest::prop_assert_eq!(short.iter().map(row_bits).collect::<Vec<_>>(), fine[..short.len()].iter().map(row_bits).collect::<Vec<_>>());
            proptest::prop_assert_eq!(short_events.iter().map(event_bits).collect::<Vec<_>>(), fine_events[..short_events.len()].iter().map(event_bits).collect::<Vec<_>>());
        }
    }
}
