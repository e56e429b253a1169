use super::*;
use crate::initial::{X0A, deg_to_state};

fn x0a_plant(cfg: SimConfig) -> Plant {
    Plant::new(Params::paper(), cfg, deg_to_state(X0A.deg), 0.0, [0.0, 0.0]).unwrap()
}

#[test]
fn smoke_x0a() {
    let mut p = x0a_plant(SimConfig::default());
    println!("mode {:?} tip {:?}", p.mode(), p.tip());
    for _ in 0..20 {
        let r = p.advance([0.0, 0.0], 0.5).unwrap();
        println!("t={:.3} mode={:?} x={:?} f={:?} events={}", r.t, r.mode, r.x, r.f, r.events.len());
        for e in r.events.iter().take(5) {
            println!("   {:?}", e);
        }
    }
    println!("{:?}", p.counters());
}
