//! Tests of the faults ([`super`]): windows of whole periods, every kind acting
//! from the same period, the checks' messages, what each link refuses, and the
//! random schedules of the soak.

use super::*;

#[test]
fn windows_cover_whole_periods() {
    let f = Fault { delay_s: 0.0, signal: None, ..Fault::new(FaultKind::DropCommand, 0.5, 0.003) };
    let ms = Period::MILLISECOND;
    assert_eq!(f.periods(ms), 500..503);
    assert_eq!(Fault { duration_s: 0.0, ..f }.periods(ms), 500..501, "at least the period at at_s");
    assert_eq!(Fault { at_s: 0.0, duration_s: 0.0, ..f }.periods(ms), 0..1);
    // Inexact products of the period round to the microsecond first.
    assert_eq!(Fault { at_s: 3.0 * 0.1, duration_s: 7.0 * 0.001, ..f }.periods(ms), 300..307);
    // At 6 kHz (167 us): the first sample time at or after 1 s is period 5989 (1.000163 s).
    let p6 = Period::from_rate_hz(6000.0).unwrap();
    assert_eq!(Fault { at_s: 1.0, duration_s: 0.0, ..f }.periods(p6), 5989..5990);
}

/// Issue 27: a fault at `at_s = 3.0005` fired in period 3000 for four kinds and
/// 3001 for the others. Every query now reads the same compiled window.
#[test]
fn every_kind_acts_from_the_same_period() {
    let at = |kind, signal| Fault { delay_s: 0.0, signal, ..Fault::new(kind, 3.0005, 0.0) };
    let faults = [
        at(FaultKind::DropCommand, None),
        Fault { delay_s: 2e-4, ..at(FaultKind::LateCommand, None) },
        Fault { duration_s: 0.05, ..at(FaultKind::Stall, None) },
        at(FaultKind::KillFirmware, None),
        at(FaultKind::StuckSensor, Some(Signal::Theta1)),
        at(FaultKind::NanSensor, Some(Signal::FN)),
        at(FaultKind::OutOfRange, Some(Signal::Belt)),
        at(FaultKind::SpiError, Some(Signal::Elbow)),
        at(FaultKind::MissingConversion, None),
        at(FaultKind::DriverFault, None),
    ];
    let plan = FaultPlan::new(&faults, Period::MILLISECOND);
    let first = |acts: &dyn Fn(u64) -> bool| (2990..3010).find(|&k| acts(k));
    assert_eq!(first(&|k| plan.drops_command(k)), Some(3001));
    assert_eq!(first(&|k| plan.command_delay(k) == Duration::from_us(200)), Some(3001));
    assert_eq!(first(&|k| plan.stall_starting(k) == Some(0.05)), Some(3001));
    assert_eq!(first(&|k| plan.kills_firmware_at(k)), Some(3001));
    for kind in [FaultKind::StuckSensor, FaultKind::NanSensor, FaultKind::OutOfRange] {
        assert_eq!(first(&|k| plan.sensor_faults(k).any(|(f, _)| f == kind)), Some(3001), "{kind:?}");
    }
    for kind in [FaultKind::SpiError, FaultKind::MissingConversion, FaultKind::DriverFault, FaultKind::StuckSensor] {
        assert_eq!(first(&|k| plan.board_faults(k).any(|(f, _)| f == kind)), Some(3001), "{kind:?}");
    }
    // One period each (duration 0), the stall's and kill's at their first only.
    assert!(!plan.drops_command(3002) && plan.stall_starting(3002).is_none() && !plan.kills_firmware_at(3002));
}

#[test]
fn checks_name_the_problem() {
    let f = Fault { delay_s: 0.0, signal: None, ..Fault::new(FaultKind::StuckSensor, 1.0, 1.0) };
    assert!(f.check().unwrap_err().contains("signal"));
    let f = Fault { delay_s: f64::NAN, signal: None, ..Fault::new(FaultKind::LateCommand, 1.0, 0.0) };
    assert!(f.check().unwrap_err().contains("delay_s"));
    // Regression (fuzzing): a fault that does not use its delay still gets a sane one.
    for delay_s in [f64::NAN, f64::INFINITY, -1.0, 10.0] {
        let f = Fault { delay_s, signal: Some(Signal::FN), ..Fault::new(FaultKind::StuckSensor, 1.0, 0.0) };
        assert!(f.check().unwrap_err().contains("delay_s"), "{delay_s}");
    }
    let f = Fault { delay_s: 0.0, signal: Some(Signal::FN), ..Fault::new(FaultKind::StuckSensor, 1.0, 0.0) };
    assert_eq!(f.check(), Ok(()));
}

/// Each link refuses exactly the faults it cannot inject, in one table: the
/// firmware in its own process takes every wire and process fault; QEMU can be
/// killed but not stalled; in-process and a board behind a serial port take
/// neither; only the board twin takes the bus faults, and it refuses the
/// wire-level frame's faults, the late step and the process faults.
#[test]
fn links_refuse_exactly_what_they_cannot_inject() {
    use FaultKind::*;
    let all = [
        LateCommand,
        DropCommand,
        Stall,
        KillFirmware,
        StuckSensor,
        NanSensor,
        OutOfRange,
        SpiError,
        ParityError,
        MagnetLost,
        MissingConversion,
        DriverFault,
        DmaTransferError,
        DmaFifoError,
        DmaDirectModeError,
        DmaLateTransfer,
        StuckChipSelect,
    ];
    // (The sensors' faults of issue 80 and `board`: their own test below.)
    let fault = |kind| Fault { delay_s: 1e-3, signal: None, ..Fault::new(kind, 1.0, 0.5) };
    for link in [LinkKind::InProcess, LinkKind::Ipc, LinkKind::PilQemu, LinkKind::PilSerial, LinkKind::Twin, LinkKind::Emulator] {
        for kind in all {
            let refused = link.check(&[fault(kind)]).is_err();
            let process_fault = matches!(kind, Stall | KillFirmware);
            let bus = kind.is_bus_fault();
            let expected = match link {
                LinkKind::Ipc => bus,
                LinkKind::PilQemu => kind == Stall || bus,
                LinkKind::InProcess | LinkKind::PilSerial => process_fault || bus,
                LinkKind::Twin | LinkKind::Emulator => process_fault || matches!(kind, LateCommand | NanSensor | OutOfRange),
            };
            assert_eq!(refused, expected, "{link:?} {kind:?}");
        }
    }
    let e = LinkKind::InProcess.check(&[fault(Stall)]).unwrap_err().to_string();
    assert!(e.contains("Stall") && e.contains("--in-process"), "{e}");
    let e = LinkKind::InProcess.check(&[fault(MagnetLost)]).unwrap_err().to_string();
    assert!(e.contains("--link twin"), "{e}");
    let e = LinkKind::Twin.check(&[fault(NanSensor)]).unwrap_err().to_string();
    assert!(e.contains("spi_error") && e.contains("stuck_sensor") && e.contains("dma_transfer_error"), "{e}");
    // The acquisition's faults are the boards' (the twin's and the emulated
    // board's, issue 66), refused by name elsewhere with where to run them.
    for kind in [DmaTransferError, DmaFifoError, DmaDirectModeError, DmaLateTransfer, StuckChipSelect] {
        assert!(kind.is_bus_fault() && kind.is_acquisition_fault(), "{kind:?}");
        for link in [LinkKind::InProcess, LinkKind::Ipc, LinkKind::PilQemu, LinkKind::PilSerial] {
            let e = link.check(&[fault(kind)]).unwrap_err().to_string();
            assert!(e.contains(&format!("{kind:?}")) && e.contains("--link twin") && e.contains("--link emulator"), "{link:?}: {e}");
        }
    }
    assert!(![SpiError, DriverFault, StuckSensor].iter().any(|k| k.is_acquisition_fault()));
}

/// The acquisition's faults, from a scenario's text: the DMA stream faults take
/// no `signal` (the streams carry both encoders' frames), a stuck chip select
/// takes the encoder's (theta1 or elbow); each is refused otherwise, saying why.
#[test]
fn acquisition_faults_parse_and_check_their_signal() {
    for (kind, name) in [
        (FaultKind::DmaTransferError, "dma_transfer_error"),
        (FaultKind::DmaFifoError, "dma_fifo_error"),
        (FaultKind::DmaDirectModeError, "dma_direct_mode_error"),
        (FaultKind::DmaLateTransfer, "dma_late_transfer"),
        (FaultKind::StuckChipSelect, "stuck_chip_select"),
    ] {
        let parsed: Fault = toml::from_str(&format!("kind = \"{name}\"\nat_s = 1.0\n")).unwrap();
        assert_eq!(parsed.kind, kind);
        let f = Fault { delay_s: 0.0, signal: None, ..Fault::new(kind, 1.0, 0.01) };
        let with = |signal| Fault { signal: Some(signal), ..f };
        if kind == FaultKind::StuckChipSelect {
            assert!(f.check().unwrap_err().contains("theta1 or elbow"), "{name}");
            assert!(with(Signal::FN).check().unwrap_err().contains("theta1 or elbow"), "{name}");
            assert_eq!(with(Signal::Theta1).check(), Ok(()));
            assert_eq!(with(Signal::Elbow).check(), Ok(()));
        } else {
            assert_eq!(f.check(), Ok(()), "{name}");
            let e = with(Signal::Theta1).check().unwrap_err();
            assert!(e.contains("take no `signal`") && e.contains(name), "{name}: {e}");
        }
    }
    // Every period of the window, as the board's faults.
    let f = Fault { delay_s: 0.0, signal: None, ..Fault::new(FaultKind::DmaLateTransfer, 0.5, 0.003) };
    let plan = FaultPlan::new(&[f], Period::MILLISECOND);
    let acts: Vec<u64> = (495..510).filter(|&k| plan.board_faults(k).any(|(kind, _)| kind == FaultKind::DmaLateTransfer)).collect();
    assert_eq!(acts, vec![500, 501, 502]);
}

fn soak_spec(seed: u64) -> RandomSchedule {
    RandomSchedule {
        seed,
        kinds: RandomSchedule::survivable_ipc_kinds(),
        count: 600,
        from_s: 3.0,
        to_s: 600.0,
        ts: 1e-3,
        max_in_a_row: 2,
        max_window: 20,
        command_timeout_s: 0.25,
        max_stall_timeouts: 2,
    }
}

/// The soak schedule: reproducible from its seed, every survivable iceoryx2
/// kind drawn, windows in whole periods inside the span, apart, and within
/// the bounds that keep the firmware out of its safe state; a scenario accepts it.
#[test]
fn random_schedules_are_seeded_disjoint_and_bounded() {
    use FaultKind::*;
    let spec = soak_spec(11);
    let a = random_schedule(&spec).unwrap();
    assert_eq!(a, random_schedule(&spec).unwrap(), "same seed, same schedule");
    assert_ne!(a, random_schedule(&soak_spec(12)).unwrap(), "another seed, another schedule");
    assert_eq!(a.len(), 600);
    assert_eq!(RandomSchedule::survivable_ipc_kinds(), [LateCommand, DropCommand, StuckSensor, NanSensor, OutOfRange, Stall]);
    for kind in RandomSchedule::survivable_ipc_kinds() {
        assert!(a.iter().filter(|f| f.kind == kind).count() >= 60, "{kind:?} drawn about 1/6 of the time");
    }
    LinkKind::Ipc.check(&a).unwrap();
    let ts = spec.ts;
    let mut end_prev = 0u64;
    let (mut late_past, mut late_on_time, mut stall_n) = (0, 0, [0; 3]);
    for f in &a {
        f.check().unwrap();
        let k0 = (f.at_s / ts).round() as u64;
        assert!((f.at_s - k0 as f64 * ts).abs() < 1e-12, "{f:?} starts on a sample");
        assert!(f.at_s >= 3.0 && k0 >= end_prev + 3, "{f:?}: at least two clean periods after the previous window");
        let n = if f.kind == Stall { 1 } else { (f.duration_s / ts).round() as u64 };
        assert!(n >= 1 && (f.duration_s - n as f64 * ts).abs() < 1e-12 || f.kind == Stall, "{f:?} lasts whole periods");
        let reach = match f.kind {
            LateCommand if f.delay_s >= ts => {
                late_past += 1;
                assert!(n <= 2 && f.delay_s <= 3.0 * ts, "{f:?}");
                n
            }
            LateCommand => {
                late_on_time += 1;
                assert!(n <= 20 && f.delay_s > 0.0, "{f:?}");
                n
            }
            NanSensor | OutOfRange => {
                assert!(n <= 2 && f.signal.is_some(), "{f:?}");
                n + 1
            }
            Stall => {
                let m = f.duration_s / 0.25 - 0.5;
                assert!((m - m.round()).abs() < 1e-9 && (0.0..=2.0).contains(&m), "{f:?}: (n + 1/2) timeouts");
                stall_n[m.round() as usize] += 1;
                m.round() as u64 + 1
            }
            DropCommand | StuckSensor => {
                assert!(n <= 20 && (f.kind == DropCommand) != f.signal.is_some(), "{f:?}");
                n
            }
            KillFirmware | SpiError | ParityError | MagnetLost | MissingConversion | DriverFault | DmaTransferError | DmaFifoError
            | DmaDirectModeError | DmaLateTransfer | StuckChipSelect | EncoderSpike | LoadCellDrift | BeltGain | Board => unreachable!(),
        };
        end_prev = k0 + reach - 1;
        assert!(((end_prev + 3) as f64) * ts <= 600.0 + 1e-9, "{f:?} ends inside the span");
    }
    assert!(late_past > 20 && late_on_time > 20, "both kinds of lateness: {late_past}, {late_on_time}");
    assert!(stall_n.iter().all(|&c| c > 5), "stalls of 0, 1 and 2 timeouts: {stall_n:?}");
    let mut s = crate::scenario::Scenario::default_scenario();
    s.timing.duration_s = 600.0;
    s.faults = a;
    s.validate().unwrap();
}

#[test]
fn random_schedules_refuse_what_cannot_fit() {
    let ok = soak_spec(1);
    let cases = [
        (RandomSchedule { kinds: vec![], ..ok.clone() }, "no fault kinds"),
        (RandomSchedule { kinds: vec![FaultKind::KillFirmware], ..ok.clone() }, "kill_firmware"),
        (RandomSchedule { count: 1001, ..ok.clone() }, "count"),
        (RandomSchedule { count: 0, ..ok.clone() }, "count"),
        (RandomSchedule { to_s: 2.0, ..ok.clone() }, "span"),
        (RandomSchedule { ts: f64::NAN, ..ok.clone() }, "ts"),
        (RandomSchedule { max_window: 0, ..ok.clone() }, "max_window"),
        (RandomSchedule { to_s: 12.0, ..ok.clone() }, "periods each"),
        (RandomSchedule { command_timeout_s: 30.0, ..ok.clone() }, "stall"),
        (RandomSchedule { max_stall_timeouts: 3, ..ok.clone() }, "max_stall_timeouts"),
    ];
    for (spec, word) in cases {
        let e = random_schedule(&spec).unwrap_err();
        assert!(e.contains(word), "{word}: {e}");
    }
}

/// The soak's setting: stalls drawn to time out at most `max_stall_timeouts`
/// periods (1 of the limit's 2), so that one more from a late wake stays short of
/// the safe state; the other kinds keep their bounds.
#[test]
fn stalls_stay_within_max_stall_timeouts() {
    let spec = RandomSchedule { max_stall_timeouts: 1, ..soak_spec(7) };
    let faults = random_schedule(&spec).unwrap();
    let stalls: Vec<f64> = faults.iter().filter(|f| f.kind == FaultKind::Stall).map(|f| f.duration_s / 0.25 - 0.5).collect();
    assert!(stalls.len() > 20, "{}", stalls.len());
    assert!(stalls.iter().all(|m| (m - m.round()).abs() < 1e-9 && (0.0..=1.0).contains(m)), "{stalls:?}");
    assert!(stalls.contains(&0.0) && stalls.contains(&1.0), "both lengths drawn");
    let bad = faults.iter().filter(|f| matches!(f.kind, FaultKind::NanSensor | FaultKind::OutOfRange));
    assert!(bad.map(|f| (f.duration_s / 1e-3).round() as u32).max() == Some(2), "bad frames still up to max_in_a_row");
}

/// The sensor faults of a real arm (issue 80) and the board's change mid-run,
/// from a scenario's text: each key belongs to its kind, in its range, refused
/// by name otherwise; an encoder spike's window is its periods; the links that
/// make them take them, the others refuse them with where to run them.
#[test]
fn spikes_drifts_belt_gains_and_board_changes_are_checked_and_refused_where_not_made() {
    let parse = |body: &str| -> Result<Fault, String> {
        let f: Fault = toml::from_str(&format!("at_s = 0.5\n{body}\n")).map_err(|e| e.to_string())?;
        f.check().map(|()| f)
    };
    let spike = parse("kind = \"encoder_spike\"\nsignal = \"elbow\"\ncounts = -40\nperiods = 3").unwrap();
    assert_eq!(spike.periods(Period::MILLISECOND), 500..503, "the window is its periods");
    let plan = FaultPlan::new(&[spike], Period::MILLISECOND);
    assert_eq!((plan.spike_counts(Signal::Elbow, 502), plan.spike_counts(Signal::Elbow, 503)), (-40, 0));
    assert_eq!(plan.spike_counts(Signal::Theta1, 501), 0);
    parse("kind = \"load_cell_drift\"\nsignal = \"f_t\"\nrate_n_per_s = -0.05\nduration_s = 1.0").unwrap();
    parse("kind = \"belt_gain\"\ngain = -1.0\nduration_s = 1.0").unwrap();
    parse("kind = \"board\"\nduration_s = 1.0\n[board.motor2]\nfull_scale_nm = 1.5").unwrap();
    for (body, word) in [
        ("kind = \"encoder_spike\"\nsignal = \"theta1\"\ncounts = 0\nperiods = 1", "counts = 0"),
        ("kind = \"encoder_spike\"\nsignal = \"theta1\"\ncounts = 101\nperiods = 1", "counts = 101"),
        ("kind = \"encoder_spike\"\nsignal = \"theta1\"\ncounts = 5\nperiods = 6", "periods = 6"),
        ("kind = \"encoder_spike\"\nsignal = \"theta1\"\ncounts = 5", "needs `periods`"),
        ("kind = \"encoder_spike\"\nsignal = \"f_n\"\ncounts = 5\nperiods = 1", "theta1 or elbow"),
        ("kind = \"encoder_spike\"\nsignal = \"elbow\"\ncounts = 5\nperiods = 1\nduration_s = 0.1", "leave duration_s out"),
        ("kind = \"load_cell_drift\"\nsignal = \"f_n\"\nrate_n_per_s = 0.6", "rate_n_per_s = 0.6"),
        ("kind = \"load_cell_drift\"\nsignal = \"f_n\"\nrate_n_per_s = nan", "rate_n_per_s = NaN"),
        ("kind = \"load_cell_drift\"\nsignal = \"belt\"\nrate_n_per_s = 0.1", "f_t or f_n"),
        ("kind = \"load_cell_drift\"\nsignal = \"f_t\"", "needs `rate_n_per_s`"),
        ("kind = \"belt_gain\"\ngain = 0.0", "gain = 0"),
        ("kind = \"belt_gain\"\ngain = inf", "gain = inf"),
        ("kind = \"belt_gain\"\nsignal = \"theta1\"\ngain = 2.0", "`signal` belt or none"),
        ("kind = \"stuck_sensor\"\nsignal = \"belt\"\ngain = 2.0", "`gain` is a key of belt_gain faults only"),
        ("kind = \"drop_command\"\ncounts = 2", "`counts` is a key of encoder_spike faults only"),
        ("kind = \"board\"", "needs `board`"),
        ("kind = \"board\"\n[board]\npwm_max_duty = 1", "board.pwm_max_duty"),
        ("kind = \"board\"\n[board.motor1]\ntorque = 1", "unknown field"),
    ] {
        let e = parse(body).unwrap_err();
        assert!(e.contains(word), "{body}: {e}");
    }
    use FaultKind::*;
    let fault = |kind| Fault::new(kind, 1.0, 0.5);
    for kind in [EncoderSpike, LoadCellDrift, BeltGain] {
        for link in [LinkKind::InProcess, LinkKind::Twin, LinkKind::Emulator] {
            link.check(&[fault(kind)]).unwrap();
        }
        for link in [LinkKind::Ipc, LinkKind::PilQemu, LinkKind::PilSerial] {
            let e = link.check(&[fault(kind)]).unwrap_err().to_string();
            assert!(e.contains("--in-process") && e.contains("--link twin"), "{link:?} {kind:?}: {e}");
        }
    }
    for link in [LinkKind::InProcess, LinkKind::Ipc, LinkKind::PilQemu, LinkKind::PilSerial] {
        let e = link.check(&[fault(Board)]).unwrap_err().to_string();
        assert!(e.contains("physical truth") && e.contains("--link emulator"), "{link:?}: {e}");
    }
    LinkKind::Twin.check(&[fault(Board)]).unwrap();
}
