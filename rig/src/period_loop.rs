//! The plant side of the SIL loop, the same for every transport (docs/hardware.md
//! "Control loop"). Period `k`: the sensors sample the plant at `t_k = k Ts` into
//! a frame; the frame goes to the firmware over a [`FirmwareLink`] (in-process or
//! iceoryx2); the command that comes back takes effect at
//! `max(t_k + delta, t_sent)` (in real-time runs: at `t_sent`, the firmware's
//! wall-clock send stamp) and is held (zero-order hold) until the next one. A command that is
//! lost, late past `t_k + Ts`, or not there when the link gives up waiting is a
//! deadline miss: the previous command stays for the whole period.
//!
//! The plant owns time: the loop never reads a clock (real-time pacing is the
//! link's business), so a run is a function of the scenario and its seed.

use shared::{
    ContactMode,
    wire::{GroundTruth, SensorFrame, status},
};

use super::{
    link::{DropCommands, Exchange, FirmwareLink},
    record::{PeriodRecord, RunError},
    sensors::{SensorFaults, SensorModel, Sensors},
    setup::RunSetup,
};
use plant::{Hold, NoObserver, Observer, Plant, PlantEvent, Sample, Validity};

/// Ground-truth mode code of [`GroundTruth::mode`]: 0 flight, 1 sliding, 2 sticking.
pub fn mode_code(mode: ContactMode) -> u8 {
    match mode {
        ContactMode::Sliding => 1,
        ContactMode::Sticking => 2,
        _ => 0,
    }
}

/// Why a period of [`PeriodLoop::period`] ended the run.
#[derive(Debug)]
pub struct PeriodFailure {
    /// The period's record, when it got that far (the firmware's safe state, a plant failure).
    pub record: Option<PeriodRecord>,
    /// What happened.
    pub error: RunError,
}

/// The plant side of a run's control periods: the sensors, the faults, the command
/// held by the zero-order hold and the last contact force, period after period.
/// [`run_loop`] drives it over a whole scenario; the closed-loop sweep
/// (`sil-host sweep --controller`) drives it from its own initial conditions.
#[derive(Debug, Clone)]
pub struct PeriodLoop {
    /// The sensor models with the run's faults (its plan also drives [`DropCommands`]).
    sensors: SensorFaults<Sensors>,
    /// The control period: `t_k = k period` (its seconds, `Period::as_secs_f64`, where
    /// the plant's `f64` time needs them).
    period: shared::Period,
    delta: f64,
    v_belt: f64,
    applied: [f64; 2],
    f_now: [f64; 2],
    /// The firmware's reference, kept over periods without an answer.
    z_t_ref: f64,
    k: usize,
    /// Whether the period's first part may run while the firmware computes ([`PeriodLoop::overlapping`]).
    overlap: bool,
    /// The look-ahead: the plant is at `t_k + delta`, past the sample at `t_k`
    /// (this), having stepped from the last zero-order-hold switch to the next.
    ahead: Option<Sample>,
    /// Whether commands may take effect at their send stamp, before `t_k + delta`
    /// (a real-time link): then the plant cannot step past `t_k + delta` ahead of
    /// the answer, and the look-ahead is off.
    stamped: bool,
}

impl PeriodLoop {
    /// The loop of `setup` starting at period 0 with zero torque on `plant` (at
    /// `t = 0`: the setup's own, [`RunSetup::plant`], or a caller's at another
    /// initial state, as the sweep's grid).
    pub fn new(setup: &RunSetup, plant: &Plant) -> Self {
        let s = setup.scenario();
        let period = s.timing.period();
        Self {
            sensors: SensorFaults::new(
                Sensors::new(s.sensors.seed, s.sensors.load_noise_n, period).with_encoder_bits(s.sensors.encoder_bits),
                setup.faults().clone(),
            ),
            period,
            delta: s.timing.delta_s,
            v_belt: s.plant.v_belt,
            applied: [0.0; 2],
            f_now: plant.contact_force([0.0; 2]),
            z_t_ref: f64::NAN,
            k: 0,
            overlap: false,
            ahead: None,
            stamped: false,
        }
    }

    /// Lets the plant run the period's first part, under the held command up to
    /// `t_k + delta`, while the firmware computes, on links that send ahead
    /// ([`FirmwareLink::send_ahead`]: lockstep over iceoryx2). Only for a caller
    /// whose trajectory observer is [`NoObserver`] (the first part runs before the
    /// answer is known, unobserved). When the answer takes effect at `t_k + delta`
    /// (every period of a lockstep run without a late or lost command) the result
    /// is that first part; otherwise the plant goes back to `t_k`
    /// ([`Plant::restore`]) and the period runs as without overlap: the trace is
    /// the same to the bit either way.
    pub fn overlapping(self, overlap: bool) -> Self {
        Self { overlap, ..self }
    }

    /// Control periods in `duration_s` seconds.
    pub fn periods_in(&self, duration_s: f64) -> usize {
        (duration_s / self.period.as_secs_f64()).round() as usize
    }

    /// The next period to run.
    pub fn next_period(&self) -> usize {
        self.k
    }

    /// Runs one period: samples `plant` into a frame (handed to `run`'s
    /// [`RunObserver::on_frame`]), gets the command over `link` and advances the
    /// plant to the next sample time under the zero-order hold, handing `run` the
    /// plant's events at their exact times and `obs` the continuous trajectory
    /// ([`plant::Observer`]). Returns the period's record.
    ///
    /// # Errors
    /// The link's failure (no record), or the firmware's safe state or a plant
    /// failure (with the period's record).
    pub fn period(
        &mut self,
        plant: &mut Plant,
        link: &mut dyn FirmwareLink,
        run: &mut dyn RunObserver,
        obs: &mut dyn Observer,
    ) -> Result<PeriodRecord, Box<PeriodFailure>> {
        let k = self.k;
        let ts = self.period.as_secs_f64();
        let t_k = k as f64 * ts;
        // The frame's stamp: k whole periods (shared::time); t_k is the same instant in s.
        let t_us = self.period.sample(k as u64).as_us();
        // The sample at t_k: read on the way when the plant stepped past it (the
        // look-ahead), else the plant's own state.
        let (x, z, mode) = match &self.ahead {
            Some(s) => (s.x, s.tip, s.mode),
            None => (plant.state(), [plant.tip()[0], plant.tip()[1]], plant.mode()),
        };
        // The belt's travel at the sample, as the board links' counter sees it
        // (`v_belt t_k`, the ground truth's `t`): docs/hardware.md "The belt sensor's model".
        let frame = self.sensors.frame(k as u32, t_us, &x, self.f_now, self.v_belt * t_k);
        run.on_frame(&frame);
        let truth = GroundTruth {
            t: t_k,
            seq: k as u32,
            mode: mode_code(mode),
            lift_off: u8::from(mode == ContactMode::Flight),
            reserved: 0,
            x,
            z: [z[0], z[1]],
            f: self.f_now,
            u_applied: self.applied,
        };
        link.before_period(k as u64);
        self.stamped = link.switches_at_stamp();
        let mut wire = DropCommands { inner: link, plan: self.sensors.plan() };
        let fail = |error| Box::new(PeriodFailure { record: None, error });
        // The first part of the period, run while the firmware computes (see
        // `overlapping`), with the plant's state before it.
        let ahead = if self.ahead.is_none()
            && self.overlap
            && self.delta > 0.0
            && self.delta < ts
            && wire.send_ahead(&frame, &truth).map_err(fail)?
        {
            let before = plant.checkpoint();
            Some((before, plant.advance_events(&Hold(self.applied), self.delta, &mut NoObserver)))
        } else {
            None
        };
        let exchange = match wire.exchange(&frame, &truth) {
            Ok(e) => e,
            Err(error) => {
                if let Some((before, _)) = ahead {
                    plant.restore(before);
                }
                return Err(fail(error));
            }
        };
        run.on_answer(&frame, &truth, &exchange);
        // When the new command takes effect (s after t_k), if it does this period.
        let (switch, command, telemetry) = match exchange {
            Exchange::Answered { command, telemetry, at_stamp } => {
                let late_s = command.t_sent_us.saturating_sub(t_us) as f64 * 1e-6;
                let at = if at_stamp { late_s } else { late_s.max(self.delta) };
                ((at < ts).then_some(at), Some(command), Some(telemetry))
            }
            Exchange::Dropped { command, telemetry } => (None, Some(command), Some(telemetry)),
            Exchange::NoAnswer => (None, None, None),
        };
        let applied = self.applied;
        let u_new = match (switch, command) {
            (Some(_), Some(c)) => wire.actuator_torque(&c),
            _ => applied,
        };
        let fw_status = command.map_or(0, |c| c.status);
        if let Some(t) = telemetry {
            self.z_t_ref = t.z_t_ref as f64;
        }
        let sample = Sample { t: t_k, x, tip: z, mode, f: self.f_now };
        let record = PeriodRecord {
            u1_cmd: u_new[0],
            u2_cmd: u_new[1],
            u1_applied: applied[0],
            u2_applied: applied[1],
            lift_off_detected: fw_status & status::LIFT_OFF != 0,
            deadline_miss: switch.is_none(),
            firmware_deadline_miss: fw_status & status::DEADLINE_MISS != 0,
            overruns: command.map_or(0, |c| c.overruns),
            status: fw_status,
            ..PeriodRecord::of_sample(&sample, self.z_t_ref)
        };
        // The first part run ahead is the period's when the switch is at `t_k + delta`.
        let (first_part, before) = match ahead {
            Some((before, part)) if switch.is_some_and(|at| at.to_bits() == self.delta.to_bits()) => (Some(part), Some(before)),
            Some((before, _)) => {
                plant.restore(before);
                (None, None)
            }
            None => (None, None),
        };
        if let Some(reason) = firmware::SafeReason::from_status(fw_status) {
            // The plant stays at `t_k`, as without overlap.
            if let Some(before) = before {
                plant.restore(before);
            }
            return Err(Box::new(PeriodFailure { record: Some(record), error: RunError::SafeState { k, t: t_k, reason } }));
        }
        // Zero-order hold: the previous command until the switch, then the new one.
        let t_next = (k + 1) as f64 * ts;
        // Already at t_k + delta (the look-ahead) or, with overlap, past the first part.
        let past_first = self.ahead.take().is_some();
        let first = match (switch, first_part) {
            (_, Some(part)) => part,
            // The switch later than delta (a late command): the old command up to it.
            (Some(at), None) if !past_first || at.to_bits() != self.delta.to_bits() => {
                plant.advance_events(&Hold(applied), k as f64 * ts + at - plant.time(), obs)
            }
            _ => Ok(Vec::new()),
        };
        let held = if switch.is_some() { u_new } else { applied };
        let step = first.and_then(|events| {
            run.on_events(&events);
            self.hold_to_next_switch(plant, held, t_next, obs)
        });
        match step {
            Ok((events, f)) => {
                run.on_events(&events);
                self.f_now = f;
            }
            Err(e) => return Err(Box::new(PeriodFailure { record: Some(record), error: e.into() })),
        }
        self.applied = u_new;
        self.k += 1;
        Ok(record)
    }

    /// Holds `u` from the plant's time to the next period's zero-order-hold switch
    /// `t_next + delta` in one solve, reading the sample at `t_next` on the way from
    /// the dense output (the look-ahead: one step per period from switch to switch,
    /// issue 43; docs/architecture.md "The accuracy contract"), or, without a delay
    /// (`delta = 0` or a whole period) or on a real-time link (a command takes
    /// effect at its send stamp, which may come before `delta`), to `t_next`.
    /// Where no accepted step covers
    /// `t_next` (a Moreau–Jean bridge there), the plant goes back and advances in
    /// two parts, `t_next` then the switch. Returns the events and the contact force
    /// at `t_next` (N).
    fn hold_to_next_switch(
        &mut self,
        plant: &mut Plant,
        u: [f64; 2],
        t_next: f64,
        obs: &mut dyn Observer,
    ) -> Result<(Vec<PlantEvent>, [f64; 2]), plant::SimError> {
        if !(self.delta > 0.0 && self.delta < self.period.as_secs_f64()) || self.stamped {
            let r = plant.advance(&Hold(u), t_next - plant.time(), obs)?;
            return Ok((r.events, r.f));
        }
        let before = plant.checkpoint();
        let switch = t_next + self.delta;
        // A late switch within rounding of t_next leaves no interval before the
        // sample, and a delay below the clock's resolution at t_next (`delta_s =
        // 1e-20`: `t_next + delta == t_next`) none after it: the two parts then
        // (the second of length zero: the delay acts as none). Issue 52, 8: the
        // sample then fell outside the solve and the run failed with a false "time
        // step must be finite".
        if t_next > plant.time() && switch > t_next {
            let (events, sample) = plant.advance_sampled(&Hold(u), switch - plant.time(), t_next, obs)?;
            if let Some(sample) = sample {
                self.ahead = Some(sample);
                return Ok((events, sample.f));
            }
            plant.restore(before);
        }
        let r = plant.advance(&Hold(u), (t_next - plant.time()).max(0.0), obs)?;
        let sample = Sample { t: t_next, x: plant.state(), tip: [plant.tip()[0], plant.tip()[1]], mode: plant.mode(), f: r.f };
        let mut events = r.events;
        events.extend(plant.advance_events(&Hold(u), switch - plant.time(), obs)?);
        self.ahead = Some(sample);
        Ok((events, sample.f))
    }
}

/// Sees a closed-loop run as it goes; every method defaults to doing nothing
/// (and going on). `()` is the quiet run.
pub trait RunObserver {
    /// A frame as it goes on the wire (a recording of what crossed it).
    fn on_frame(&mut self, _frame: &SensorFrame) {}

    /// The firmware's answer to `frame` as the period loop got it (after the
    /// `drop_command` fault's wrapper: a lost command is [`Exchange::Dropped`]):
    /// with the frame and the ground truth of the same instant, what a replay
    /// needs ([`crate::frames::FrameRow`]).
    fn on_answer(&mut self, _frame: &SensorFrame, _truth: &GroundTruth, _exchange: &Exchange) {}

    /// Plant events at their exact times (the start-up events, then those of each
    /// interval): lift-offs between two samples included, which the records cannot show.
    fn on_events(&mut self, _events: &[PlantEvent]) {}

    /// A period's record as soon as it is made (before the run can stop on it), so
    /// a caller can stream the trace to disk and lose nothing if killed.
    fn on_record(&mut self, _record: &PeriodRecord) {}

    /// After period `k` of `n` (progress); `false` stops the run with
    /// [`RunError::Interrupted`] (Ctrl-C).
    fn on_period(&mut self, _k: usize, _n: usize) -> bool {
        true
    }

    /// At the end of the run (also after a failure): the plant's validity counters
    /// (energy-creating impacts, fallbacks, cone violations, Zeno stops, integrator
    /// failures; [`Validity`]).
    fn on_finished(&mut self, _validity: &Validity) {}

    /// At the end of the run, just before [`RunObserver::on_finished`]: the plant's
    /// energy ledger ([`plant::Ledger`], docs/plant.md "The energy ledger").
    fn on_ledger(&mut self, _ledger: &plant::Ledger) {}

    /// At the end of the run, just before [`RunObserver::on_ledger`]: the plant's
    /// event counts since `t = 0` ([`plant::Counters`]; every departure from the
    /// belt, the outputs' `lift_offs`, is its `lift_offs` plus its `bounces`:
    /// docs/plant.md "Counting lift-offs").
    fn on_counters(&mut self, _counters: &plant::Counters) {}
}

impl RunObserver for () {}

/// Runs the scenario over `link` (the one closed-loop loop: in-process,
/// iceoryx2 and PIL runs, sweeps and `Z_t,sliding` trials all go through it),
/// telling `run` what happens, and keeps nothing itself: memory stays flat
/// in the run's length (`run` streams or summarises each record as
/// [`RunObserver::on_record`] hands it over; `sil-host run` and `pil`).
///
/// Returns the number of periods recorded and, when the run stopped early
/// (plant failure, the firmware lost or in its safe state, `on_period` said
/// stop), why; the last period's record is handed to `run` before the error
/// when it was made.
pub fn stream_loop(setup: &RunSetup, link: &mut dyn FirmwareLink, run: &mut dyn RunObserver) -> (usize, Option<RunError>) {
    let mut plant = setup.plant().clone();
    run.on_events(plant.startup_events());
    // No trajectory observer here: the period's first part may overlap the firmware's step.
    let mut periods = PeriodLoop::new(setup, &plant).overlapping(true);
    let n = periods.periods_in(setup.scenario().timing.duration_s);
    let mut recorded = 0;
    let mut failure = None;
    for k in 0..n {
        match periods.period(&mut plant, link, run, &mut NoObserver) {
            Ok(r) => {
                run.on_record(&r);
                recorded += 1;
            }
            Err(f) => {
                if let Some(r) = &f.record {
                    run.on_record(r);
                    recorded += 1;
                }
                failure = Some(f.error);
                break;
            }
        }
        if !run.on_period(k + 1, n) && k + 1 < n {
            failure = Some(RunError::Interrupted { k: k + 1 });
            break;
        }
    }
    link.finish(recorded as u32);
    let sim_error = match &failure {
        Some(RunError::Sim(e)) => Some(e),
        _ => None,
    };
    run.on_counters(plant.counters());
    run.on_ledger(&plant.ledger());
    run.on_finished(&plant.validity(sim_error));
    (recorded, failure)
}

/// [`stream_loop`] keeping every period's record, for short runs whose caller
/// needs them (tests, sweeps, `Z_t,sliding` trials): memory grows with the run
/// (about 150 bytes per period).
///
/// Returns every period's record; when the run stops early (plant failure, the
/// firmware lost or in its safe state, `on_period` said stop) the records up to
/// and including the last period come back with the error.
pub fn run_loop(setup: &RunSetup, link: &mut dyn FirmwareLink, run: &mut dyn RunObserver) -> (Vec<PeriodRecord>, Option<RunError>) {
    /// Forwards everything to `inner` and keeps the records.
    struct Keep<'a> {
        inner: &'a mut dyn RunObserver,
        records: Vec<PeriodRecord>,
    }
    impl RunObserver for Keep<'_> {
        fn on_frame(&mut self, frame: &SensorFrame) {
            self.inner.on_frame(frame);
        }

        fn on_answer(&mut self, frame: &SensorFrame, truth: &GroundTruth, exchange: &Exchange) {
            self.inner.on_answer(frame, truth, exchange);
        }

        fn on_events(&mut self, events: &[PlantEvent]) {
            self.inner.on_events(events);
        }

        fn on_record(&mut self, record: &PeriodRecord) {
            self.inner.on_record(record);
            self.records.push(*record);
        }

        fn on_period(&mut self, k: usize, n: usize) -> bool {
            self.inner.on_period(k, n)
        }

        fn on_finished(&mut self, validity: &Validity) {
            self.inner.on_finished(validity);
        }

        fn on_ledger(&mut self, ledger: &plant::Ledger) {
            self.inner.on_ledger(ledger);
        }

        fn on_counters(&mut self, counters: &plant::Counters) {
            self.inner.on_counters(counters);
        }
    }
    // One allocation up front (capped: a scenario that is not validated may ask for anything).
    let capacity = usize::try_from(setup.scenario().timing.periods()).unwrap_or(0).min(1 << 20);
    let mut keep = Keep { inner: run, records: Vec::with_capacity(capacity) };
    let (_, failure) = stream_loop(setup, link, &mut keep);
    (keep.records, failure)
}
