//! The in-process closed loop alone (plant, sensors, firmware step; no output),
//! for instruction counts under callgrind and quick rates:
//! `cargo run --release -p rig --example loop_profile -- [DURATION_S] [REPEAT]`
//! (default 10 s, once); prints periods per wall second of each run. With a
//! third argument `ipc FIRMWARE_EXE` (the `sil-host` binary), the same over
//! iceoryx2 in lockstep, the firmware in its own process.

use rig::{
    FirmwareLink,
    in_process::InProcessLink,
    ipc::{MonitorPolicy, default_rig_name},
    ipc_link::IpcLink,
    scenario::Scenario,
    stream_loop,
};

fn main() {
    let mut args = std::env::args().skip(1);
    let duration: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(10.0);
    let repeat: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let ipc = args.next().filter(|a| a == "ipc").and(args.next());
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = duration;
    let setup = rig::RunSetup::new(s).unwrap();
    for _ in 0..repeat {
        let mut link: Box<dyn FirmwareLink> = match &ipc {
            Some(exe) => Box::new(
                IpcLink::connect(&setup, &default_rig_name(), Some(std::path::Path::new(exe)), false, &MonitorPolicy::default())
                    .expect("firmware process"),
            ),
            None => Box::new(InProcessLink::new(&setup).expect("default scenario")),
        };
        let t = std::time::Instant::now();
        let (periods, err) = stream_loop(&setup, link.as_mut(), &mut ());
        assert!(err.is_none(), "{err:?}");
        println!("{periods} periods, {:.0} periods/s", periods as f64 / t.elapsed().as_secs_f64());
    }
}
