//! The impedance law beside the paper's two laws (docs/results.md "A law of one's
//! own"): `Z_t,sliding` and the tracking limit from `x0d` and `x0u` (the same
//! search as `sil-host zmax`, sampled setting: `analyses::zmax::search_law`), and
//! the lift-offs of a 10 s run of each of the paper's four scenarios
//! (`scenarios/{pid,hybrid}-x0{d,u}.toml`) with each law.
//!
//!     cargo run --release -p law-template --example paper_cases [-- --json]

use std::sync::atomic::AtomicBool;

use analyses::zmax::{Combination, Criteria, Setting, default_bracket, search_law};
use firmware::{ControlLaw, ControllerKind, PaperLaws};
use law_template::Impedance;
use plant::initial::PaperX0;
use rig::{RunObserver, Scenario, in_process::run_law, law::LawTable};

/// Counts the plant's departures from the belt (`analyses::lift_offs::of`).
#[derive(Default)]
struct LiftOffs(u64);

impl RunObserver for LiftOffs {
    fn on_counters(&mut self, counters: &plant::Counters) {
        self.0 = analyses::lift_offs::of(counters);
    }
}

fn paper(name: &str) -> Scenario {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(format!("{name}.toml"));
    Scenario::from_toml(&std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))).unwrap()
}

fn with_law(mut s: Scenario) -> Scenario {
    s.law = Some(LawTable { name: Impedance::SPEC.name.into(), params: Default::default() });
    s
}

/// The run's lift-offs and how it ended.
fn lift_offs<L: ControlLaw>(s: &Scenario) -> (u64, String) {
    let mut seen = LiftOffs::default();
    let (_, e) = run_law::<L>(s, &mut seen);
    (seen.0, e.map_or_else(|| "ran 10 s".into(), |e| e.to_string()))
}

fn main() {
    let json = std::env::args().any(|a| a == "--json");
    let mut out = serde_json::Map::new();
    let stop = AtomicBool::new(false);
    // Z_t,sliding of the impedance law, from x0d and x0u.
    for (x0, base) in [(PaperX0::D, "hybrid-x0d"), (PaperX0::U, "hybrid-x0u")] {
        let base = with_law(paper(base));
        let combo = Combination { controller: ControllerKind::Hybrid, x0, setting: Setting::Sampled };
        let bracket = default_bracket(&base, x0).unwrap();
        let s = search_law::<Impedance>(&base, combo, bracket, 1e-3, &Criteria::default(), &stop, |_| {}).unwrap();
        let (z, tracked) = (s.bisection.limit(), s.tracking.limit());
        let why = s.failing_trial(&s.bisection).map(|t| t.stop.name()).unwrap_or("-");
        if !json {
            println!(
                "impedance from x0{}: Z_t,sliding {} m (above it: {why}), tracking limit {} m, {} trials",
                x0.letter(),
                z.map_or("none".into(), |z| format!("{z:.4}")),
                tracked.map_or("none".into(), |z| format!("{z:.4}")),
                s.trials.len()
            );
        }
        out.insert(
            format!("zmax-x0{}", x0.letter()),
            serde_json::json!({"z_t_sliding_m": z, "tracking_limit_m": tracked, "above": why, "trials": s.trials.len()}),
        );
    }
    // The lift-offs of the paper's four scenarios, with their own law and with the impedance law.
    for name in ["pid-x0d", "pid-x0u", "hybrid-x0d", "hybrid-x0u"] {
        let s = paper(name);
        let (own, own_end) = lift_offs::<PaperLaws>(&s);
        let (imp, imp_end) = lift_offs::<Impedance>(&with_law(s));
        if !json {
            println!("{name}: its own law {own} lift-offs ({own_end}); impedance {imp} lift-offs ({imp_end})");
        }
        out.insert(
            name.into(),
            serde_json::json!({"own_law": {"lift_offs": own, "end": own_end}, "impedance": {"lift_offs": imp, "end": imp_end}}),
        );
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&out).unwrap());
    }
}
