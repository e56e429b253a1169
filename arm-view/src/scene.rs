//! The 3D scene of one instant (`foxglove.SceneUpdate`): the two links and the
//! tip in their own frames ([`crate::geometry`]), the belt with stripes moving
//! at `v_belt`, the contact force as an arrow at the tip, the tip's recent
//! path and a label with the time, the contact mode and the forces.

use foxglove::messages::{
    ArrowPrimitive, Color, CubePrimitive, LinePrimitive, Point3, Pose, SceneEntity, SceneUpdate, SpherePrimitive, TextPrimitive, Vector3,
    line_primitive,
};

use crate::geometry::{ArmGeometry, FRAMES, about_y, timestamp};

/// The contact force's arrow: metres of arrow per newton (10 N, the default
/// `f_n*`, is 0.1 m, about half a link).
pub const FORCE_SCALE_M_PER_N: f64 = 0.01;

/// The belt's drawn length along `x` (m), centred under the base, and its
/// stripes' spacing (m): stripes move at `v_belt`, so their motion shows the belt's.
pub const BELT_LENGTH_M: f64 = 0.8;
/// The spacing of the belt's stripes, m.
pub const STRIPE_SPACING_M: f64 = 0.05;

/// What the scene shows at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Instant<'a> {
    /// Time, s.
    pub t: f64,
    /// The tip `[z_t, z_n]`, m.
    pub tip: [f64; 2],
    /// Contact force `[f_t, f_n]`, N (NaN: not known, no arrow).
    pub force: [f64; 2],
    /// Contact mode (`sliding`, `flight`, `sticking`).
    pub mode: &'a str,
    /// The tip's recent positions `[z_t, z_n]` (m), oldest first, this one last.
    pub path: &'a [[f64; 2]],
}

fn color(r: f64, g: f64, b: f64) -> Option<Color> {
    Some(Color { r, g, b, a: 1.0 })
}

fn pose(x: f64, z: f64, angle_about_y: f64) -> Option<Pose> {
    Some(Pose { position: Some(Vector3 { x, y: 0.0, z }), orientation: Some(about_y(angle_about_y)) })
}

fn entity(id: &str, frame: &str, t: f64) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(t)),
        frame_id: frame.into(),
        id: id.into(),
        // Locked to its frame: the links follow the transforms of /tf.
        frame_locked: true,
        ..Default::default()
    }
}

/// The scene at `now` for the arm `g`: entities `link1`, `link2` (a bar along
/// each link, in its frame), `tip` (a sphere), `belt` (the belt and its
/// stripes), `force` (the contact force, [`FORCE_SCALE_M_PER_N`]; no arrow
/// when it is zero or not finite), `path` (the tip's recent path) and `label`.
/// Each update replaces the entities of the last by their ids.
pub fn scene_update(g: &ArmGeometry, now: &Instant) -> SceneUpdate {
    let t = now.t;
    let bar = |frame: &str, rgb: (f64, f64, f64)| {
        let mut e = entity(frame, frame, t);
        e.cubes.push(CubePrimitive {
            pose: pose(0.0, -g.l / 2.0, 0.0),
            size: Some(Vector3 { x: 0.012, y: 0.012, z: g.l }),
            color: color(rgb.0, rgb.1, rgb.2),
        });
        e.spheres.push(SpherePrimitive {
            pose: pose(0.0, 0.0, 0.0),
            size: Some(Vector3 { x: 0.02, y: 0.02, z: 0.02 }),
            color: color(0.2, 0.2, 0.2),
        });
        e
    };
    let mut tip = entity(FRAMES[4], FRAMES[4], t);
    tip.spheres.push(SpherePrimitive {
        pose: pose(0.0, 0.0, 0.0),
        size: Some(Vector3 { x: 0.016, y: 0.016, z: 0.016 }),
        color: color(0.85, 0.1, 0.1),
    });

    let mut belt = entity("belt", FRAMES[0], t);
    belt.cubes.push(CubePrimitive {
        pose: pose(0.0, -g.h - 0.01, 0.0),
        size: Some(Vector3 { x: BELT_LENGTH_M, y: 0.1, z: 0.02 }),
        color: color(0.55, 0.55, 0.5),
    });
    // The stripes' offset: the belt has moved v_belt t since t = 0.
    let shift = (g.v_belt * t).rem_euclid(STRIPE_SPACING_M);
    let n = (BELT_LENGTH_M / STRIPE_SPACING_M) as i32;
    for k in 0..n {
        let x = -BELT_LENGTH_M / 2.0 + shift + f64::from(k) * STRIPE_SPACING_M;
        belt.cubes.push(CubePrimitive {
            pose: pose(x, -g.h + 0.0005, 0.0),
            size: Some(Vector3 { x: 0.006, y: 0.1, z: 0.001 }),
            color: color(0.2, 0.2, 0.2),
        });
    }

    let mut force = entity("force", FRAMES[0], t);
    let [f_t, f_n] = now.force;
    let magnitude = f_t.hypot(f_n);
    if magnitude.is_finite() && magnitude > 0.0 {
        // The arrow's +x turned onto (f_t, f_n): a turn about y by atan2(-f_n, f_t).
        let length = magnitude * FORCE_SCALE_M_PER_N;
        force.arrows.push(ArrowPrimitive {
            pose: pose(now.tip[0], now.tip[1], (-f_n).atan2(f_t)),
            shaft_length: 0.8 * length,
            shaft_diameter: 0.004,
            head_length: 0.2 * length,
            head_diameter: 0.012,
            color: color(0.95, 0.55, 0.0),
        });
    }

    let mut path = entity("path", FRAMES[0], t);
    if now.path.len() >= 2 {
        path.lines.push(LinePrimitive {
            r#type: line_primitive::Type::LineStrip as i32,
            pose: pose(0.0, 0.0, 0.0),
            thickness: 0.002,
            scale_invariant: false,
            points: now.path.iter().map(|p| Point3 { x: p[0], y: 0.0, z: p[1] }).collect(),
            color: color(0.1, 0.4, 0.85),
            ..Default::default()
        });
    }

    let mut label = entity("label", FRAMES[0], t);
    label.texts.push(TextPrimitive {
        pose: pose(0.0, 0.06, 0.0),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: color(0.1, 0.1, 0.1),
        text: format!("t = {t:.3} s, {}, f_t = {f_t:.2} N, f_n = {f_n:.2} N", now.mode),
    });

    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![bar(FRAMES[2], (0.25, 0.45, 0.7)), bar(FRAMES[3], (0.3, 0.6, 0.85)), tip, belt, force, path, label],
    }
}
