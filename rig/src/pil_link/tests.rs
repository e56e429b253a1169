//! The link over a serial port, against a fake board at the other end of a
//! pseudo-terminal: the handshake through a previous run's leftovers, the
//! cycle unit, and a board that goes silent or a port that hangs up.

use std::{
    cell::Cell,
    fs::File,
    io::{Read, Write},
    os::fd::FromRawFd,
    path::{Path, PathBuf},
    thread::JoinHandle,
    time::{Duration, Instant},
};

use firmware::{
    Firmware, TickClock,
    pil::{self, Downlink, FrameBuffer, MAX_FRAME, Push, StepClock, Uplink},
};
use shared::wire::SensorFrame;

use super::{
    pipe::{Got, Pipe, open_fifo},
    qemu::qemu_opt_value,
    *,
};
use crate::{link::FirmwareLink, period_loop::run_loop, record::RunError, scenario::Scenario, setup::firmware_config, summary::CountUnit};

#[test]
fn the_step_budget_is_five_percent_of_the_period_at_168_mhz() {
    assert_eq!(step_budget(1000.0), STEP_BUDGET_INSTRUCTIONS);
    assert_eq!(step_budget(10_000.0), 840.0);
    assert_eq!(step_budget(250.0), 33_600.0);
}

#[test]
fn counts_are_instructions_under_qemu_and_cycles_on_silicon() {
    let mut c = PilCounts { ticks_per_second: 168_000_000, ..PilCounts::default() };
    assert_eq!(c.unit(), CountUnit::Instructions);
    assert!((c.counts_per_tick() - 1e9 / 168e6).abs() < 1e-12);
    c.clock = StepClock::DwtCycles;
    assert_eq!((c.unit(), c.counts_per_tick()), (CountUnit::Cycles, 1.0));
    assert_eq!(serde_json::to_value(CountUnit::Cycles).unwrap(), "cycles");
    assert_eq!(serde_json::to_value(CountUnit::Instructions).unwrap(), "instructions");
}

fn with_kill_fault() -> Scenario {
    let toml = format!("{}\n[[faults]]\nkind = \"kill_firmware\"\nat_s = 0.3\n", crate::scenario::DEFAULT_TOML);
    Scenario::from_toml(&toml).unwrap()
}

#[test]
fn a_serial_link_refuses_kill_firmware_and_bad_settings_before_touching_the_port() {
    let mut s = with_kill_fault();
    // The device does not exist either: the fault is what is reported.
    match PilLink::start(&crate::setup::RunSetup::new(s.clone()).unwrap(), &PilOptions::serial("/nonexistent/ttyUSB9", DEFAULT_BAUD), None)
    {
        Err(RunError::Unsupported(m)) => assert!(m.contains("kill_firmware") && m.contains("serial port") && !m.contains("QEMU"), "{m}"),
        other => panic!("expected Unsupported, got {other:?}"),
    }
    // Under QEMU the fault is fine.
    assert!(
        check_faults(&s, &PilTarget::Qemu { image: "pil".into(), qemu: "qemu-system-arm".into(), link: QemuLink::Semihosting }).is_ok()
    );
    s.faults.clear();
    let err =
        PilLink::start(&crate::setup::RunSetup::new(s.clone()).unwrap(), &PilOptions::serial("/nonexistent/ttyUSB9", DEFAULT_BAUD), None)
            .unwrap_err()
            .to_string();
    assert!(err.contains("cannot open the serial port /nonexistent/ttyUSB9 at 2000000 baud"), "{err}");
    let err = PilLink::start(&crate::setup::RunSetup::new(s.clone()).unwrap(), &PilOptions::serial("/dev/null", 300), None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("outside 9600..=12000000 baud"), "{err}");
    for bad in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
        let opts = PilOptions { answer_timeout_s: bad, ..PilOptions::serial("/dev/null", DEFAULT_BAUD) };
        let err = PilLink::start(&crate::setup::RunSetup::new(s.clone()).unwrap(), &opts, None).unwrap_err().to_string();
        assert!(err.contains("answer timeout") && err.contains("positive number of seconds"), "{err}");
    }
}

/// A pseudo-terminal: the fake board holds the master, the link opens `path`.
struct Pty {
    master: File,
    /// Held until the link has opened the port: with no slave open, reads of the
    /// master fail (EIO) and the fake board would stop.
    slave: File,
    path: PathBuf,
}

fn pty() -> Pty {
    let (mut master, mut slave) = (-1, -1);
    // SAFETY: openpty only writes the two descriptors; no name buffer, default settings.
    let rc = unsafe { libc::openpty(&mut master, &mut slave, std::ptr::null_mut(), std::ptr::null(), std::ptr::null()) };
    assert_eq!(rc, 0, "openpty: {}", std::io::Error::last_os_error());
    let path = std::fs::read_link(format!("/proc/self/fd/{slave}")).unwrap();
    // SAFETY: two fresh descriptors that nothing else owns.
    let (master, slave) = unsafe { (File::from_raw_fd(master), File::from_raw_fd(slave)) };
    Pty { master, slave, path }
}

/// A tick counter that advances 700 ticks per reading.
struct Counting(Cell<u32>);

impl TickClock for Counting {
    fn ticks(&self) -> u32 {
        let t = self.0.get();
        self.0.set(t.wrapping_add(700));
        t
    }
    fn ticks_per_second(&self) -> u32 {
        168_000_000
    }
}

/// What the fake board does once it has answered `answer` frames.
#[derive(Debug, Clone, Copy)]
enum Then {
    /// It keeps reading but never answers again (a hung board).
    Silent,
    /// It drops its end of the line (a USB adapter pulled out).
    HangUp,
}

/// The fake board's behaviour.
#[derive(Debug, Clone, Copy)]
struct Script {
    protocol: u16,
    /// The digest its Hello says its law's declaration has (`LawSpec::digest`).
    law_digest: u32,
    /// Before its first Hello, it sends what a previous run can leave on the
    /// line: an Answer, a Garbled and a broken frame.
    leftovers: bool,
    /// Right after its first Hello it sends a Garbled, as for a frame damaged
    /// before its USART was up: the link sends the configuration again.
    garbled_after_hello: bool,
    answer: usize,
    then: Then,
}

impl Script {
    /// A board of this protocol running the paper's laws, that answers
    /// `answer` frames and then does `then`, with nothing else on the line.
    fn paper(answer: usize, then: Then) -> Self {
        Self { protocol: pil::PROTOCOL_VERSION, law_digest: PAPER, leftovers: false, garbled_after_hello: false, answer, then }
    }
}

/// What the fake board saw.
#[derive(Debug, Default)]
struct Seen {
    hellos: usize,
    configures: usize,
    frames: usize,
    ended: bool,
}

fn send(to: &mut File, msg: &Uplink) {
    let mut buf = [0u8; MAX_FRAME];
    let _ = to.write_all(pil::encode(msg, &mut buf).unwrap());
}

/// A board speaking the PIL protocol with real firmware steps and DWT-cycle counts.
fn fake_board(mut master: File, script: Script) -> JoinHandle<Seen> {
    std::thread::spawn(move || {
        let clock = Counting(Cell::new(0));
        let mut rx = FrameBuffer::default();
        let mut fw: Option<Firmware<firmware::PaperLaws>> = None;
        let mut seen = Seen::default();
        let mut buf = [0u8; 512];
        loop {
            let n = match master.read(&mut buf) {
                Ok(0) | Err(_) => return seen, // the link closed the port
                Ok(n) => n,
            };
            for &byte in &buf[..n] {
                let Push::Frame(frame) = rx.push(byte) else { continue };
                match pil::decode::<Downlink>(frame) {
                    Err(_) => send(&mut master, &Uplink::Garbled),
                    Ok(Downlink::Hello) => {
                        seen.hellos += 1;
                        if script.leftovers && seen.hellos == 1 {
                            let mut old = Firmware::new(firmware_config(&Scenario::default_scenario())).unwrap();
                            let command = old.step(shared::time::Instant::from_us(0), &SensorFrame::default(), &clock);
                            let telemetry = old.telemetry_message(&command);
                            send(&mut master, &Uplink::Answer { command, telemetry, frame_ticks: 1 });
                            send(&mut master, &Uplink::Garbled);
                            let _ = master.write_all(&[7, 1, 2, 3, 0]);
                        }
                        send(
                            &mut master,
                            &Uplink::Hello {
                                protocol: script.protocol,
                                ticks_per_second: 168_000_000,
                                clock: StepClock::DwtCycles,
                                law_digest: script.law_digest,
                            },
                        );
                        if script.garbled_after_hello && seen.hellos == 1 {
                            send(&mut master, &Uplink::Garbled);
                        }
                    }
                    Ok(Downlink::Configure(cfg)) => {
                        seen.configures += 1;
                        fw = Firmware::new(cfg).ok();
                        send(&mut master, if fw.is_some() { &Uplink::Configured } else { &Uplink::Rejected });
                    }
                    Ok(Downlink::Frame { frame, start_delay_us }) => {
                        if seen.frames == script.answer {
                            match script.then {
                                Then::Silent => continue,
                                Then::HangUp => return seen,
                            }
                        }
                        seen.frames += 1;
                        let Some(f) = fw.as_mut() else { return seen };
                        let command = f.step(
                            frame.sampled_at().saturating_add(shared::time::Duration::from_us(u64::from(start_delay_us))),
                            &frame,
                            &clock,
                        );
                        let telemetry = f.telemetry_message(&command);
                        send(&mut master, &Uplink::Answer { command, telemetry, frame_ticks: 2 * command.step_ticks });
                    }
                    Ok(Downlink::End) => {
                        seen.ended = true;
                        return seen;
                    }
                }
            }
        }
    })
}

fn short(duration_s: f64) -> Scenario {
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = duration_s;
    s
}

/// Starts a link to a fake board with `script`; the board's thread.
fn board_link(setup: &crate::setup::RunSetup, script: Script, answer_timeout_s: f64) -> (Result<PilLink, RunError>, JoinHandle<Seen>) {
    let Pty { master, slave, path } = pty();
    let board = fake_board(master, script);
    let opts = PilOptions { boot_timeout_s: 5.0, answer_timeout_s, ..PilOptions::serial(path, DEFAULT_BAUD) };
    let link = PilLink::start(setup, &opts, None);
    drop(slave);
    (link, board)
}

#[test]
fn a_board_behind_a_serial_port_closes_the_loop_through_a_previous_runs_leftovers() {
    let setup = crate::setup::RunSetup::new(short(0.3)).unwrap();
    let script = Script { leftovers: true, ..Script::paper(usize::MAX, Then::Silent) };
    let (link, board) = board_link(&setup, script, 5.0);
    let mut link = link.unwrap();
    assert_eq!(link.transport(), "pil-serial");
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    assert!(err.is_none(), "{err:?}");
    assert_eq!(records.len(), 300);
    let c = &link.counts;
    assert_eq!((c.unit(), c.clock, c.ticks_per_second), (CountUnit::Cycles, StepClock::DwtCycles, 168_000_000));
    assert_eq!((c.answers, c.step.len(), c.frame.len()), (300, 300, 300));
    assert!(c.step.min().is_some_and(|t| t > 0), "the step measured itself");
    assert!(c.step_ticks.is_empty(), "per-period ticks are kept only when asked");
    assert_eq!(c.step_series.len(), 300);
    // No log and no exit status over a serial port.
    assert!(!link.captures_log() && link.log().is_empty() && link.exit_status().is_none());
    let seen = board.join().unwrap();
    assert!(seen.hellos >= 1 && seen.frames == 300 && seen.ended, "{seen:?}");
}

#[test]
fn a_garbled_answer_during_the_handshake_resends_the_configuration_and_the_run_goes_on() {
    let setup = crate::setup::RunSetup::new(short(0.2)).unwrap();
    let script = Script { garbled_after_hello: true, ..Script::paper(usize::MAX, Then::Silent) };
    let (link, board) = board_link(&setup, script, 5.0);
    let mut link = link.unwrap();
    // The board answers both configurations; the second `Configured` comes
    // before the first answer and must not end the run.
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    assert!(err.is_none(), "{err:?}");
    assert_eq!(records.len(), 200);
    let seen = board.join().unwrap();
    assert_eq!((seen.configures, seen.frames), (2, 200), "{seen:?}");
}

#[test]
fn a_board_that_stops_answering_ends_the_run_after_the_answer_timeout() {
    let setup = crate::setup::RunSetup::new(short(1.0)).unwrap();
    let script = Script::paper(50, Then::Silent);
    let (link, _board) = board_link(&setup, script, 0.3);
    let mut link = link.unwrap();
    let started = Instant::now();
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    // 50 periods and one 0.3 s answer timeout: a bound of 20 s tells a hang from a
    // loaded machine.
    assert!(started.elapsed() < Duration::from_secs(20), "no hang: {:?}", started.elapsed());
    match err {
        Some(RunError::FirmwareLost { k, what, .. }) => {
            assert_eq!(k, 50);
            assert!(what.contains("no answer within 0.3 s") && what.contains("is the board powered"), "{what}");
            assert!(!what.contains("QEMU"), "{what}");
        }
        other => panic!("expected FirmwareLost, got {other:?}"),
    }
    assert_eq!(records.len(), 50);
}

#[test]
fn a_serial_port_that_hangs_up_ends_the_run_with_a_clear_error() {
    let setup = crate::setup::RunSetup::new(short(1.0)).unwrap();
    let script = Script::paper(50, Then::HangUp);
    // An answer timeout of 60 s: noticed in under half of it is noticed by the
    // hang-up, not by the timeout, however loaded the machine is.
    let (link, _board) = board_link(&setup, script, 60.0);
    let mut link = link.unwrap();
    let started = Instant::now();
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    assert!(started.elapsed() < Duration::from_secs(30), "noticed at once, not after the timeout: {:?}", started.elapsed());
    match err {
        Some(RunError::FirmwareLost { k, what, .. }) => {
            assert!((50..=51).contains(&k), "{k}");
            assert!(what.contains("unplugged?") && what.contains("the serial port /dev/pts/"), "{what}");
            assert!(!what.contains("QEMU"), "{what}");
        }
        other => panic!("expected FirmwareLost, got {other:?}"),
    }
    assert!((50..=51).contains(&records.len()));
}

/// The paper's laws' declaration's digest: what their PIL image says in its Hello.
const PAPER: u32 = firmware::LawSpec::PAPER.digest();

/// Issue 70: a board whose image runs another control law than the one the
/// bridge binds the scenario to (the flashed ELF's, or the paper's laws without
/// one) is refused after its Hello, before any configuration goes, naming what
/// to give.
#[test]
fn a_board_running_another_law_than_the_elf_given_is_refused_before_its_configuration() {
    let setup = crate::setup::RunSetup::new(short(0.1)).unwrap();
    let script = Script { law_digest: PAPER ^ 1, ..Script::paper(0, Then::Silent) };
    let (link, board) = board_link(&setup, script, 5.0);
    let err = link.unwrap_err().to_string();
    assert!(err.contains("another control law") && err.contains("give the ELF that was flashed"), "{err}");
    assert_eq!(board.join().unwrap().configures, 0, "nothing configured");
}

#[test]
fn a_board_of_another_protocol_or_no_board_is_refused_with_a_clear_error() {
    let setup = crate::setup::RunSetup::new(short(0.1)).unwrap();
    let script = Script { protocol: 1, ..Script::paper(0, Then::Silent) };
    let err = board_link(&setup, script, 5.0).0.unwrap_err().to_string();
    assert!(err.contains("speaks PIL protocol 1") && err.contains("flash"), "{err}");

    // Nobody at the other end: no Hello within the boot timeout.
    let Pty { master: _master, slave: _slave, path } = pty();
    let opts = PilOptions { boot_timeout_s: 0.5, ..PilOptions::serial(&path, DEFAULT_BAUD) };
    let started = Instant::now();
    let err = PilLink::start(&setup, &opts, None).unwrap_err().to_string();
    assert!(started.elapsed() < Duration::from_secs(20), "the boot timeout ends the wait: {:?}", started.elapsed());
    assert!(err.contains("the image did not say Hello within 0.5 s: nothing from /dev/pts/") && !err.contains("QEMU"), "{err}");
}

#[test]
fn the_fifo_pipe_waits_for_a_booting_image_reads_its_bytes_and_sees_it_close() {
    use std::{fs::OpenOptions, io::Write as _};
    let dir = std::env::temp_dir().join(format!("painleve-fifo-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir(&dir).unwrap();
    let (down_path, up_path) = (dir.join("x.down"), dir.join("x.up"));
    let down = open_fifo(&down_path, true).unwrap();
    let up = open_fifo(&up_path, false).unwrap();
    let mut pipe = Pipe::Fifo { down, up };
    let mut buf = [0u8; 64];
    // No writer yet (QEMU still booting): silence, not the end of the file.
    let t = Instant::now();
    assert!(matches!(pipe.read_within(&mut buf, Duration::from_millis(30)), Ok(Got::Nothing)));
    assert!(t.elapsed() >= Duration::from_millis(25), "the read waited: {:?}", t.elapsed());
    // The image's ends: it reads `down` and writes `up`.
    let mut image_up = OpenOptions::new().write(true).open(&up_path).unwrap();
    let mut image_down = OpenOptions::new().read(true).open(&down_path).unwrap();
    image_up.write_all(&[1, 2, 3, 0]).unwrap();
    match pipe.read_within(&mut buf, Duration::from_secs(5)) {
        Ok(Got::Bytes(4)) => assert_eq!(&buf[..4], &[1, 2, 3, 0]),
        _ => panic!("the image's frame arrives whole"),
    }
    pipe.write_all(&[9, 8, 0], Duration::from_secs(1)).unwrap();
    let mut got = [0u8; 3];
    image_down.read_exact(&mut got).unwrap();
    assert_eq!(got, [9, 8, 0]);
    // The image gone (QEMU exited or killed): the end of the file, at once.
    drop(image_up);
    let t = Instant::now();
    let err = pipe.read_within(&mut buf, Duration::from_secs(60)).err().expect("a closed FIFO is an error");
    assert!(err.contains("QEMU closed its semihosting FIFO"), "{err}");
    assert!(t.elapsed() < Duration::from_secs(30), "the end of the file, not the 60 s wait: {:?}", t.elapsed());
    // A pipe the image never reads fills up: an error, never a hang.
    let big = vec![1u8; 1 << 20];
    let err = pipe.write_all(&big, Duration::from_secs(1)).unwrap_err();
    assert!(err.contains("full"), "{err}");
    assert_eq!(qemu_opt_value(Path::new("/tmp/a,b")).unwrap(), "/tmp/a,,b");
    std::fs::remove_dir_all(&dir).unwrap();
}
