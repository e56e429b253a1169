//! Each period's exchange over the link ([`FirmwareLink`] for [`IpcLink`]): the
//! frame published and the command awaited, in lockstep or paced by the wall
//! clock, the timings measured, and the injected faults that may leave a period
//! without its answer.

use std::time::{Duration, Instant};

use shared::wire::{FirmwareTelemetry, GroundTruth, SensorFrame, frame_flags};

use super::{IpcLink, process::process_state};
use crate::{
    handshake::Announced,
    link::{Exchange, FirmwareLink},
    record::RunError,
};

impl IpcLink {
    /// Lockstep: whether an injected fault may leave period `k` without its
    /// answer (then the plant waits `rig.command_timeout_s` and counts a miss).
    /// Notes a stall that starts at `k`: its periods stay faulted until the
    /// firmware answers again.
    fn fault_may_miss(&mut self, k: u64) -> bool {
        if self.faults.stall_starting(k).is_some() {
            self.in_stall = true;
        }
        self.in_stall || self.faults.drops_command(k) || self.faults.command_delay(k).as_us() > 0 || self.faults.kills_firmware_at(k)
    }

    /// Lockstep outside injected faults: waits for the command echoing `seq`
    /// whatever the host's load; `Err` when the firmware is gone or made no
    /// progress for `rig.stall_limit_s`.
    fn wait_for_answer(&mut self, seq: u32, t: f64) -> Result<Option<shared::wire::ActuatorCommand>, RunError> {
        let transport = |e: crate::ipc::IpcError| RunError::Transport(e.to_string());
        let start = Instant::now();
        loop {
            let chunk = Instant::now() + Duration::from_millis(20);
            match self.ports.commands.next_before(chunk).map_err(transport)? {
                Some(c) if c.seq == seq => return Ok(Some(c)),
                Some(_) => self.timings.late_answers += 1,
                None => {
                    let k = seq as usize;
                    if let Some(what) = self.firmware_gone() {
                        return Err(RunError::FirmwareLost { k, t, what: format!("the firmware process {what}") });
                    }
                    let waited = start.elapsed();
                    if waited >= self.stall_limit {
                        let stopped = self.firmware_pid().and_then(process_state).is_some_and(|c| c == 'T' || c == 't');
                        return Err(RunError::FirmwareLost {
                            k,
                            t,
                            what: format!(
                                "the firmware made no progress for {:.1} s (rig.stall_limit_s){}",
                                waited.as_secs_f64(),
                                if stopped { ": its process is stopped (SIGSTOP or a debugger); resume it with SIGCONT" } else { "" }
                            ),
                        });
                    }
                }
            }
        }
    }

    /// Publishes `truth` (to monitors) and `frame` (to the firmware); returns when the frame went out.
    fn publish(&self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Instant, RunError> {
        let transport = |e: crate::ipc::IpcError| RunError::Transport(e.to_string());
        self.ports.publish_truth(*truth).map_err(transport)?;
        let published = Instant::now();
        self.ports.frames.send(*frame).map_err(transport)?;
        Ok(published)
    }

    fn telemetry_for(&self, seq: u32) -> Result<FirmwareTelemetry, RunError> {
        // Published just before the command: it is there, behind older ones.
        while let Some(t) = self.ports.telemetry.try_next().map_err(|e| RunError::Transport(e.to_string()))? {
            if t.seq == seq {
                return Ok(t);
            }
        }
        Ok(FirmwareTelemetry { seq, z_t_ref: f32::NAN, ..FirmwareTelemetry::default() })
    }
}

impl FirmwareLink for IpcLink {
    fn transport(&self) -> &'static str {
        "iceoryx2"
    }

    fn switches_at_stamp(&self) -> bool {
        self.realtime
    }

    fn announcement(&self) -> Option<&Announced> {
        self.announced.as_ref()
    }

    fn before_period(&mut self, k: u64) {
        self.k = k;
        if self.faults.kills_firmware_at(k)
            && let Some(sp) = &mut self.spawned
        {
            let _ = sp.child.kill();
        }
    }

    /// Lockstep only: publishes the frame now; [`FirmwareLink::exchange`] then
    /// waits for its answer (its round trip then runs to when the plant takes the
    /// command, after the plant's own work in between).
    fn send_ahead(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<bool, RunError> {
        if self.realtime {
            return Ok(false);
        }
        let published = self.publish(frame, truth)?;
        self.sent_ahead = Some((frame.seq, published));
        Ok(true)
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let transport = |e: crate::ipc::IpcError| RunError::Transport(e.to_string());
        let patient = !self.realtime && !self.fault_may_miss(u64::from(frame.seq));
        let deadline = if self.realtime {
            let t0 = *self.t0.get_or_insert_with(Instant::now);
            let ideal = t0 + Duration::from_micros(frame.sampled_at().as_us());
            sleep_until(ideal, self.spin);
            None
        } else {
            Some(Instant::now() + self.timeout)
        };
        let published = match self.sent_ahead.take() {
            Some((seq, published)) if seq == frame.seq => published,
            _ => self.publish(frame, truth)?,
        };
        if patient && let Some(c) = self.wait_for_answer(frame.seq, truth.t)? {
            self.consecutive_timeouts = 0;
            self.timings.rtt.record(published.elapsed());
            self.timings.step.record_ns(u64::from(c.step_ticks));
            let telemetry = self.telemetry_for(c.seq)?;
            return Ok(Exchange::Answered { command: c, telemetry, at_stamp: false });
        }
        // Real time: the sample instant is the frame's publication (the hardware's
        // timer tick); the plant's own lateness against `t0 + t_k` is period jitter,
        // not the firmware's deadline. The plant stops waiting at the next sample
        // instant `t0 + t_{k+1}`, so a firmware that does not answer never puts it
        // behind the wall clock (one period per missed period at most); if the
        // plant itself published late, the firmware still gets half a period.
        let deadline = deadline.unwrap_or_else(|| {
            let ideal = self.t0.map_or(published, |t0| t0 + Duration::from_micros(frame.sampled_at().as_us()));
            self.timings.jitter.record(published.saturating_duration_since(ideal));
            let ts = Duration::from_micros(self.period.as_us());
            (ideal + ts).max(published + ts / 2)
        });
        loop {
            match self.ports.commands.next_before(deadline).map_err(transport)? {
                Some(c) if c.seq == frame.seq => {
                    let now = Instant::now();
                    self.consecutive_timeouts = 0;
                    self.in_stall = false;
                    self.timings.rtt.record(now - published);
                    self.timings.step.record_ns(u64::from(c.step_ticks));
                    let telemetry = self.telemetry_for(c.seq)?;
                    // Real time: the command's own send stamp (the firmware's clock,
                    // anchored at the frame's arrival) dates it; the plant's own view
                    // (`now`) is late by however long the plant itself was descheduled.
                    return Ok(Exchange::Answered { command: c, telemetry, at_stamp: self.realtime });
                }
                Some(_) => self.timings.late_answers += 1,
                None => break,
            }
        }
        // Nothing this period: a deadline miss, unless the firmware is gone.
        let k = frame.seq as usize;
        if let Some(what) = self.firmware_gone_checked() {
            return Err(RunError::FirmwareLost { k, t: truth.t, what: format!("the firmware process {what}") });
        }
        self.consecutive_timeouts += 1;
        // In both timings: a firmware that does not answer for this many periods in
        // a row is given up (exit 1, the trace kept), stalled or not.
        if self.consecutive_timeouts >= self.max_timeouts {
            let each = if self.realtime {
                format!("one period of {} s of wall time each", self.period.as_secs_f64())
            } else {
                format!("{} s of wall time each", self.timeout.as_secs_f64())
            };
            return Err(RunError::FirmwareLost {
                k,
                t: truth.t,
                what: format!(
                    "no command for {} periods in a row ({each}; rig.max_consecutive_timeouts): the firmware process is stalled",
                    self.consecutive_timeouts
                ),
            });
        }
        Ok(Exchange::NoAnswer)
    }

    fn finish(&mut self, last_seq: u32) {
        let end = SensorFrame { seq: last_seq, flags: frame_flags::END_OF_RUN, ..SensorFrame::default() };
        let _ = self.ports.frames.send(end);
        if let Some(sp) = &mut self.spawned {
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(2) {
                if let Ok(Some(_)) = sp.child.try_wait() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(2));
            }
            let _ = sp.child.kill();
            let _ = sp.child.wait();
        }
    }
}

/// Waits until `when`: the OS sleep to `spin` before, then a spin that yields the
/// core (sleep alone overshoots by the wake-up latency).
fn sleep_until(when: Instant, spin: Duration) {
    let now = Instant::now();
    if when > now + spin {
        std::thread::sleep(when - now - spin);
    }
    while Instant::now() < when {
        std::thread::yield_now();
    }
}
