//! End-to-end: the arm in Foxglove (issue 55). A run's and a simulation's
//! `trace.mcap` carry `/tf`, `/scene` and `/log` in Foxglove's own schemas;
//! every message checks against the schema its channel carries, the frames put
//! the tip where the trace's `/contact` does at the same time, the log holds
//! the events. `--live` serves the same channels over the Foxglove WebSocket
//! protocol to a client while the run goes, and the run's files are the same
//! bytes with a viewer as without.

use std::{
    collections::BTreeMap,
    io::{BufRead, BufReader},
    path::Path,
    process::{Command, Stdio},
    time::{Duration, Instant},
};

use arm_view::validate::Schema;
use foxglove::messages::{FrameTransforms, Log};
use prost::Message as _;

fn sil_host() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sil-host"))
}

/// What a `trace.mcap` holds on its Foxglove channels.
struct Checked {
    /// Messages per topic.
    counts: BTreeMap<String, usize>,
    /// The log's lines.
    log: Vec<Log>,
    /// `/tf` messages whose tip was compared with `/contact`.
    compared: usize,
}

/// Reads `path`: every message (the tables' and the view's, all protobuf)
/// checked against its channel's schema, every `/tf` tip against the trace's
/// `z_t`, `z_n` at the same log time (the table as `read_mcap` gives it).
fn check_file(path: &Path) -> Checked {
    let bytes = std::fs::read(path).unwrap();
    let tables = tables::mcap::read_mcap(path).unwrap();
    let trace = &tables.iter().find(|(n, _)| n == "trace").unwrap().1;
    let column = |name: &str| match trace.columns.iter().find(|(n, _)| n == name) {
        Some((_, tables::Column::F64(v))) => v.clone(),
        other => panic!("{name}: {other:?}"),
    };
    let contact: BTreeMap<u64, (f64, f64)> = column("t")
        .iter()
        .zip(column("z_t"))
        .zip(column("z_n"))
        .map(|((t, z_t), z_n)| (tables::mcap::log_time_ns(*t), (z_t, z_n)))
        .collect();
    let mut tips: Vec<(u64, [f64; 3])> = Vec::new();
    let mut counts = BTreeMap::new();
    let mut log = Vec::new();
    let mut schemas: BTreeMap<u16, Schema> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        *counts.entry(m.channel.topic.clone()).or_insert(0) += 1;
        let schema = m.channel.schema.as_ref().unwrap();
        assert_eq!((schema.encoding.as_str(), m.channel.message_encoding.as_str()), ("protobuf", "protobuf"), "{}", m.channel.topic);
        {
            let s = schemas.entry(m.channel.id).or_insert_with(|| Schema::parse(&schema.data).unwrap());
            s.check(&schema.name, &m.data).unwrap_or_else(|e| panic!("{} at {} ns: {e}", m.channel.topic, m.log_time));
        }
        match m.channel.topic.as_str() {
            "/tf" => {
                tips.push((m.log_time, arm_view::geometry::origin_in_world(&FrameTransforms::decode(&*m.data).unwrap(), "tip").unwrap()))
            }
            "/log" => log.push(Log::decode(&*m.data).unwrap()),
            _ => {}
        }
    }
    for (t, tip) in &tips {
        let (z_t, z_n) = contact[t];
        assert!(
            (tip[0] - z_t).abs() < 1e-9 && tip[1].abs() < 1e-12 && (tip[2] - z_n).abs() < 1e-9,
            "at {t} ns: tip {tip:?}, trace ({z_t}, {z_n})"
        );
    }
    Checked { counts, log, compared: tips.len() }
}

/// A closed-loop run's trace.mcap: a frame and a scene every 10 ms of its 1 ms
/// periods, each valid against Foxglove's schema; the tip of the frames is the
/// trace's; the log starts with the control law, then the contact mode.
#[test]
fn a_runs_trace_mcap_shows_the_arm_in_foxglove_schemas() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let s = sil_host().args(["run", "--in-process", "--duration", "1", "--format", "mcap", "--json", "--out"]).arg(&out).output().unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let c = check_file(&out.join("trace.mcap"));
    assert_eq!(c.counts["/state"], 1000, "{:?}", c.counts);
    assert_eq!((c.counts["/tf"], c.counts["/scene"]), (100, 100), "a frame every 10 ms: {:?}", c.counts);
    assert_eq!(c.compared, 100);
    // The control law first (issue 84), then the start's contact mode.
    assert_eq!(c.log[0].message, "control law: hybrid");
    assert!(c.log[1].message.starts_with("start: contact mode sliding"), "{:?}", c.log[1].message);
    // The file's `painleve.run` metadata record and summary.json say the same words.
    let bytes = std::fs::read(out.join("trace.mcap")).unwrap();
    let run: Vec<_> = mcap::read::LinearReader::new(&bytes)
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            mcap::records::Record::Metadata(m) if m.name == "painleve.run" => Some(m.metadata),
            _ => None,
        })
        .collect();
    assert_eq!(run, [BTreeMap::from([("law".to_string(), "hybrid".to_string())])]);
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["law"], "hybrid");
}

/// A simulation's trace.mcap: the open-loop bounce from x0a (the Painlevé
/// paradox: an impact without collision, then touchdowns), its default 10 s; its
/// log holds one line per event of events.csv, in order, at the events' times:
/// every touchdown among them (issue 69: as many as the page lists).
#[test]
fn a_simulations_log_holds_its_events() {
    let dir = tempfile::tempdir().unwrap();
    let (mcap, csv) = (dir.path().join("mcap"), dir.path().join("csv"));
    for (out, format) in [(&mcap, "mcap"), (&csv, "csv")] {
        let s = sil_host().args(["simulate", "--x0", "a", "--format", format, "--json", "--out"]).arg(out).output().unwrap();
        assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    }
    let c = check_file(&mcap.join("trace.mcap"));
    let events = std::fs::read_to_string(csv.join("events.csv")).unwrap();
    let kinds: Vec<&str> = events.lines().skip(1).map(|l| l.split(',').nth(1).unwrap()).collect();
    assert!(kinds.contains(&"impact_without_collision") && kinds.contains(&"touchdown"), "the bounce: {kinds:?}");
    assert_eq!(c.log.len(), kinds.len());
    let touchdowns = kinds.iter().filter(|k| **k == "touchdown").count();
    assert!(touchdowns >= 20, "the whole bounce: {touchdowns} touchdowns");
    assert_eq!(c.log.iter().filter(|l| l.message.starts_with("touchdown:")).count(), touchdowns, "every touchdown is in /log");
    for (line, kind) in c.log.iter().zip(&kinds) {
        assert!(line.message.starts_with(&format!("{kind}:")), "{} against {kind}", line.message);
    }
    assert_eq!(c.counts["/tf"], 1001, "samples from 0 to 10 s, a frame every 10 ms");
}

/// Reads the `ws://` address the run prints on stderr (waiting at most 30 s).
fn live_address(stderr: impl std::io::Read + Send + 'static) -> (String, std::sync::mpsc::Receiver<String>) {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let line = rx.recv_timeout(left).expect("sil-host printed no live address within 30 s");
        if let Some(at) = line.split_whitespace().find(|w| w.starts_with("ws://")) {
            return (at.to_string(), rx);
        }
    }
}

/// `run --live`: a WebSocket client (protocol `foxglove.sdk.v1`) is told the
/// server's channels (the file's seven, with their schemas), subscribes to
/// `/tf` and `/log` (the run waits for it, `--live-wait`) and receives
/// messages that check against Foxglove's schemas, the log's first line among
/// them; the run's trace.mcap is the same bytes as a run without a viewer.
#[test]
fn a_live_run_streams_the_files_channels_and_leaves_the_files_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let (live_out, plain_out) = (dir.path().join("live"), dir.path().join("plain"));
    // 2 s of simulated time at 2 simulated s per s: about 1 s of wall time.
    let mut child = sil_host()
        .args([
            "run",
            "--in-process",
            "--duration",
            "2",
            "--format",
            "mcap",
            "--json",
            "--live",
            "127.0.0.1:0",
            "--live-rate",
            "2",
            "--live-wait",
            "60",
            "--out",
        ])
        .arg(&live_out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (addr, _rest) = live_address(child.stderr.take().unwrap());
    let mut request = tungstenite::client::IntoClientRequest::into_client_request(addr.as_str()).unwrap();
    request.headers_mut().insert("Sec-WebSocket-Protocol", "foxglove.sdk.v1".parse().unwrap());
    let (mut ws, response) = tungstenite::connect(request).expect("the live server accepts a client");
    assert_eq!(response.headers()["Sec-WebSocket-Protocol"], "foxglove.sdk.v1");

    let mut channels: BTreeMap<u64, (String, String, String)> = BTreeMap::new();
    let mut subscribed = BTreeMap::new();
    let mut received: BTreeMap<String, usize> = BTreeMap::new();
    let deadline = Instant::now() + Duration::from_secs(60);
    let enough =
        |r: &BTreeMap<String, usize>| ["/tf", "/wire/frame"].iter().all(|k| r.get(*k).copied().unwrap_or(0) >= 5) && r.contains_key("/log");
    while !enough(&received) {
        assert!(Instant::now() < deadline, "no /tf and /log messages within 60 s: {received:?}, channels {channels:?}");
        match ws.read().expect("the server keeps the connection while the run goes") {
            tungstenite::Message::Text(text) => {
                let v: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
                if v["op"] == "advertise" {
                    let mut subscriptions = Vec::new();
                    for c in v["channels"].as_array().unwrap() {
                        let id = c["id"].as_u64().unwrap();
                        let topic = c["topic"].as_str().unwrap().to_string();
                        let schema = c["schema"].as_str().unwrap_or_default().to_string();
                        channels.insert(id, (topic.clone(), c["schemaName"].as_str().unwrap().to_string(), schema));
                        if topic == "/tf" || topic == "/log" || topic == "/wire/frame" {
                            let sub = subscribed.len() as u64 + 1;
                            subscribed.insert(sub, id);
                            subscriptions.push(serde_json::json!({ "id": sub, "channelId": id }));
                        }
                    }
                    // One subscribe for both: the run waits for it (--live-wait).
                    let msg = serde_json::json!({ "op": "subscribe", "subscriptions": subscriptions });
                    ws.send(tungstenite::Message::Text(msg.to_string().into())).unwrap();
                }
            }
            tungstenite::Message::Binary(b) if b.first() == Some(&1) => {
                // Message data: op 1, subscription id (u32 LE), log time (u64 LE), payload.
                let sub = u64::from(u32::from_le_bytes(b[1..5].try_into().unwrap()));
                let (topic, schema_name, _) = &channels[&subscribed[&sub]];
                let payload = &b[13..];
                let (_, _, advertised) = &channels[&subscribed[&sub]];
                // Every message checks against the schema its channel advertised (the
                // frames' own, `painleve.WireFrame`; Foxglove's for /tf and /log).
                let parsed =
                    Schema::parse(&base64::Engine::decode(&base64::engine::general_purpose::STANDARD, advertised).unwrap()).unwrap();
                parsed.check(schema_name, payload).unwrap_or_else(|e| panic!("{topic}: {e}"));
                *received.entry(topic.clone()).or_insert(0) += 1;
            }
            _ => {}
        }
    }
    let mut topics: Vec<&str> = channels.values().map(|c| c.0.as_str()).collect();
    topics.sort_unstable();
    drop(ws);
    let status = child.wait().unwrap();
    assert!(status.success());
    // The file's channels, every one (the frames' `/wire/*` among them).
    let bytes = std::fs::read(live_out.join("trace.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let mut in_file: Vec<&str> = summary.channels.values().map(|c| c.topic.as_str()).collect();
    in_file.sort_unstable();
    assert_eq!(topics, in_file);
    assert_eq!(topics.len(), 11, "{topics:?}");

    let s = sil_host()
        .args(["run", "--in-process", "--duration", "2", "--format", "mcap", "--json", "--out"])
        .arg(&plain_out)
        .output()
        .unwrap();
    assert!(s.status.success());
    assert!(
        std::fs::read(live_out.join("trace.mcap")).unwrap() == std::fs::read(plain_out.join("trace.mcap")).unwrap(),
        "a viewer changes no byte of trace.mcap"
    );
}

/// `--live` on an address in use is refused (exit 2) before anything is written.
#[test]
fn a_live_address_in_use_is_refused_with_nothing_written() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let s = sil_host().args(["run", "--in-process", "--duration", "0.1", "--live", &addr, "--out"]).arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&s.stderr);
    assert_eq!(s.status.code(), Some(2), "{err}");
    assert!(err.contains("could not start") && err.contains(&addr), "{err}");
    assert!(!out.exists(), "nothing written");
    let s = sil_host().args(["run", "--in-process", "--live", "127.0.0.1:0", "--live-rate", "0", "--out"]).arg(&out).output().unwrap();
    assert_eq!(s.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&s.stderr).contains("--live-rate 0"));
    for backlog in ["15", "1000001"] {
        let s = sil_host()
            .args(["run", "--in-process", "--live", "127.0.0.1:0", "--live-backlog", backlog, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(s.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&s.stderr).contains(&format!("--live-backlog {backlog}: expected")), "{s:?}");
        assert!(!out.exists(), "nothing written");
    }
}

/// How long a run may outlive its end because of a viewer (docs/rig.md "Live"):
/// the viewers get 1 s to take the close, the outputs are written meanwhile.
const AFTER_THE_RUN: Duration = Duration::from_secs(2);

/// A `ws://` client of the live server, connected from a socket whose receive
/// buffer is `rcvbuf` bytes (set before the connection, so the window it
/// advertises is that small: a client that stops reading fills it at once), the
/// WebSocket handshake done with protocol `foxglove.sdk.v1`. It reads the
/// server's advertisement and subscribes to every channel.
fn viewer(ws_url: &str, rcvbuf: Option<i32>) -> tungstenite::WebSocket<std::net::TcpStream> {
    use std::os::fd::FromRawFd;
    let addr: std::net::SocketAddrV4 = ws_url.trim_start_matches("ws://").parse().unwrap();
    // SAFETY: a new socket of our own, options and connect on it; the fd is then owned by the TcpStream.
    let stream = unsafe {
        let fd = libc::socket(libc::AF_INET, libc::SOCK_STREAM | libc::SOCK_CLOEXEC, 0);
        assert!(fd >= 0, "socket: {}", std::io::Error::last_os_error());
        if let Some(size) = rcvbuf {
            let r = libc::setsockopt(
                fd,
                libc::SOL_SOCKET,
                libc::SO_RCVBUF,
                (&raw const size).cast(),
                std::mem::size_of::<i32>() as libc::socklen_t,
            );
            assert_eq!(r, 0, "SO_RCVBUF: {}", std::io::Error::last_os_error());
        }
        let sa = libc::sockaddr_in {
            sin_family: libc::AF_INET as libc::sa_family_t,
            sin_port: addr.port().to_be(),
            sin_addr: libc::in_addr { s_addr: u32::from_ne_bytes(addr.ip().octets()) },
            sin_zero: [0; 8],
        };
        let r = libc::connect(fd, (&raw const sa).cast(), std::mem::size_of::<libc::sockaddr_in>() as libc::socklen_t);
        assert_eq!(r, 0, "connect {addr}: {}", std::io::Error::last_os_error());
        std::net::TcpStream::from_raw_fd(fd)
    };
    let mut request = tungstenite::client::IntoClientRequest::into_client_request(ws_url).unwrap();
    request.headers_mut().insert("Sec-WebSocket-Protocol", "foxglove.sdk.v1".parse().unwrap());
    let (mut ws, _) = tungstenite::client::client(request, stream).expect("the live server accepts a client");
    loop {
        if let tungstenite::Message::Text(text) = ws.read().expect("the advertisement") {
            let v: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
            if v["op"] == "advertise" {
                let subscriptions: Vec<_> = v["channels"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .enumerate()
                    .map(|(i, c)| serde_json::json!({ "id": i + 1, "channelId": c["id"] }))
                    .collect();
                let msg = serde_json::json!({ "op": "subscribe", "subscriptions": subscriptions });
                ws.send(tungstenite::Message::Text(msg.to_string().into())).unwrap();
                return ws;
            }
        }
    }
}

/// A live run (`--live 127.0.0.1:0 --live-wait 60 --live-rate 4`, 20 s of
/// simulated time: about 5 s of wall time) with `args` more, its stderr lines
/// timestamped as they come; the server's address.
fn live_run(out: &Path, args: &[&str]) -> (std::process::Child, String, std::sync::mpsc::Receiver<(Instant, String)>) {
    let mut child = sil_host()
        .args(["run", "--in-process", "--duration", "20", "--json", "--no-page", "--live", "127.0.0.1:0", "--live-rate", "4"])
        .args(["--live-wait", "60"])
        .args(args)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send((Instant::now(), line));
        }
    });
    let deadline = Instant::now() + Duration::from_secs(60);
    while let Ok((_, line)) = rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
        if let Some(at) = line.split_whitespace().find(|w| w.starts_with("ws://")) {
            return (child, at.to_string(), rx);
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("no live address within 60 s");
}

/// The child's exit, waited for on a thread of its own: when it came, and the status.
fn exit_of(mut child: std::process::Child) -> (std::sync::mpsc::Receiver<Instant>, std::thread::JoinHandle<std::process::Output>) {
    let (tx, rx) = std::sync::mpsc::channel();
    let waiter = std::thread::spawn(move || {
        let status = child.wait().unwrap();
        let _ = tx.send(Instant::now());
        let mut stdout = Vec::new();
        std::io::Read::read_to_end(child.stdout.as_mut().unwrap(), &mut stdout).unwrap();
        std::process::Output { status, stdout, stderr: Vec::new() }
    });
    (rx, waiter)
}

/// Reads a live run's stderr lines to their end: when the server said the run had
/// ended ("the run has ended", its viewers told), and every line.
fn the_runs_end(lines: &std::sync::mpsc::Receiver<(Instant, String)>) -> (Instant, Vec<String>) {
    let (mut ended, mut said) = (None, Vec::new());
    while let Ok((at, line)) = lines.recv_timeout(Duration::from_secs(120)) {
        if line.contains("the run has ended") {
            ended = Some(at);
        }
        said.push(line);
    }
    (ended.unwrap_or_else(|| panic!("no line of the run's end: {said:#?}")), said)
}

/// Reads what is left on a viewer that stopped reading, after the run: the
/// connection must end (end of stream or reset) rather than stay open.
fn drain_to_the_end(ws: &mut tungstenite::WebSocket<std::net::TcpStream>) -> usize {
    let s = ws.get_mut();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let (mut buf, mut total) = (vec![0u8; 1 << 16], 0);
    loop {
        match std::io::Read::read(s, &mut buf) {
            Ok(0) => return total,
            Ok(n) => total += n,
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => return total,
            Err(e) => panic!("the dropped viewer's connection did not end: {e}"),
        }
    }
}

/// Issue 66 (4): a viewer that subscribes and then never reads (a 4 KiB
/// receive window: the server's writer to it blocks within the run) no longer
/// holds the process after its run. At the run's end the server closes: a
/// viewer that reads gets the close frame (after the status message, if that
/// came), the stuck one is dropped after 1 s and stderr says so; the process
/// exits within 2 s of the run's end with its summary printed, and the stuck
/// viewer's connection ends.
#[test]
fn a_viewer_that_stopped_reading_is_dropped_and_the_run_exits() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (child, addr, lines) = live_run(&out, &[]);
    let mut stuck = viewer(&addr, Some(4096));
    let mut reader = viewer(&addr, None);
    let reading = std::thread::spawn(move || {
        let (mut messages, mut bytes, mut status, mut close) = (0usize, 0usize, None, None);
        let end = loop {
            match reader.read() {
                Ok(tungstenite::Message::Close(frame)) => close = Some((frame, status.is_some())),
                Ok(tungstenite::Message::Text(t)) if t.contains("\"status\"") => status = Some(t.to_string()),
                Ok(m) => {
                    messages += 1;
                    bytes += m.len();
                }
                Err(e) => break e.to_string(),
            }
        };
        eprintln!("the reading viewer: {bytes} bytes in {messages} messages; its connection ended: {end}");
        (messages, status, close)
    });
    let (exited, waiter) = exit_of(child);
    // The run's end: the server tells its viewers.
    let (ended, said) = the_runs_end(&lines);
    let exited = exited.recv().unwrap();
    let o = waiter.join().unwrap();
    let after = exited.duration_since(ended);
    eprintln!("the run exited {:.3} s after its end (its viewers told), one viewer stuck", after.as_secs_f64());
    assert!(o.status.success(), "{said:#?}");
    assert!(after < AFTER_THE_RUN, "exited {after:?} after the run's end: {said:#?}");
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the summary is printed");
    assert_eq!(summary["status"], "ok");
    assert!(summary["periods"].as_u64().unwrap() >= 20_000, "{summary}");
    assert!(out.join("summary.json").is_file() && out.join("trace.csv").is_file());
    assert!(said.iter().any(|l| l.starts_with("live: dropped 1 of 2 viewer(s)") && l.contains("within 1 s")), "{said:#?}");
    let (messages, status, close) = reading.join().unwrap();
    let (frame, after_status) = close.expect("the reading viewer gets the close frame");
    assert!(messages > 100, "it received the run: {messages} messages");
    if let Some(status) = &status {
        assert!(status.contains("the run has ended") && after_status, "the status, before the close: {status}, {frame:?}");
    }
    eprintln!("the reading viewer: {messages} messages, status {}, close {frame:?}", status.is_some());
    let left = drain_to_the_end(&mut stuck);
    eprintln!("the stuck viewer had {left} bytes in flight when its connection ended");
}

/// Issue 84: a slow viewer (1 ms a message: it falls behind the 11 channels'
/// messages at once) holds neither the run nor its end: the process exits within
/// 2 s of the run's end, as with no viewer; the viewer is dropped or takes the close.
#[test]
fn a_slow_viewer_does_not_hold_the_run_or_its_end() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (child, addr, lines) = live_run(&out, &[]);
    let mut slow = viewer(&addr, None);
    let reading = std::thread::spawn(move || {
        let mut messages = 0usize;
        while slow.read().is_ok() {
            messages += 1;
            std::thread::sleep(Duration::from_millis(1));
        }
        messages
    });
    let started = Instant::now();
    let (exited, waiter) = exit_of(child);
    let (ended, said) = the_runs_end(&lines);
    let exited = exited.recv().unwrap();
    let o = waiter.join().unwrap();
    assert!(o.status.success(), "{said:#?}");
    let (run, after) = (ended.duration_since(started), exited.duration_since(ended));
    eprintln!("a slow viewer: the run took {:.2} s (5 s paced), exited {:.3} s after its end", run.as_secs_f64(), after.as_secs_f64());
    // 20 s of simulated time at --live-rate 4 is 5 s of wall time; the viewer adds none of it.
    assert!(run < Duration::from_secs(5) + AFTER_THE_RUN, "the run took {run:?}: {said:#?}");
    assert!(after < AFTER_THE_RUN, "exited {after:?} after the run's end: {said:#?}");
    let messages = reading.join().unwrap();
    assert!(messages > 100, "it received the run: {messages} messages");
}

/// Issue 66 (4): Ctrl-C (SIGINT) mid-run with a stuck viewer ends the run at
/// once: exit 130, the summary printed (the run stopped early: `failed`,
/// "interrupted"), the outputs written, the viewer cut without the grace.
#[test]
fn ctrl_c_ends_a_live_run_with_a_stuck_viewer_and_prints_the_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (child, addr, lines) = live_run(&out, &[]);
    let pid = child.id() as i32;
    let _stuck = viewer(&addr, Some(4096));
    let (exited, waiter) = exit_of(child);
    // 12 000 of the 20 000 periods streamed (200 B a row of trace.csv at
    // least; 3 s of wall time; its viewer subscribed, --live-wait let the run
    // start): by then the messages sent to the viewer (about 0.57 KB a period:
    // a reading viewer gets 11.4 MB over the run) are more than its connection
    // holds (its 4 KiB window and the server's send buffer: 2.8 MB were in
    // flight when the stuck viewer of the test above was dropped; at most the
    // kernel's 4 MiB by default), so it is stuck.
    let partial = out.join("trace.csv.partial");
    let started = Instant::now();
    while std::fs::metadata(&partial).map_or(0, |m| m.len()) < 12_000 * 200 {
        assert!(started.elapsed() < Duration::from_secs(60), "the run never started");
        std::thread::sleep(Duration::from_millis(5));
    }
    let signalled = Instant::now();
    // SAFETY: kill(2) on our own child's pid (not yet reaped: its waiter holds it).
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let exited = exited.recv_timeout(Duration::from_secs(60)).expect("the run ends on SIGINT");
    let o = waiter.join().unwrap();
    let mut said = Vec::new();
    while let Ok((_, line)) = lines.recv_timeout(Duration::from_secs(30)) {
        said.push(line);
    }
    let took = exited.duration_since(signalled);
    eprintln!("SIGINT: exited {:.3} s after the signal", took.as_secs_f64());
    assert_eq!(o.status.code(), Some(130), "{said:#?}");
    assert!(took < AFTER_THE_RUN, "{took:?}: {said:#?}");
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the summary is printed");
    assert_eq!(summary["status"], "failed");
    assert!(summary["error"].as_str().unwrap().contains("interrupted"), "{summary}");
    let periods = summary["periods"].as_u64().unwrap();
    assert!(periods > 0 && periods < 20_001, "stopped mid-run: {periods}");
    assert!(out.join("summary.json").is_file() && out.join("trace.csv").is_file());
    assert!(said.iter().any(|l| l.contains("stopped by a signal") && l.contains("1 of 1 viewer(s)")), "{said:#?}");
}

/// Issue 69 (5): Ctrl-C while the run waits for a viewer (`--live-wait`) says
/// so, not that the run starts; the run stops after its first period (exit 130,
/// the summary printed: one period, "interrupted").
#[test]
fn ctrl_c_while_waiting_for_a_viewer_says_the_run_stops() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (child, _addr, lines) = live_run(&out, &[]);
    let pid = child.id() as i32;
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut said = Vec::new();
    while !said.iter().any(|l: &String| l.contains("waiting up to")) {
        let (_, line) = lines.recv_timeout(deadline.saturating_duration_since(Instant::now())).expect("the wait is announced");
        said.push(line);
    }
    let (exited, waiter) = exit_of(child);
    // SAFETY: kill(2) on our own child's pid (not yet reaped: its waiter holds it).
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    exited.recv_timeout(Duration::from_secs(60)).expect("the run ends on SIGINT");
    let o = waiter.join().unwrap();
    while let Ok((_, line)) = lines.recv_timeout(Duration::from_secs(30)) {
        said.push(line);
    }
    assert_eq!(o.status.code(), Some(130), "{said:#?}");
    assert!(said.iter().any(|l| l.contains("stopped by a signal while waiting for a viewer")), "{said:#?}");
    assert!(!said.iter().any(|l| l.contains("the run starts")), "{said:#?}");
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the summary is printed");
    assert_eq!(summary["periods"].as_u64(), Some(1), "the first period alone: {summary}");
    assert!(summary["error"].as_str().unwrap().contains("interrupted"), "{summary}");
}

/// Issue 66 (5): an address that is not a loopback one serves the run to the
/// network: stderr warns of it; a loopback one says nothing of the kind.
#[test]
fn a_live_address_off_this_machine_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    for (addr, warned) in [("0.0.0.0:0", true), ("127.0.0.1:0", false)] {
        let o = sil_host()
            .args(["run", "--in-process", "--duration", "0.05", "--no-page", "--live", addr, "--live-rate", "1000", "--out"])
            .arg(dir.path().join(if warned { "any" } else { "loopback" }))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert_eq!(err.contains("warning: live: ws://0.0.0.0:") && err.contains("every network interface"), warned, "{addr}: {err}");
        assert_eq!(err.contains("warning"), warned, "{addr}: {err}");
    }
}

/// Issues 69 (4) and 84: which WebSocket subprotocols `--live` accepts, with a
/// plain client offering each (docs/rig.md "Live", "Which clients connect"): the
/// Foxglove SDK's `foxglove.sdk.v1` and `foxglove.sdk.v1.1` (the newer preferred
/// when both are offered, in any order), and the published spec's
/// `foxglove.websocket.v1` alone (`@foxglove/ws-protocol`'s `FoxgloveClient`,
/// Lichtblick, older apps), answered under that name: such a client is told the
/// channels, subscribes to `/log` and receives its first line, the control law. A
/// client offering no Foxglove protocol is refused with HTTP 400.
#[test]
fn the_live_server_accepts_the_sdks_subprotocols_and_the_published_one() {
    let dir = tempfile::tempdir().unwrap();
    let mut child = sil_host()
        .args(["run", "--in-process", "--duration", "1", "--no-page", "--live", "127.0.0.1:0", "--live-wait", "60", "--out"])
        .arg(dir.path().join("out"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (addr, _rest) = live_address(child.stderr.take().unwrap());
    let offer = |protocols: &str| {
        let mut request = tungstenite::client::IntoClientRequest::into_client_request(addr.as_str()).unwrap();
        request.headers_mut().insert("Sec-WebSocket-Protocol", protocols.parse().unwrap());
        tungstenite::connect(request)
    };
    for (offered, negotiated) in [
        ("foxglove.sdk.v1", "foxglove.sdk.v1"),
        ("foxglove.sdk.v1.1", "foxglove.sdk.v1.1"),
        ("foxglove.sdk.v1, foxglove.sdk.v1.1", "foxglove.sdk.v1.1"),
        ("foxglove.websocket.v1, foxglove.sdk.v1", "foxglove.sdk.v1"),
    ] {
        let (mut ws, response) = offer(offered).unwrap_or_else(|e| panic!("a client offering {offered} connects: {e}"));
        assert_eq!(response.headers()["Sec-WebSocket-Protocol"], negotiated, "offered {offered}");
        let _ = ws.close(None);
    }
    match offer("chat") {
        Err(tungstenite::Error::Http(response)) => assert_eq!(response.status(), 400, "refused with HTTP 400"),
        Err(e) => panic!("a client offering no Foxglove protocol: {e}"),
        Ok(_) => panic!("a client offering no Foxglove protocol connected"),
    }
    // The published protocol alone: the whole exchange a v1 client makes.
    let (mut ws, response) = offer("foxglove.websocket.v1").expect("a client offering only foxglove.websocket.v1 connects");
    assert_eq!(response.headers()["Sec-WebSocket-Protocol"], "foxglove.websocket.v1");
    let deadline = Instant::now() + Duration::from_secs(60);
    let (mut server_info, mut log_channel, mut first_line) = (false, None, None);
    while first_line.is_none() {
        assert!(Instant::now() < deadline, "no /log message within 60 s (serverInfo {server_info}, /log channel {log_channel:?})");
        match ws.read().expect("the server keeps the connection while the run goes") {
            tungstenite::Message::Text(text) => {
                let v: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
                server_info |= v["op"] == "serverInfo";
                if v["op"] == "advertise" {
                    // Inline schemas, as the published spec's advertise has them.
                    let c = v["channels"].as_array().unwrap().iter().find(|c| c["topic"] == "/log").expect("/log advertised");
                    assert!(c["schema"].as_str().is_some_and(|s| !s.is_empty()), "{c}");
                    log_channel = c["id"].as_u64();
                    let msg = serde_json::json!({ "op": "subscribe", "subscriptions": [{ "id": 7, "channelId": log_channel }] });
                    ws.send(tungstenite::Message::Text(msg.to_string().into())).unwrap();
                }
            }
            tungstenite::Message::Binary(b) if b.first() == Some(&1) && b.len() > 13 => {
                assert_eq!(u32::from_le_bytes(b[1..5].try_into().unwrap()), 7, "the subscription's id");
                first_line = Some(Log::decode(&b[13..]).unwrap().message);
            }
            _ => {}
        }
    }
    assert!(server_info, "serverInfo first");
    assert_eq!(first_line.as_deref(), Some("control law: hybrid"));
    let _ = ws.close(None);
    let _ = child.kill();
    let _ = child.wait();
}
