//! The arm view's geometry: the joints of every frame by the plant's own
//! forward kinematics ([`shared::kinematics`]), the world box the view must
//! show, and the force arrow's scale.

use nalgebra::Vector2;
use shared::kinematics::joint_positions;

/// Depth of the belt drawn under its surface, m.
pub const BELT_DEPTH_M: f64 = 0.03;

/// The longest force arrow, m of the view (the largest force in the frames).
pub const ARROW_MAX_M: f64 = 0.08;

/// The elbow and the tip of configuration `theta = [theta1, theta2]` (rad) with
/// links of length `l` (m), in the belt's frame `[z_t, z_n]` (m, the base at the
/// origin), by [`shared::kinematics::joint_positions`] (the plant's kinematics).
pub fn joints(l: f64, theta: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let [elbow, tip] = joint_positions(l, &Vector2::new(theta[0], theta[1]));
    ([elbow[0], elbow[1]], [tip[0], tip[1]])
}

/// The world box `[z_t min, z_t max, z_n min, z_n max]` (m) the view shows: the
/// arm's full reach `2 l` each side of the base, from under the belt (at `-h`,
/// [`BELT_DEPTH_M`] of it and 3 cm for the `z_t*` marker) up to above the base mount or the
/// highest joint of `points` (m), whichever is higher.
pub fn world_box(l: f64, h: f64, points: impl Iterator<Item = [f64; 2]>) -> [f64; 4] {
    let top = points.map(|p| p[1]).filter(|y| y.is_finite()).fold(0.0_f64, f64::max);
    let reach = 2.0 * l * 1.05;
    [-reach, reach, -h - BELT_DEPTH_M - 0.03, top.max(0.03) + 0.02]
}

/// The force arrow's scale, N per m of the view: the smallest of 1, 2 or 5
/// times a power of ten that draws `f_max` (N, the largest force) no longer
/// than [`ARROW_MAX_M`]; 100 N/m (1 cm per N) when there is no force.
pub fn force_scale(f_max: f64) -> f64 {
    if !(f_max.is_finite() && f_max > 0.0) {
        return 100.0;
    }
    let need = f_max / ARROW_MAX_M;
    let decade = 10f64.powf(need.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * decade).find(|s| *s >= need * (1.0 - 1e-12)).unwrap_or(10.0 * decade)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_joints_follow_the_model_geometry() {
        // docs/model.md: z_t = l (sin theta1 + sin theta2), z_n = -l (cos theta1 + cos theta2).
        let (l, th) = (0.21, [0.3_f64, -0.7_f64]);
        let (e, t) = joints(l, th);
        assert!((e[0] - l * th[0].sin()).abs() < 1e-12 && (e[1] + l * th[0].cos()).abs() < 1e-12);
        assert!((t[0] - l * (th[0].sin() + th[1].sin())).abs() < 1e-12);
        assert!((t[1] + l * (th[0].cos() + th[1].cos())).abs() < 1e-12);
        let hanging = joints(l, [0.0, 0.0]).1;
        assert!((hanging[1] + 2.0 * l).abs() < 1e-12);
    }

    #[test]
    fn the_force_scale_is_a_round_number_that_fits() {
        assert_eq!(force_scale(12.0), 200.0, "12 N / 0.08 m = 150 N/m -> 200 N/m");
        assert_eq!(force_scale(8.0), 100.0);
        assert_eq!(force_scale(0.0), 100.0);
        assert_eq!(force_scale(f64::NAN), 100.0);
        for f in [0.013, 0.9, 3.0, 47.0, 1234.0] {
            let s = force_scale(f);
            assert!(f / s <= ARROW_MAX_M * (1.0 + 1e-9) && f / s > ARROW_MAX_M / 5.01, "{f} N at {s} N/m");
        }
    }

    #[test]
    fn the_box_holds_the_belt_and_the_arm() {
        let b = world_box(0.21, 0.3775, [[0.0, 0.1], [0.1, f64::NAN]].into_iter());
        assert!(b[2] < -0.3775 - BELT_DEPTH_M && (b[3] - 0.12).abs() < 1e-12 && b[0] < -0.42 && b[1] > 0.42);
    }
}
