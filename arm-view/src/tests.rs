//! The view's frames against the plant's kinematics, its messages against
//! Foxglove's published schemas, the layout against the channels.

use foxglove::{
    Encode,
    messages::{FrameTransforms, Log, SceneUpdate},
};
use proptest::prelude::*;
use prost::Message as _;
use tables::mcap::McapView;

use crate::{geometry::*, validate::Schema, view::*};

/// The origin of `frame` in `world`, which every test's chain has.
fn origin(tf: &FrameTransforms, frame: &str) -> [f64; 3] {
    origin_in_world(tf, frame).expect("a chain to world")
}

const PAPER: ArmGeometry = ArmGeometry { l: 0.21, h: 0.3775, v_belt: -0.4 };

proptest! {
    /// The transforms composed put the tip where the plant's kinematics do
    /// (docs/model.md: `z_t = l (sin theta1 + sin theta2)`, `z_n = -l (cos theta1
    /// + cos theta2)`), the elbow `l` from the base, in the plane `y = 0`.
    #[test]
    fn the_frames_put_the_tip_where_the_kinematics_do(theta1 in -3.2..3.2f64, theta2 in -3.2..3.2f64, l in 0.05..1.0f64) {
        let g = ArmGeometry { l, ..PAPER };
        let tf = frame_transforms(&g, 0.5, theta1, theta2);
        let tip = origin(&tf, "tip");
        let want = g.tip(theta1, theta2);
        prop_assert!((tip[0] - want[0]).abs() < 1e-12 && tip[1].abs() < 1e-15 && (tip[2] - want[1]).abs() < 1e-12, "{tip:?} against {want:?}");
        let elbow = origin(&tf, "link2");
        prop_assert!(((elbow[0].powi(2) + elbow[2].powi(2)).sqrt() - l).abs() < 1e-12);
        prop_assert!((elbow[0] - l * theta1.sin()).abs() < 1e-12);
    }
}

fn record(t: f64, theta1: f64, theta2: f64, mode: &'static str) -> rig::record::PeriodRecord {
    let [z_t, z_n] = PAPER.tip(theta1, theta2);
    rig::record::PeriodRecord {
        t,
        theta1,
        theta1_dot: 0.0,
        theta2,
        theta2_dot: 0.0,
        z_t,
        z_n,
        z_t_ref: 0.1,
        f_t: -6.0,
        f_n: 10.0,
        mode,
        u1_cmd: 0.1,
        u2_cmd: -0.2,
        u1_applied: 0.1,
        u2_applied: -0.2,
        lift_off_true: mode == "flight",
        lift_off_detected: mode == "flight",
        deadline_miss: false,
        firmware_deadline_miss: false,
        overruns: 0,
        status: 0,
    }
}

/// Every message of a run's view checks against the schema its channel
/// carries (the SDK's published descriptors), and decodes to what was drawn:
/// a frame every 10 ms of 1 ms rows, a log line per change.
#[test]
fn a_runs_view_messages_check_against_foxglove_schemas() {
    let mut view = ArmView::new(PAPER);
    let channels = McapView::<rig::record::PeriodRecord>::channels(&view);
    let names: Vec<&str> = channels.iter().map(|c| c.schema_name.as_str()).collect();
    assert_eq!(names, ["foxglove.FrameTransforms", "foxglove.SceneUpdate", "foxglove.Log"]);
    let schemas: Vec<Schema> = channels.iter().map(|c| Schema::parse(&c.schema).unwrap()).collect();
    let mut seen = [0usize; 3];
    let mut decoded_logs = Vec::new();
    for k in 0..100 {
        let t = k as f64 * 1e-3;
        let mode = if (40..60).contains(&k) { "flight" } else { "sliding" };
        let r = record(t, 0.3 + 0.001 * k as f64, 1.2, mode);
        view.messages(&r, &mut |c, bytes| {
            schemas[c].check(&channels[c].schema_name, bytes).unwrap_or_else(|e| panic!("period {k}, {}: {e}", channels[c].topic));
            seen[c] += 1;
            match c {
                0 => {
                    let tf = FrameTransforms::decode(bytes).unwrap();
                    let tip = origin(&tf, "tip");
                    assert!((tip[0] - r.z_t).abs() < 1e-12 && (tip[2] - r.z_n).abs() < 1e-12);
                }
                1 => {
                    let s = SceneUpdate::decode(bytes).unwrap();
                    let force = s.entities.iter().find(|e| e.id == "force").unwrap();
                    let a = &force.arrows[0];
                    let length = a.shaft_length + a.head_length;
                    assert!((length - 0.01 * (6.0f64.hypot(10.0))).abs() < 1e-12, "the arrow is |f| at 0.01 m/N");
                }
                _ => decoded_logs.push(Log::decode(bytes).unwrap()),
            }
        });
    }
    assert_eq!(seen[..2], [10, 10], "100 rows of 1 ms: a frame and a scene every 10 ms");
    let messages: Vec<&str> = decoded_logs.iter().map(|l| l.message.as_str()).collect();
    assert_eq!(decoded_logs.len(), 5, "start, lift-off (true and detected), touchdown (true and detected): {messages:?}");
    assert!(messages[1].starts_with("lift-off (true)") && decoded_logs[1].timestamp.unwrap().nsec() == 40_000_000);
}

/// Issue 84: a closed-loop run's `/log` names its control law at the first
/// period, before the start line, as the firmware's line; a view made without
/// one (`ArmView::new`) logs no law line.
#[test]
fn the_log_names_the_law_at_the_first_period() {
    let lines = |mut view: ArmView| {
        let mut out = Vec::new();
        for k in 0..3 {
            view.messages(&record(k as f64 * 1e-3, 0.3, 1.2, "sliding"), &mut |c, bytes| {
                if c == 2 {
                    out.push(Log::decode(bytes).unwrap());
                }
            });
        }
        out
    };
    let law = "law `impedance` (k_t = 2500, the rest at their defaults)";
    let named = lines(ArmView::of_law(PAPER, law.to_string()));
    assert_eq!(named.len(), 2, "{named:?}");
    assert_eq!(named[0].message, format!("control law: {law}"));
    assert_eq!(
        (named[0].name.as_str(), named[0].timestamp, named[0].level),
        ("firmware", named[1].timestamp, 2),
        "an info line of the firmware's, at the first period"
    );
    assert!(named[1].message.starts_with("start: contact mode sliding"), "{named:?}");
    let unnamed = lines(ArmView::new(PAPER));
    assert_eq!(unnamed.len(), 1);
    assert_eq!(unnamed[0].message, named[1].message);
}

/// A message that breaks the schema is caught: an undeclared field, a wrong
/// wire type, a cut message (the checker can fail).
#[test]
fn the_schema_check_catches_broken_messages() {
    let c = channel::<Log>(LOG_TOPIC);
    let schema = Schema::parse(&c.schema).unwrap();
    let mut good = Vec::new();
    Encode::encode(&crate::log::line(1.5, foxglove::messages::log::Level::Warning, "plant", "lift-off".into()), &mut good).unwrap();
    schema.check("foxglove.Log", &good).unwrap();
    let mut unknown = good.clone();
    // Field 99 (key 99 << 3 = 792, the varint 0x98 0x06), a varint 1.
    unknown.extend_from_slice(&[0x98, 0x06, 1]);
    assert!(schema.check("foxglove.Log", &unknown).unwrap_err().contains("field number 99 is not declared"));
    let cut = &good[..good.len() - 1];
    assert!(schema.check("foxglove.Log", cut).is_err());
    // Field 2 (level, an enum) sent as a 64-bit value.
    let mut wrong = good.clone();
    wrong.extend_from_slice(&[(2 << 3) | 1, 0, 0, 0, 0, 0, 0, 0, 0]);
    assert!(schema.check("foxglove.Log", &wrong).unwrap_err().contains("wire type"));
    // An undeclared log level.
    let mut level = good.clone();
    level.extend_from_slice(&[2 << 3, 77]);
    assert!(schema.check("foxglove.Log", &level).unwrap_err().contains("not a value"));
    assert!(schema.check("foxglove.Nothing", &good).is_err());
}

/// The belt's stripes move at `v_belt`: between two frames `dt` apart their
/// offset moves by `v_belt dt` (modulo the spacing).
#[test]
fn the_belts_stripes_move_at_the_belt_speed() {
    let stripe_x = |t: f64| {
        let s = crate::scene::scene_update(
            &PAPER,
            &crate::scene::Instant { t, tip: [0.0, -0.3], force: [0.0, 0.0], mode: "sliding", path: &[] },
        );
        let belt = s.entities.iter().find(|e| e.id == "belt").unwrap();
        belt.cubes[1].pose.unwrap().position.unwrap().x
    };
    let dt = 0.01;
    let moved = (stripe_x(0.5 + dt) - stripe_x(0.5)).rem_euclid(crate::scene::STRIPE_SPACING_M);
    let want = (PAPER.v_belt * dt).rem_euclid(crate::scene::STRIPE_SPACING_M);
    assert!((moved - want).abs() < 1e-12, "{moved} against {want}");
}

/// The shipped layout shows the view's channels and the tables' columns: its
/// 3D panel's topics, its plots' `topic.field` paths and its log panel's topic
/// are channels of a run's `trace.mcap` (the table's protobuf schemas, the view's).
#[test]
fn the_layout_names_channels_and_fields_a_run_writes() {
    let layout: serde_json::Value = serde_json::from_str(crate::LAYOUT).unwrap();
    let encoder = tables::mcap::RowEncoder::<rig::record::PeriodRecord>::new().unwrap();
    let fields = |topic: &str| -> Option<Vec<String>> {
        let c = encoder.channels().iter().find(|c| c.topic == topic)?;
        let set = <prost_types::FileDescriptorSet as prost::Message>::decode(&c.schema[..]).ok()?;
        Some(set.file.iter().flat_map(|f| &f.message_type).flat_map(|m| &m.field).map(|f| f.name().to_string()).collect())
    };
    let view_topics = [TF_TOPIC, SCENE_TOPIC, LOG_TOPIC];
    let panels = layout["configById"].as_object().unwrap();
    let mut plotted = 0;
    for (id, config) in panels {
        match id.split('!').next().unwrap() {
            "3D" => {
                for topic in config["topics"].as_object().unwrap().keys() {
                    assert!(view_topics.contains(&topic.as_str()), "{id}: {topic}");
                }
                assert_eq!(config["followTf"], "world");
            }
            "Plot" => {
                for path in config["paths"].as_array().unwrap() {
                    let path = path["value"].as_str().unwrap();
                    let (topic, field) = path.rsplit_once('.').unwrap();
                    let have = fields(topic).unwrap_or_else(|| panic!("{id}: no channel {topic}"));
                    assert!(have.iter().any(|f| f == field), "{id}: {topic} has no field {field}: {have:?}");
                    plotted += 1;
                }
            }
            "RosOut" => assert_eq!(config["topicToRender"], LOG_TOPIC),
            other => panic!("unexpected panel {other}"),
        }
        assert!(layout["layout"].to_string().contains(&format!("\"{id}\"")), "{id} is placed in the layout");
    }
    assert_eq!(plotted, 6);
}

/// The schema a channel carries is the SDK's own (`foxglove.<Type>`, protobuf).
#[test]
fn the_channels_carry_the_sdks_schemas() {
    for (c, want) in [
        (channel::<FrameTransforms>(TF_TOPIC), FrameTransforms::get_schema().unwrap()),
        (channel::<SceneUpdate>(SCENE_TOPIC), SceneUpdate::get_schema().unwrap()),
        (channel::<Log>(LOG_TOPIC), Log::get_schema().unwrap()),
    ] {
        assert_eq!(
            (c.schema_name.as_str(), c.schema_encoding.as_str(), c.message_encoding.as_str()),
            (want.name.as_str(), "protobuf", "protobuf")
        );
        assert_eq!(c.schema, want.data.as_ref());
        assert!(Schema::parse(&c.schema).unwrap().check(&c.schema_name, &[]).is_ok(), "an empty message is valid");
    }
}

/// A chain that does not reach `world` has no origin: a frame without a parent,
/// a loop between two frames.
#[test]
fn a_broken_chain_has_no_origin() {
    let mut tf = frame_transforms(&PAPER, 0.0, 0.1, 0.2);
    assert!(origin_in_world(&tf, "nowhere").is_none());
    tf.transforms[2].parent_frame_id = "link2".into();
    tf.transforms[3].parent_frame_id = "link2".into();
    assert!(origin_in_world(&tf, "tip").is_none(), "link2 is its own parent");
}
