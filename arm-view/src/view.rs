//! The views of the CLI's tables ([`tables::mcap::McapView`]): the frames and
//! the scene of a trace's rows (`run`, `pil`: [`rig::record::PeriodRecord`];
//! `simulate`: [`TraceRow`]) every [`VIEW_PERIOD_S`] of simulated time, the
//! log of a closed-loop run's periods and of an open-loop run's events.

use std::collections::VecDeque;

use foxglove::{
    Encode,
    messages::{FrameTransforms, Log, SceneUpdate},
};
use tables::mcap::{ChannelSpec, McapView};

use crate::{
    geometry::{ArmGeometry, frame_transforms},
    log::{RunLog, event_line},
    scene::{Instant, scene_update},
};
use experiments::simulate::summary::{EventRow, TraceRow};
use rig::record::PeriodRecord;

/// The frames' and the scene's period, s of simulated time (100 frames per
/// simulated second): a row is drawn when its time reaches the next multiple.
pub const VIEW_PERIOD_S: f64 = 0.01;

/// The tip's path in the scene: this many frames, the last 0.25 s.
pub const PATH_FRAMES: usize = 25;

/// The topic of the frames (`foxglove.FrameTransforms`).
pub const TF_TOPIC: &str = "/tf";
/// The topic of the 3D scene (`foxglove.SceneUpdate`).
pub const SCENE_TOPIC: &str = "/scene";
/// The topic of the log (`foxglove.Log`).
pub const LOG_TOPIC: &str = "/log";

/// The channel of Foxglove messages `M` on `topic`: the SDK's schema
/// (`foxglove.<M>`, a protobuf `FileDescriptorSet`) and encoding (`protobuf`).
pub fn channel<M: Encode>(topic: &str) -> ChannelSpec {
    let (schema_name, schema_encoding, schema) = match M::get_schema() {
        Some(s) => (s.name, s.encoding, s.data.into_owned()),
        None => (String::new(), String::new(), Vec::new()),
    };
    ChannelSpec { topic: topic.into(), schema_name, schema_encoding, schema, message_encoding: M::get_message_encoding() }
}

/// Encodes `m` into `buf` (cleared first). The SDK's protobuf encoding into a
/// growing vector does not fail; were it to, the message is left empty.
fn encode<'b, M: Encode>(m: &M, buf: &'b mut Vec<u8>) -> &'b [u8] {
    buf.clear();
    if m.encode(buf).is_err() {
        buf.clear();
    }
    buf
}

/// The arm drawn from a trace: frames and scene every [`VIEW_PERIOD_S`], the
/// tip's recent path. One per table.
#[derive(Debug, Clone)]
pub struct ArmView {
    geometry: ArmGeometry,
    /// Time of the next frame, s.
    next: f64,
    path: VecDeque<[f64; 2]>,
    log: RunLog,
    buf: Vec<u8>,
}

impl ArmView {
    /// The view of the arm `geometry`; the first row is drawn.
    pub fn new(geometry: ArmGeometry) -> Self {
        Self {
            geometry,
            next: f64::NEG_INFINITY,
            path: VecDeque::with_capacity(PATH_FRAMES),
            log: RunLog::default(),
            buf: Vec::with_capacity(4096),
        }
    }

    /// As [`ArmView::new`], for a closed-loop run of the control law `law` (in
    /// words, `rig::scenario::Scenario::law_in_words`), which the `/log` names at its first period.
    pub fn of_law(geometry: ArmGeometry, law: String) -> Self {
        Self { log: RunLog::of_law(law), ..Self::new(geometry) }
    }

    /// Whether a row at `t` (s) is drawn: the first, then the first at or past
    /// each multiple of [`VIEW_PERIOD_S`] (within 1 ns, so rows on a 1 ms grid
    /// are drawn every tenth).
    fn due(&mut self, t: f64) -> bool {
        // NaN times are never drawn.
        if t.is_nan() || t < self.next - 1e-9 {
            return false;
        }
        self.next = ((t + 1e-9) / VIEW_PERIOD_S).floor() * VIEW_PERIOD_S + VIEW_PERIOD_S;
        true
    }

    /// The frames (channel 0) and the scene (channel 1) of a drawn row.
    fn draw(&mut self, t: f64, q: [f64; 2], force: [f64; 2], mode: &str, emit: &mut dyn FnMut(usize, &[u8])) {
        let tip = self.geometry.tip(q[0], q[1]);
        if self.path.len() == PATH_FRAMES {
            self.path.pop_front();
        }
        self.path.push_back(tip);
        emit(0, encode(&frame_transforms(&self.geometry, t, q[0], q[1]), &mut self.buf));
        let path: Vec<[f64; 2]> = self.path.iter().copied().collect();
        let scene = scene_update(&self.geometry, &Instant { t, tip, force, mode, path: &path });
        emit(1, encode(&scene, &mut self.buf));
    }
}

/// `run`, `pil`: `/tf`, `/scene` and `/log` (the periods' log, every period).
impl McapView<PeriodRecord> for ArmView {
    fn channels(&self) -> Vec<ChannelSpec> {
        vec![channel::<FrameTransforms>(TF_TOPIC), channel::<SceneUpdate>(SCENE_TOPIC), channel::<Log>(LOG_TOPIC)]
    }

    fn messages(&mut self, r: &PeriodRecord, emit: &mut dyn FnMut(usize, &[u8])) {
        if self.due(r.t) {
            self.draw(r.t, [r.theta1, r.theta2], [r.f_t, r.f_n], r.mode, emit);
        }
        for line in self.log.lines(r) {
            emit(2, encode(&line, &mut self.buf));
        }
    }

    /// `painleve.run`, `law`: the control law that ran, in words (when known,
    /// [`ArmView::of_law`]); Foxglove's metadata panel shows it.
    fn metadata(&self) -> Vec<(String, std::collections::BTreeMap<String, String>)> {
        self.log
            .law()
            .map(|law| ("painleve.run".to_string(), std::collections::BTreeMap::from([("law".to_string(), law.to_string())])))
            .into_iter()
            .collect()
    }
}

/// `simulate`'s samples: `/tf` and `/scene`.
impl McapView<TraceRow> for ArmView {
    fn channels(&self) -> Vec<ChannelSpec> {
        vec![channel::<FrameTransforms>(TF_TOPIC), channel::<SceneUpdate>(SCENE_TOPIC)]
    }

    fn messages(&mut self, r: &TraceRow, emit: &mut dyn FnMut(usize, &[u8])) {
        if self.due(r.t) {
            self.draw(r.t, [r.theta1, r.theta2], [r.f_t, r.f_n], r.mode, emit);
        }
    }
}

/// The log of `simulate`'s events: `/log`, a line per event.
#[derive(Debug, Clone, Default)]
pub struct EventLog {
    buf: Vec<u8>,
}

impl McapView<EventRow> for EventLog {
    fn channels(&self) -> Vec<ChannelSpec> {
        vec![channel::<Log>(LOG_TOPIC)]
    }

    fn messages(&mut self, e: &EventRow, emit: &mut dyn FnMut(usize, &[u8])) {
        emit(0, encode(&event_line(e), &mut self.buf));
    }
}
