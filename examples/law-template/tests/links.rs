//! The law of this crate where the paper's laws run (issue 70): in process and
//! as its own firmware process over iceoryx2 (this crate's `law-firmware`, as
//! `sil-host run --attach` meets it), the same records bit for bit; the
//! scenario's `[law]` table checked against the law's declaration on both links.

use std::path::Path;

use law_template::Impedance;
use rig::{
    in_process::InProcessLink, ipc::MonitorPolicy, ipc_link::IpcLink, law::LawTable, period_loop::run_loop, record::PeriodRecord,
    scenario::Scenario, setup::RunSetup,
};

/// The default scenario (hybrid's settings, x0d, mu 0.6) for `duration_s`
/// under the impedance law with `params`.
fn scenario(duration_s: f64, params: &[(&str, f64)]) -> Scenario {
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = duration_s;
    s.law = Some(LawTable { name: "impedance".into(), params: params.iter().map(|(k, v)| ((*k).to_string(), *v)).collect() });
    s
}

fn in_process(s: &Scenario) -> Vec<PeriodRecord> {
    let setup = RunSetup::new(s.clone()).unwrap();
    let mut link = InProcessLink::<Impedance>::for_law(&setup).unwrap();
    let (records, error) = run_loop(&setup, &mut link, &mut ());
    assert!(error.is_none(), "{error:?}");
    records
}

/// A rig name of this test process's own.
fn rig_name(tag: &str) -> String {
    format!("law-template-{tag}-{}", std::process::id())
}

fn over_iceoryx2(s: &Scenario, rig: &str) -> Result<Vec<PeriodRecord>, String> {
    let setup = RunSetup::new(s.clone()).map_err(|e| e.to_string())?;
    let exe = Path::new(env!("CARGO_BIN_EXE_law-firmware"));
    let mut link = IpcLink::connect(&setup, rig, Some(exe), false, &MonitorPolicy::default()).map_err(|e| e.to_string())?;
    let (records, error) = run_loop(&setup, &mut link, &mut ());
    match error {
        None => Ok(records),
        Some(e) => Err(e.to_string()),
    }
}

/// Bit for bit: every field of every record, NaN included.
fn bits(records: &[PeriodRecord]) -> Vec<String> {
    records.iter().map(|r| format!("{r:?}")).collect()
}

#[test]
fn the_law_runs_in_process_and_over_iceoryx2_with_the_same_records() {
    let s = scenario(2.0, &[("k_t", 2500.0), ("d_n", 50.0)]);
    let a = in_process(&s);
    let b = over_iceoryx2(&s, &rig_name("same")).unwrap();
    assert_eq!(a.len(), 2000);
    assert_eq!(bits(&a), bits(&b));
    // The law acts: at the end the tip slides on the belt, presses with about
    // f_n* = 10 N, and is within friction's offset mu f_n / k_t (2.4 mm) and
    // a millimetre of z_t*; no safe state.
    let last = a.last().unwrap();
    assert_eq!((last.mode, last.status & 0xff), ("sliding", 0), "{last:?}");
    assert!((last.f_n - 10.0).abs() < 1.0, "{last:?}");
    assert!((last.z_t - last.z_t_ref).abs() < 2.4e-3 + 1e-3, "{last:?}");
}

#[test]
fn a_law_table_that_does_not_fit_is_refused_on_both_links() {
    let bad = scenario(0.1, &[("k_t", 1e6)]);
    let setup = RunSetup::new(bad.clone()).unwrap();
    let e = InProcessLink::<Impedance>::for_law(&setup).unwrap_err().to_string();
    assert!(e.contains("`k_t` = 1000000 N/m is out of its range [0, 20000] N/m"), "{e}");
    // The law's process refuses the table itself (bad input, exit 2, its
    // reason on stderr) before it announces anything (before it connects, on a
    // loaded machine, or after: either way before the handshake).
    let e = over_iceoryx2(&bad, &rig_name("bad")).unwrap_err();
    assert!(e.contains("the firmware process exited (exit status: 2) before"), "{e}");
    // The paper's firmware is not this law: the in-process link of the
    // paper's laws refuses the table and says where a law of one's own runs.
    let e = InProcessLink::new(&RunSetup::new(scenario(0.1, &[])).unwrap()).unwrap_err().to_string();
    assert!(e.contains("the firmware runs the paper's laws"), "{e}");
}

/// A law that misbehaves on purpose: the impedance law until `t = 0.5 s`,
/// then torques that are not finite (NaN on motor 2).
#[derive(Debug, Clone, Copy, Default)]
struct Misbehaving {
    law: Impedance,
    periods: u32,
}

impl firmware::ControlLaw for Misbehaving {
    const SPEC: firmware::LawSpec = firmware::LawSpec { name: "misbehaving", ..Impedance::SPEC };

    fn fresh(cfg: &firmware::Config) -> Self {
        Self { law: Impedance::fresh(cfg), periods: 0 }
    }

    fn declares(cfg: &firmware::Config) -> firmware::Declares {
        Impedance::declares(cfg)
    }

    fn step(&mut self, ctx: &firmware::LawContext<'_>, input: &firmware::LawInput) -> Result<firmware::LawOutput, firmware::law::LawError> {
        self.periods += 1;
        let mut out = self.law.step(ctx, input)?;
        if self.periods > 500 {
            out.u[1] = f32::NAN;
        }
        Ok(out)
    }
}

#[test]
fn a_law_that_answers_nan_is_stopped_in_the_safe_state_at_zero_torque() {
    let mut s = scenario(1.0, &[]);
    s.law.as_mut().unwrap().name = "misbehaving".into();
    let setup = RunSetup::new(s).unwrap();
    let mut link = InProcessLink::<Misbehaving>::for_law(&setup).unwrap();
    let (records, error) = run_loop(&setup, &mut link, &mut ());
    match error {
        Some(rig::record::RunError::SafeState { k, reason: firmware::SafeReason::NonFinite, .. }) => assert_eq!(k, 500, "the first NaN"),
        other => panic!("{other:?}"),
    }
    // Its period's command is the safe state's: zero torque, the safe-state bit set.
    let last = records.last().unwrap();
    assert_eq!((last.u1_cmd, last.u2_cmd), (0.0, 0.0), "{last:?}");
    assert!(records[..500].iter().all(|r| r.status & shared::wire::status::SAFE_STATE == 0), "healthy before");
    assert_ne!(last.status & shared::wire::status::SAFE_STATE, 0, "{last:?}");
}

/// docs/results.md "A law of one's own": the impedance law's `Z_t,sliding` from
/// x0d is 0.1487 m (examples/paper_cases.rs, bisection to 1 mm): a trial 3 mm
/// below it slides to its target, one 3 mm above lifts off.
#[test]
fn the_impedance_law_slides_below_its_z_t_sliding_and_lifts_off_above() {
    use analyses::zmax::{Combination, Criteria, Setting, StopReason, trial_law};
    let mut base =
        Scenario::from_toml(&std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/hybrid-x0d.toml")).unwrap())
            .unwrap();
    base.law = Some(LawTable { name: "impedance".into(), params: Default::default() });
    let combo = Combination { controller: firmware::ControllerKind::Hybrid, x0: plant::initial::PaperX0::D, setting: Setting::Sampled };
    let c = Criteria::default();
    let (below, _) = trial_law::<Impedance>(&base, combo, 0.1457, &c).unwrap();
    assert!(below.slides_to_target && below.lift_offs == 0, "{:?}", below.stop);
    let (above, _) = trial_law::<Impedance>(&base, combo, 0.1517, &c).unwrap();
    assert_eq!(above.stop, StopReason::LiftOff);
    // The ideal setting is the paper's laws' continuous time: refused for this law.
    let ideal = Combination { setting: Setting::Ideal, ..combo };
    assert!(trial_law::<Impedance>(&base, ideal, 0.1, &c).unwrap_err().to_string().contains("sampled setting only"));
}

/// The impedance law, declaring the hybrid law's tracking dynamics (`K'_P`,
/// `K'_D`, `K'_I` of the configuration) it does not have.
#[derive(Debug, Clone, Copy, Default)]
struct Pretender(Impedance);

impl firmware::ControlLaw for Pretender {
    const SPEC: firmware::LawSpec = firmware::LawSpec { name: "pretender", ..Impedance::SPEC };

    fn fresh(cfg: &firmware::Config) -> Self {
        Self(Impedance::fresh(cfg))
    }

    fn declares(cfg: &firmware::Config) -> firmware::Declares {
        firmware::HybridLaw::declares(cfg)
    }

    fn step(&mut self, ctx: &firmware::LawContext<'_>, input: &firmware::LawInput) -> Result<firmware::LawOutput, firmware::law::LawError> {
        self.0.step(ctx, input)
    }
}

/// The tracking check follows what a law declares, not its name: the same
/// torques run clean when the law promises nothing, and are stopped by the
/// tracking check when it promises the hybrid law's dynamics.
#[test]
fn the_tracking_check_holds_a_law_to_what_it_declares() {
    // A soft spring along the belt: a steady error mu f_n / k_t of about 12 mm,
    // past the check's 5 mm margin (firmware::tracking::TRACKING_M).
    let s = scenario(3.0, &[("k_t", 500.0), ("d_t", 45.0)]);
    let records = in_process(&s);
    assert_eq!(records.len(), 3000, "promising nothing, it runs to the end");
    let mut p = s.clone();
    p.law.as_mut().unwrap().name = "pretender".into();
    let setup = RunSetup::new(p).unwrap();
    let mut link = InProcessLink::<Pretender>::for_law(&setup).unwrap();
    let (pretended, error) = run_loop(&setup, &mut link, &mut ());
    match error {
        Some(rig::record::RunError::SafeState { reason: firmware::SafeReason::Tracking, k, .. }) => {
            // The same torques up to the trip: the check changed nothing before it.
            assert_eq!(bits(&pretended[..k]), bits(&records[..k]));
        }
        other => panic!("{other:?}"),
    }
}

/// `law-firmware firmware --help` names the binary as it was run and lists every
/// parameter the law declares (`ControlLaw::SPEC`) with its unit, default and
/// range (issue 84: the subcommand's help had `FirmwareArgs`' own text instead).
#[test]
fn the_firmware_help_names_the_binary_and_lists_every_parameter() {
    use firmware::ControlLaw;
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_law-firmware")).args(["firmware", "--help"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(help.contains("Usage: law-firmware firmware"), "{help}");
    assert!(help.contains(&format!("control law `{}`", Impedance::SPEC.name)), "{help}");
    assert!(!Impedance::SPEC.params.is_empty());
    for p in Impedance::SPEC.params {
        let line =
            help.lines().find(|l| l.split_whitespace().next() == Some(p.name)).unwrap_or_else(|| panic!("{} not listed: {help}", p.name));
        for part in [format!("{}:", p.unit), format!("default {}", p.default), format!("from {} to {}", p.min, p.max)] {
            assert!(line.contains(&part), "{}: {part:?} not in {line:?}", p.name);
        }
    }
}
