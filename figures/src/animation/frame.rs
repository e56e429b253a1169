//! One frame of an animation, drawn with plotters' bitmap backend into RGB
//! pixels: the title and the strip plot once ([`Painter::new`], the
//! background), then per frame the belt with stripes moving at its speed, the
//! base, the two links, the tip's recent path, the contact force (or an impact's
//! impulse) as an arrow at the tip, the tip itself, the time and contact mode, and
//! the strip plot's cursor.

use plotters::{
    coord::Shift,
    prelude::*,
    style::text_anchor::{HPos, Pos, VPos},
};

use super::{
    scene::{Arm, BELT_THICKNESS_M, Rect, Scene, joints},
    trace::ArmTrace,
};
use crate::plot::{
    self, Axes, colors,
    font::FAMILY,
    symbols::{Z_N, Z_T},
};

/// Frame width, px.
pub const WIDTH: u32 = 640;
/// Frame height, px.
pub const HEIGHT: u32 = 480;
/// The tip's colour (vermilion, Okabe-Ito): drawn nowhere else in a frame.
pub const TIP: RGBColor = colors::RED;
/// The links' colour.
pub const LINK: RGBColor = colors::BLUE;
/// The tip's recent path.
pub const PATH: RGBColor = colors::ORANGE;
/// The contact force's arrow.
pub const FORCE: RGBColor = colors::GREEN;
/// An impact's impulse arrow.
pub const IMPULSE: RGBColor = colors::PURPLE;
/// The belt's face and its stripes.
pub const BELT: (RGBColor, RGBColor) = (RGBColor(205, 205, 205), colors::GREY);
/// Every colour a frame draws with besides black, white and greys (for the palette).
pub const INKS: [RGBColor; 7] = [TIP, LINK, PATH, FORCE, IMPULSE, BELT.0, BELT.1];

/// The contact force's arrow scale, px per N.
pub const FORCE_PX_PER_N: f64 = 4.0;
/// An impact's impulse arrow scale, px per N s.
pub const IMPULSE_PX_PER_NS: f64 = 80.0;
/// How long an impact's impulse arrow stays after the impact, s of the run.
pub const IMPULSE_SHOWN_S: f64 = 0.04;
/// The tip's recent path: this much of the run before the frame's time, s.
pub const PATH_S: f64 = 0.3;
/// The distance between the belt's stripes, m.
const STRIPE_M: f64 = 0.03;

/// Text size of the labels, plotters' px.
const TEXT: f64 = 16.0;
/// The area the arm is fitted into (the rest of the scene band holds the labels).
pub const SCENE: Rect = Rect { x: 190.0, y: 58.0, w: 260.0, h: 236.0 };
/// Top of the strip plot, px.
const STRIP_TOP: i32 = 300;

/// What the strip plot under the scene shows against time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strip {
    /// The tip's height above the belt `z_n + H`, mm (open loop: the bounces).
    Height,
    /// The tip's z_t and the target z_t*, m (closed loop: the move along the belt).
    Tangential,
}

/// How an animation reads: its title, what the strip shows, how fast it runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Look {
    /// Title at the top (broken into lines to fit).
    pub title: String,
    /// The strip plot.
    pub strip: Strip,
    /// Slow-down: seconds of animation per second of the run (1: real time).
    pub slow_down: f64,
}

/// The background of every frame and the mappings that place the rest.
pub struct Painter<'a> {
    arm: Arm,
    trace: &'a ArmTrace,
    look: Look,
    /// The arm's plane to pixels.
    pub scene: Scene,
    background: Vec<u8>,
    /// The strip plot's time axis: pixel x of `t` is `a + b t`.
    strip_x: (f64, f64),
    /// The strip plot's pixel rows, top to bottom of its data.
    strip_y: (i32, i32),
}

fn e(e: impl std::fmt::Display) -> String {
    e.to_string()
}

impl<'a> Painter<'a> {
    /// The painter of frames of `trace` from `t0` to `t1` (s): the arm fitted to
    /// what it does then ([`Scene::fit`]), the title and the strip plot drawn.
    ///
    /// # Errors
    /// plotters' error, as text.
    pub fn new(arm: Arm, trace: &'a ArmTrace, look: Look, t0: f64, t1: f64) -> Result<Self, String> {
        let (i0, i1) = (trace.index_at(t0), trace.index_at(t1));
        let scene = Scene::fit(&arm, trace, i0, i1, SCENE, 0.02);
        let mut background = vec![255u8; (3 * WIDTH * HEIGHT) as usize];
        let (strip_x, strip_y);
        {
            plot::font::register();
            let root = BitMapBackend::with_buffer(&mut background, (WIDTH, HEIGHT)).into_drawing_area();
            root.fill(&WHITE).map_err(e)?;
            plot::draw_title(&root, &look.title, 18.0, 6)?;
            let strip = root.clone().shrink((0, STRIP_TOP), (WIDTH, HEIGHT - STRIP_TOP as u32));
            let ts: Vec<f64> = trace.t[i0..=i1].to_vec();
            let (series, y_desc): (Vec<(Vec<f64>, bool)>, String) = match look.strip {
                Strip::Height => (vec![((i0..=i1).map(|i| 1e3 * (trace.z_n[i] + arm.h)).collect(), false)], format!("{Z_N} + H (mm)")),
                Strip::Tangential => {
                    let mut v = vec![(trace.z_t[i0..=i1].to_vec(), false)];
                    if let Some(r) = &trace.z_t_ref {
                        v.push((r[i0..=i1].to_vec(), true));
                    }
                    (v, format!("{Z_T}, {Z_T}* (m)"))
                }
            };
            let (lo, hi) = series.iter().flat_map(|(v, _)| v.iter()).fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
            let pad = 0.08 * (hi - lo).max(1e-3);
            let lo = if look.strip == Strip::Height { lo.min(0.0) } else { lo - pad };
            let axes = Axes { caption: None, x: t0..t1, y: lo..hi + pad, x_desc: "t (s)", y_desc: &y_desc };
            let mut chart = plot::xy_chart(&strip, &axes)?;
            for (values, dashed) in &series {
                let points = ts.iter().copied().zip(values.iter().copied());
                if *dashed {
                    chart.draw_series(DashedLineSeries::new(points, 6, 5, BLACK.stroke_width(1))).map_err(e)?;
                } else {
                    chart.draw_series(LineSeries::new(points, LINK.stroke_width(2))).map_err(e)?;
                }
            }
            let (a, b) = (chart.backend_coord(&(t0, lo)), chart.backend_coord(&(t1, hi + pad)));
            strip_x = (f64::from(a.0) - t0 * f64::from(b.0 - a.0) / (t1 - t0), f64::from(b.0 - a.0) / (t1 - t0));
            strip_y = (b.1, a.1);
            root.present().map_err(e)?;
        }
        Ok(Self { arm, trace, look, scene, background, strip_x, strip_y })
    }

    /// The frame at time `t` of the run (s): RGB pixels, row by row, drawn from
    /// the trace's sample nearest to `t`.
    ///
    /// # Errors
    /// plotters' error, as text.
    pub fn frame(&self, t: f64) -> Result<Vec<u8>, String> {
        let mut buf = self.background.clone();
        {
            let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
            self.draw(&root, t)?;
            root.present().map_err(e)?;
        }
        Ok(buf)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, t: f64) -> Result<(), String> {
        let (tr, s, arm) = (self.trace, &self.scene, &self.arm);
        let i = tr.index_at(t);
        let px = |z_t: f64, z_n: f64| {
            let (x, y) = s.px(z_t, z_n);
            (x.round() as i32, y.round() as i32)
        };
        // The belt: its face, stripes moved by v_belt t, its surface line.
        let (top, bottom) = (px(0.0, -arm.h).1, px(0.0, -arm.h - BELT_THICKNESS_M).1);
        root.draw(&Rectangle::new([(0, top), (WIDTH as i32, bottom)], BELT.0.filled())).map_err(e)?;
        let spacing = STRIPE_M * s.px_per_m;
        let shift = (arm.v_belt * tr.t[i] * s.px_per_m).rem_euclid(spacing);
        let slant = f64::from(bottom - top) * 0.5;
        let mut x = shift - spacing;
        while x < f64::from(WIDTH) + spacing {
            let (x0, x1) = ((x + slant).round() as i32, x.round() as i32);
            if x1 >= 0 && x0 < WIDTH as i32 {
                root.draw(&PathElement::new(vec![(x0, top + 2), (x1, bottom - 1)], BELT.1.stroke_width(3))).map_err(e)?;
            }
            x += spacing;
        }
        root.draw(&PathElement::new(vec![(0, top), (WIDTH as i32, top)], BLACK.stroke_width(2))).map_err(e)?;
        // The base: a hatched mount above the joint.
        let o = px(0.0, 0.0);
        root.draw(&PathElement::new(vec![(o.0 - 22, o.1 - 9), (o.0 + 22, o.1 - 9)], BLACK.stroke_width(2))).map_err(e)?;
        for k in 0..5 {
            let x = o.0 - 20 + 10 * k;
            root.draw(&PathElement::new(vec![(x, o.1 - 9), (x + 7, o.1 - 17)], BLACK.stroke_width(1))).map_err(e)?;
        }
        root.draw(&PathElement::new(vec![(o.0, o.1 - 9), (o.0, o.1)], BLACK.stroke_width(3))).map_err(e)?;
        // The tip's recent path.
        let from = tr.index_at(tr.t[i] - PATH_S);
        let path: Vec<(i32, i32)> = (from..=i).map(|k| joints(arm.l, tr.theta1[k], tr.theta2[k])[1]).map(|p| px(p[0], p[1])).collect();
        root.draw(&PathElement::new(path, PATH.stroke_width(2))).map_err(e)?;
        // The links and joints.
        let [elbow, tip] = joints(arm.l, tr.theta1[i], tr.theta2[i]);
        let (pe, pt) = (px(elbow[0], elbow[1]), px(tip[0], tip[1]));
        root.draw(&PathElement::new(vec![o, pe, pt], LINK.stroke_width(6))).map_err(e)?;
        for j in [o, pe] {
            root.draw(&Circle::new(j, 5, WHITE.filled())).map_err(e)?;
            root.draw(&Circle::new(j, 5, BLACK.stroke_width(2))).map_err(e)?;
        }
        // The contact force (or the impulse of an impact just before), ending at the tip.
        let at_tip = |(vx, vy): (f64, f64), color: RGBColor| -> Result<(), String> {
            // The arrow's length is the vector's; it ends at the tip dot's edge.
            let len = vx.hypot(vy);
            if len < 3.0 {
                return Ok(());
            }
            let (ux, uy) = (vx / len, -vy / len);
            let end = (f64::from(pt.0) - 7.0 * ux, f64::from(pt.1) - 7.0 * uy);
            arrow(root, (end.0 - len * ux, end.1 - len * uy), end, color, 8.0)
        };
        at_tip((tr.f_t[i] * FORCE_PX_PER_N, tr.f_n[i] * FORCE_PX_PER_N), FORCE)?;
        if let Some(imp) = tr.impacts.iter().rev().find(|m| m.t <= tr.t[i] && tr.t[i] - m.t < IMPULSE_SHOWN_S) {
            at_tip((imp.impulse_t * IMPULSE_PX_PER_NS, imp.impulse_n * IMPULSE_PX_PER_NS), IMPULSE)?;
        }
        root.draw(&Circle::new(pt, 6, TIP.filled())).map_err(e)?;
        self.labels(root, i)?;
        // The strip plot's cursor.
        let cx = (self.strip_x.0 + self.strip_x.1 * tr.t[i]).round() as i32;
        root.draw(&PathElement::new(vec![(cx, self.strip_y.0), (cx, self.strip_y.1)], BLACK.stroke_width(2))).map_err(e)?;
        Ok(())
    }

    /// The time, mode and speed on the left; the legend with the arrows' scales on the right.
    fn labels<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, i: usize) -> Result<(), String> {
        let tr = self.trace;
        let style = TextStyle::from((FAMILY, TEXT).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let speed = if (self.look.slow_down - 1.0).abs() < 1e-9 {
            "real time".to_string()
        } else {
            format!("slowed down {}×", self.look.slow_down)
        };
        for (k, line) in [format!("t = {:.3} s", tr.t[i]), format!("contact: {}", tr.mode[i]), speed].iter().enumerate() {
            root.draw_text(line, &style, (12, 80 + 24 * k as i32)).map_err(e)?;
        }
        let x = 462;
        let mut y = 80;
        root.draw(&PathElement::new(vec![(x, y), (x + 24, y - 6)], PATH.stroke_width(2))).map_err(e)?;
        root.draw_text(&format!("tip path, last {PATH_S} s"), &style, (x + 32, y)).map_err(e)?;
        y += 26;
        let ten = 10.0 * FORCE_PX_PER_N;
        arrow(root, (f64::from(x), f64::from(y)), (f64::from(x) + ten, f64::from(y)), FORCE, 8.0)?;
        root.draw_text("force: 10 N", &style, (x + ten as i32 + 8, y)).map_err(e)?;
        if !tr.impacts.is_empty() {
            y += 26;
            let half = 0.5 * IMPULSE_PX_PER_NS;
            arrow(root, (f64::from(x), f64::from(y)), (f64::from(x) + half, f64::from(y)), IMPULSE, 8.0)?;
            root.draw_text("impulse: 0.5 N s", &style, (x + half as i32 + 8, y)).map_err(e)?;
        }
        if self.look.strip == Strip::Tangential {
            y += 26;
            root.draw(&PathElement::new(vec![(x, y), (x + 24, y)], LINK.stroke_width(2))).map_err(e)?;
            root.draw_text(&format!("{Z_T} (below)"), &style, (x + 32, y)).map_err(e)?;
            y += 26;
            root.draw(&PathElement::new(vec![(x, y), (x + 7, y)], BLACK.stroke_width(1))).map_err(e)?;
            root.draw(&PathElement::new(vec![(x + 12, y), (x + 19, y)], BLACK.stroke_width(1))).map_err(e)?;
            root.draw_text(&format!("{Z_T}* (below)"), &style, (x + 32, y)).map_err(e)?;
        }
        y += 26;
        let dir = if self.arm.v_belt < 0.0 {
            " ←"
        } else if self.arm.v_belt > 0.0 {
            " →"
        } else {
            ""
        };
        root.draw_text(&format!("belt: {} m/s{dir}", self.arm.v_belt), &style, (x, y)).map_err(e)?;
        Ok(())
    }
}

/// An arrow from `from` to `to` (px), its head `head` px long.
fn arrow<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    from: (f64, f64),
    to: (f64, f64),
    color: RGBColor,
    head: f64,
) -> Result<(), String> {
    let (dx, dy) = (to.0 - from.0, to.1 - from.1);
    let len = dx.hypot(dy).max(1e-9);
    let (ux, uy) = (dx / len, dy / len);
    let base = (to.0 - ux * head, to.1 - uy * head);
    let p = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
    root.draw(&PathElement::new(vec![p(from.0, from.1), p(base.0, base.1)], color.stroke_width(3))).map_err(e)?;
    let wing = 0.5 * head;
    let tri = vec![p(to.0, to.1), p(base.0 - uy * wing, base.1 + ux * wing), p(base.0 + uy * wing, base.1 - ux * wing)];
    root.draw(&Polygon::new(tri, color.filled())).map_err(e)?;
    Ok(())
}
