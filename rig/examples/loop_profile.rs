//! The in-process closed loop alone (plant, sensors, firmware step; no output),
//! for instruction counts under callgrind and quick rates:
//! `cargo run --release -p rig --example loop_profile -- [DURATION_S] [REPEAT]`
//! (default 10 s, once); prints periods per wall second of each run.

use rig::{in_process::InProcessLink, rig::stream_loop, scenario::Scenario};

fn main() {
    let mut args = std::env::args().skip(1);
    let duration: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(10.0);
    let repeat: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = duration;
    for _ in 0..repeat {
        let mut link = InProcessLink::new(&s).expect("default scenario");
        let t = std::time::Instant::now();
        let (periods, err) = stream_loop(&s, &mut link, &mut ());
        assert!(err.is_none(), "{err:?}");
        println!("{periods} periods, {:.0} periods/s", periods as f64 / t.elapsed().as_secs_f64());
    }
}
