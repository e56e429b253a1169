//! The way from the plant's period loop to the firmware: the [`FirmwareLink`]
//! trait every transport implements (in-process, the board twin, iceoryx2 to the
//! firmware process, PIL to the MCU image), the [`Exchange`] that answers one
//! frame, and the `drop_command` fault as a wrapper around any link
//! ([`DropCommands`]). The loop that drives a link is [`crate::period_loop`].

use shared::wire::{self, ActuatorCommand, FirmwareTelemetry, GroundTruth, SensorFrame};

use super::{faults::FaultPlan, record::RunError};

/// The answer to one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exchange {
    /// The firmware answered this period.
    Answered {
        /// Its command (echoing the frame's `seq`).
        command: ActuatorCommand,
        /// Its telemetry of the same step.
        telemetry: FirmwareTelemetry,
        /// Real-time runs: the command takes effect at its send stamp
        /// (`t_sent_us`, the firmware's wall clock anchored at the frame's arrival);
        /// lockstep: at that stamp but never before `delta` after `t_k`.
        at_stamp: bool,
    },
    /// No command for this period arrived before the link stopped waiting (the
    /// wall-clock deadline in real time, the command timeout in lockstep).
    NoAnswer,
    /// The firmware answered but the wire lost the command (the `drop_command`
    /// fault, [`DropCommands`]): it is recorded, not applied.
    Dropped {
        /// The command that was lost.
        command: ActuatorCommand,
        /// Its telemetry.
        telemetry: FirmwareTelemetry,
    },
}

/// The `drop_command` faults of a plan wrapped around any link (the way
/// smoltcp's `FaultInjector` wraps a device): in their windows an answer is lost
/// on the wire, so the plant holds the previous command (a deadline miss).
pub struct DropCommands<'a, L: ?Sized> {
    /// The link.
    pub inner: &'a mut L,
    /// The faults (only `drop_command` acts here).
    pub plan: &'a FaultPlan,
}

impl<L: FirmwareLink + ?Sized> FirmwareLink for DropCommands<'_, L> {
    fn transport(&self) -> &'static str {
        self.inner.transport()
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        Ok(match self.inner.exchange(frame, truth)? {
            Exchange::Answered { command, telemetry, .. } if self.plan.drops_command(u64::from(frame.seq)) => {
                Exchange::Dropped { command, telemetry }
            }
            other => other,
        })
    }

    fn send_ahead(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<bool, RunError> {
        self.inner.send_ahead(frame, truth)
    }

    fn before_period(&mut self, k: u64) {
        self.inner.before_period(k);
    }

    fn announcement(&self) -> Option<&crate::handshake::Announced> {
        self.inner.announcement()
    }

    fn finish(&mut self, last_seq: u32) {
        self.inner.finish(last_seq);
    }

    fn actuator_torque(&self, command: &ActuatorCommand) -> [f64; 2] {
        self.inner.actuator_torque(command)
    }

    fn switches_at_stamp(&self) -> bool {
        self.inner.switches_at_stamp()
    }
}

/// A way to reach the firmware: in-process, or over iceoryx2 in another process.
pub trait FirmwareLink {
    /// `in-process` or `iceoryx2`.
    fn transport(&self) -> &'static str;

    /// Sends frame `k` (and the ground truth of the same instant, for monitors)
    /// and waits for the command that answers it.
    ///
    /// # Errors
    /// [`RunError`] when the firmware is gone (its process died, or it stopped
    /// answering for `rig.max_consecutive_timeouts` periods) or the transport failed.
    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError>;

    /// Sends frame `k` (and its ground truth) ahead of [`FirmwareLink::exchange`],
    /// which then only waits for the answer, so that the plant can work while the
    /// firmware computes (lockstep over another process). `Ok(false)`: this link
    /// does not (the default), and `exchange` sends.
    ///
    /// # Errors
    /// As [`FirmwareLink::exchange`].
    fn send_ahead(&mut self, _frame: &SensorFrame, _truth: &GroundTruth) -> Result<bool, RunError> {
        Ok(false)
    }

    /// Called once before the exchange of period `k` (its index: sample time
    /// `k Ts`), for fault injection that acts on the firmware process itself, such
    /// as killing it ([`FaultPlan::kills_firmware_at`]).
    fn before_period(&mut self, _k: u64) {}

    /// Tells the firmware the run is over (no answer expected).
    fn finish(&mut self, _last_seq: u32) {}

    /// The joint torques `[u1, u2]` (N m) that `command`, just answered, makes
    /// at the joints: by default its codes decoded (`wire::decode_torque`: the
    /// wire's 5/2048 N m per code); the board twin's motor stage instead
    /// (duty quantisation, full scales, wiring, enable and fault line).
    fn actuator_torque(&self, command: &ActuatorCommand) -> [f64; 2] {
        [wire::decode_torque(command.u1_code) as f64, wire::decode_torque(command.u2_code) as f64]
    }

    /// Whether a command takes effect at its send stamp, which may come before
    /// `t_k + delta` (a real-time link: [`Exchange::Answered`]'s `at_stamp`), rather
    /// than at `max(t_k + delta, t_sent)`. The period loop then cannot step past
    /// `t_k + delta` ahead of the answer ([`crate::PeriodLoop`]'s look-ahead is off).
    fn switches_at_stamp(&self) -> bool {
        false
    }

    /// The firmware's own announcement of its configuration, checked against the
    /// scenario before period 0 (the handshake, [`crate::handshake`]); `None` for a
    /// link without one (the PIL image, which checks its protocol version instead).
    fn announcement(&self) -> Option<&crate::handshake::Announced> {
        None
    }
}
