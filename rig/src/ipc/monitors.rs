//! What the plant does for monitors, the subscribers of `ground_truth`: whether
//! it waits for them ([`MonitorPolicy`]), what they cost the run
//! ([`MonitorCounts`]), and the lossless publisher that gives up a monitor that
//! takes nothing for too long.

use std::{
    sync::{Arc, Mutex, PoisonError},
    time::Duration,
};

use iceoryx2::{
    port::{BackpressureAction, BackpressureInfo, publisher::Publisher},
    prelude::*,
};
use shared::wire::GroundTruth;

use super::{
    error::{IpcError, err},
    mailbox::PubSub,
};

/// What the plant does for monitors, the subscribers of `ground_truth`
/// (`sil-host run --monitors N`; docs/rig.md, "Monitors").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MonitorPolicy {
    /// Monitors to wait for before period 0 (up to `rig.connect_timeout_s`).
    pub wait_for: usize,
    /// Lockstep: a sample that finds a monitor's buffer full waits for room
    /// instead of being discarded for that monitor, so a monitor receives every
    /// sample; the run goes at the pace of the slowest monitor.
    pub lossless: bool,
    /// How long one sample waits for a full monitor before that monitor is given
    /// up (never waited for again: it then loses what finds its buffer full).
    pub timeout: Duration,
}

impl Default for MonitorPolicy {
    /// No monitor waited for, none ever waits the plant, 2 s.
    fn default() -> Self {
        Self { wait_for: 0, lossless: false, timeout: Duration::from_secs(2) }
    }
}

/// What monitors cost the run so far.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MonitorCounts {
    /// Monitors given up ([`MonitorPolicy::lossless`] only): a sample waited
    /// [`MonitorPolicy::timeout`] for room in their buffer (dead, stopped, or too
    /// slow), or found the buffer of a monitor not yet connected to the plant's
    /// publisher full (see [`PlantPorts::publish_truth`](super::PlantPorts::publish_truth)).
    pub given_up: u32,
    /// Samples a subscribed monitor did not receive (one per monitor per
    /// sample): discarded for a given-up monitor, or (real time) for a monitor
    /// whose buffer was full. Exact when `ground_truth` has no safe overflow, as
    /// the rig creates it; with safe overflow (a service a monitor created with
    /// iceoryx2's defaults) the oldest queued sample is replaced unseen, which no
    /// count can know.
    pub samples_dropped: u64,
}

#[derive(Debug, Default)]
pub(super) struct MonitorState {
    pub(super) given_up_ports: Vec<u128>,
    /// The most subscribers found unreached by one sample so far: monitors that
    /// subscribed before the plant's publisher existed and have not received since.
    pub(super) unreached_max: usize,
    pub(super) counts: MonitorCounts,
}

/// The `ground_truth` publisher of a lossless run: iceoryx2 retries a full
/// subscriber (yielding, then sleeping) and asks this handler each time whether
/// to go on; past the timeout the monitor is given up, and from then on a sample
/// that finds its buffer full is discarded for it at once.
pub(super) fn lossless_publisher(
    service: &PubSub<GroundTruth>,
    full_name: String,
    timeout: Duration,
    state: Arc<Mutex<MonitorState>>,
) -> Result<Publisher<ipc::Service, GroundTruth, ()>, IpcError> {
    service
        .publisher_builder()
        .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
        .set_backpressure_handler(move |info: &BackpressureInfo| {
            let mut st = state.lock().unwrap_or_else(PoisonError::into_inner);
            if st.given_up_ports.contains(&info.receiver_port_id) {
                st.counts.samples_dropped += 1;
                return BackpressureAction::DiscardData;
            }
            if info.elapsed_time < timeout {
                return BackpressureAction::Retry;
            }
            st.given_up_ports.push(info.receiver_port_id);
            st.counts.given_up += 1;
            st.counts.samples_dropped += 1;
            eprintln!(
                "rig: a monitor of {full_name} took no sample for {} s with its buffer full (dead, stopped or too slow): \
                 it is no longer waited for, and loses the samples that find its buffer full",
                timeout.as_secs_f64()
            );
            BackpressureAction::DiscardData
        })
        .create()
        .map_err(|e| err("publisher ground_truth", e))
}
