//! Plant speed targets (issue 2):
//! - `advance` over 1 ms intervals in steady sliding: median at most 5 us per interval;
//! - 300 s of open-loop simulation from x0a (mu = 0.6, v_belt = -0.4): under 0.5 s;
//! - the SIL pattern (issue 4): one 1 ms control period as the rig runs it, 0.2 ms
//!   under the previous command (`advance_events`: no force report) then 0.8 ms under
//!   the new one (`advance`; the zero-order-hold
//!   switch at `t_k + delta`): at most 2 us per period, so that the in-process loop
//!   (plant plus a ~0.4 us firmware step) reaches 300 000 periods per second;
//! - the default scenario's 10 s closed-loop run (10 000 periods) in-process.
//!
//! Run: `cargo bench -p sil-host --bench plant`.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use plant::initial::{X0A, X0D, deg_to_state};
use plant::{Plant, SimConfig};
use rig::{in_process, scenario::Scenario};
use shared::{ContactMode, Params};

/// A plant in steady sliding: from x0d with mu = 0.3 the tip slides without lifting off.
fn sliding_plant() -> Plant {
    let params = Params::new(0.3, -0.4).unwrap();
    let mut p = Plant::new(params, SimConfig::default(), deg_to_state(X0D.deg), 0.0, [0.0, 0.0]).unwrap();
    for _ in 0..2000 {
        p.advance(&plant::Hold([0.0, 0.0]), 1e-3, &mut plant::NoObserver).unwrap();
    }
    assert_eq!(p.mode(), ContactMode::Sliding, "benchmark state must be sliding");
    p
}

fn bench(c: &mut Criterion) {
    let base = sliding_plant();
    c.bench_function("advance_1ms_sliding", |b| {
        b.iter_batched_ref(
            || base.clone(),
            |p| {
                let r = p.advance(&plant::Hold([0.0, 0.0]), 1e-3, &mut plant::NoObserver).unwrap();
                assert_eq!(r.mode, ContactMode::Sliding);
                r.t
            },
            BatchSize::SmallInput,
        )
    });
    c.bench_function("sil_period_0.2ms_0.8ms_sliding", |b| {
        b.iter_batched_ref(
            || base.clone(),
            |p| {
                p.advance_events(&plant::Hold([0.02, -0.01]), 2e-4, &mut plant::NoObserver).unwrap();
                let r = p.advance(&plant::Hold([0.03, 0.01]), 8e-4, &mut plant::NoObserver).unwrap();
                assert_eq!(r.mode, ContactMode::Sliding);
                r.f[1]
            },
            BatchSize::SmallInput,
        )
    });
    let mut sil = c.benchmark_group("sil");
    sil.sample_size(10);
    let scenario = Scenario::default_scenario();
    sil.bench_function("default_scenario_10s_in_process", |b| {
        b.iter(|| {
            let (records, err) = in_process::run(&scenario, &mut ());
            assert!(err.is_none(), "{err:?}");
            records.len()
        })
    });
    sil.finish();
    let mut group = c.benchmark_group("open_loop");
    group.sample_size(10);
    group.bench_function("x0a_300s_one_interval", |b| {
        b.iter(|| {
            let mut p = Plant::new(Params::paper(), SimConfig::default(), deg_to_state(X0A.deg), 0.0, [0.0, 0.0]).unwrap();
            p.advance(&plant::Hold([0.0, 0.0]), 300.0, &mut plant::NoObserver).unwrap();
            p.counters().touchdowns
        })
    });
    group.bench_function("x0a_300s_1ms_ticks", |b| {
        b.iter(|| {
            let mut p = Plant::new(Params::paper(), SimConfig::default(), deg_to_state(X0A.deg), 0.0, [0.0, 0.0]).unwrap();
            for k in 0..300_000 {
                p.advance(&plant::Hold([0.0, 0.0]), (k + 1) as f64 * 1e-3 - p.time(), &mut plant::NoObserver).unwrap();
            }
            p.counters().touchdowns
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
