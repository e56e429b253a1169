//! End-to-end across crates: the firmware evaluates the shared model in f32, the
//! plant in f64, from one implementation; they agree to f32 rounding.

use nalgebra::Vector2;
use shared::{Arm, Params, SlipDirection};

#[test]
fn firmware_f32_model_matches_plant_f64_model() {
    let fw = firmware::paper_arm();
    let plant = Arm::new(Params::<f64>::paper());
    for i in -8..=8 {
        for j in -8..=8 {
            let q = Vector2::new(0.15 * i as f64, 0.17 * j as f64 - 0.3);
            let qd = Vector2::new(0.4 * j as f64, -0.3 * i as f64);
            let u = Vector2::new(0.1, -0.05);
            let a = plant.tip_dynamics(&q, &qd, &u);
            let b = fw.tip_dynamics(&q.cast::<f32>(), &qd.cast::<f32>(), &u.cast::<f32>());
            let rel = |x: f64, y: f32, scale: f64| ((y as f64) - x).abs() / scale.max(1e-6);
            assert!(rel(a.b(), b.b(), a.a_free.norm() + 1.0) < 1e-4, "b at q = {q:?}");
            for dir in [SlipDirection::Positive, SlipDirection::Negative] {
                assert!(rel(a.p(0.6, dir), b.p(0.6, dir), a.qmat.norm()) < 1e-5, "p at q = {q:?}");
            }
        }
    }
}
