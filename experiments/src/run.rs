//! A closed-loop SIL run of a scenario (`sil-host run`, `painleve.run`): the
//! check of the scenario and of the link before any link is made. The run
//! itself is the rig's ([`rig::run_loop`]).

use crate::{
    error::Error,
    scenario::load_scenario,
    settings::{RunArgs, RunLink},
};
use rig::faults::LinkKind;
use rig::record::RunError;
use rig::scenario::Scenario;
use rig::setup::RunSetup;

/// The run `scenario` asks for ([`RunSetup`]: the plant at `t = 0`, the
/// firmware's configuration, the faults), made once, before the output folder
/// is touched; `run` and `pil` hand it to the loop and the link.
///
/// # Errors
/// Bad plant parameters or initial conditions, or a firmware configuration the
/// firmware refuses (exit 2).
pub fn setup(scenario: Scenario) -> Result<RunSetup, Error> {
    RunSetup::new(scenario).map_err(|e| match e {
        RunError::Firmware(e) => Error::bad_input(format!("firmware configuration: {e}")),
        e => Error::from(e),
    })
}

/// Checks `sil-host run`'s scenario and options before any link is made: the
/// scenario with its overrides, the run it makes ([`setup`]), the link
/// (`--in-process`, `--link`) with the options it allows and the faults it can
/// inject. Returns the run and the link.
///
/// # Errors
/// Bad scenario, overrides or options (exit 2).
pub fn prepare(args: &RunArgs) -> Result<(RunSetup, RunLink), Error> {
    let setup = setup(load_scenario(&args.scenario)?)?;
    let scenario = setup.scenario();
    let chosen = if args.in_process { RunLink::InProcess } else { args.link.unwrap_or(RunLink::Iceoryx2) };
    let kind = match chosen {
        RunLink::InProcess => LinkKind::InProcess,
        RunLink::Iceoryx2 => LinkKind::Ipc,
        RunLink::Twin => LinkKind::Twin,
        RunLink::Emulator => LinkKind::Emulator,
    };
    if !matches!(chosen, RunLink::Twin | RunLink::Emulator) {
        crate::scenario::refuse_board_overrides(&args.scenario.set, chosen.without_board())?;
    }
    if args.elf.is_some() && chosen != RunLink::Emulator {
        return Err(Error::bad_input("--elf names the image for --link emulator only"));
    }
    if chosen != RunLink::Iceoryx2 {
        let what = match chosen {
            RunLink::Twin => "--link twin",
            RunLink::Emulator => "--link emulator",
            _ => "--in-process",
        };
        for (given, flag) in [
            (args.realtime, "--realtime"),
            (args.attach.is_some(), "--attach"),
            (args.rig.is_some(), "--rig"),
            (args.monitors > 0, "--monitors"),
        ] {
            if given {
                return Err(Error::bad_input(format!("{flag} needs the firmware process over iceoryx2: not with {what}")));
            }
        }
    }
    kind.check(&scenario.faults).map_err(|e| Error::bad_input(e.to_string()))?;
    Ok((setup, chosen))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use rig::record::PeriodRecord;
    use tables::{
        Table,
        csv::{CsvRow, push_header, push_row},
    };

    fn float() -> impl Strategy<Value = f64> {
        prop_oneof![any::<u64>().prop_map(f64::from_bits), -10.0..10.0f64, Just(0.0), Just(-0.0)]
    }

    proptest! {
        /// `trace.csv` of `run`/`pil`: the bytes of the old path (`csv::Writer::serialize`, header derived).
        #[test]
        fn period_records_match_the_csv_crate(
            f in proptest::array::uniform14(float()),
            b in proptest::array::uniform4(any::<bool>()),
            n in any::<(u32, u32)>(),
            m in 0..3usize,
        ) {
            let r = PeriodRecord {
                t: f[0], theta1: f[1], theta1_dot: f[2], theta2: f[3], theta2_dot: f[4], z_t: f[5], z_n: f[6], z_t_ref: f[7],
                f_t: f[8], f_n: f[9], mode: ["flight", "sliding", "sticking"][m], u1_cmd: f[10], u2_cmd: f[11],
                u1_applied: f[12], u2_applied: f[13], lift_off_true: b[0], lift_off_detected: b[1], deadline_miss: b[2],
                firmware_deadline_miss: b[3], overruns: n.0, status: n.1,
            };
            let mut w = csv::Writer::from_writer(Vec::new());
            w.serialize(r).unwrap();
            w.serialize(r).unwrap();
            let old = w.into_inner().unwrap();
            let mut new = Vec::new();
            push_header(&mut new, <PeriodRecord as CsvRow>::HEADER);
            push_row(&mut new, &r);
            push_row(&mut new, &r);
            prop_assert_eq!(String::from_utf8(old).unwrap(), String::from_utf8(new).unwrap());
            // The declared columns (Arrow, NumPy) and the serde path agree.
            let (declared, serde) = (Table::of_columns(&[r, r]), Table::of_rows(&[r, r]).unwrap());
            prop_assert_eq!(format!("{:?}", declared.columns), format!("{:?}", serde.columns));
        }
    }
}
