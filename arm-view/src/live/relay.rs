//! The published protocol's name in front of the SDK's server: a TCP relay on the
//! address the user asked for, the Foxglove SDK's WebSocket server behind it on a
//! loopback port of its own.
//!
//! The SDK (0.30) negotiates only its own subprotocols, `foxglove.sdk.v1` and
//! `foxglove.sdk.v1.1`, and answers HTTP 400 to a client that offers the published
//! spec's `foxglove.websocket.v1` alone (`@foxglove/ws-protocol`'s `FoxgloveClient`,
//! Lichtblick, older Foxglove apps, `foxglove_bridge` clients before 3.x). The two
//! v1 protocols are the same messages under two names (Foxglove's stance, foxglove
//! discussion 1131; Lichtblick and Flora accept both names for that reason): so a
//! client that offers `foxglove.websocket.v1` and none of the SDK's names has its
//! upgrade request passed on offering `foxglove.sdk.v1`, and the answer passed back
//! naming `foxglove.websocket.v1`. Every other request, the SDK's own clients' among
//! them, is passed on unchanged. After the handshake the relay copies bytes both ways
//! (the WebSocket frames, untouched) until either side ends, then ends both.
//!
//! The request's and the answer's heads are parsed with `httparse` (hyper's parser),
//! each at most [`HEAD_LIMIT`] bytes and read within [`HEAD_TIMEOUT`]; a head that is
//! malformed, too long or late ends that connection, no other.

use std::{
    io::{self, Read, Write},
    net::{Shutdown, SocketAddr, TcpListener, TcpStream},
    sync::{
        Arc, Mutex, PoisonError,
        atomic::{AtomicBool, AtomicUsize, Ordering},
    },
    thread::JoinHandle,
    time::{Duration, Instant},
};

/// The published spec's subprotocol (github.com/foxglove/ws-protocol, `docs/spec.md`).
pub const PUBLISHED_V1: &str = "foxglove.websocket.v1";
/// The SDK's name for the same protocol.
const SDK_V1: &str = "foxglove.sdk.v1";
/// The SDK's names: a request that offers one of them goes through unchanged.
const SDK_NAMES: [&str; 2] = [SDK_V1, "foxglove.sdk.v1.1"];
/// The longest request or answer head the relay reads, bytes.
const HEAD_LIMIT: usize = 16 * 1024;
/// The longest wait for a head, from the connection's start.
const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// Headers a head may have (`httparse` needs a bound).
const MAX_HEADERS: usize = 64;
/// How often the accept loop looks at its stop flag.
const ACCEPT_POLL: Duration = Duration::from_millis(5);
/// The kernel's buffers on the relay's two sockets of a viewer (its send buffer
/// towards the viewer, its receive buffer from the SDK), bytes: small, so that a
/// viewer that reads slowly backs up into the SDK's own queue for it within about
/// this much more than a direct connection would hold, rather than the megabytes
/// the kernel's autotuning would let the relay hold on its behalf.
const RELAY_BUFFER: usize = 64 * 1024;

/// The relay: its listener's thread and the viewers' connections (kept to be cut
/// at [`Relay::stop`]).
pub struct Relay {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    open: Arc<Mutex<Vec<TcpStream>>>,
    /// Viewers past the handshake whose connection has not ended.
    active: Arc<AtomicUsize>,
    accept: Option<JoinHandle<()>>,
}

impl Relay {
    /// Listens on `listen` (port 0: any free port, [`Relay::addr`] tells which) and
    /// relays every connection to `upstream`, the SDK's server.
    ///
    /// # Errors
    /// The bind's [`io::Error`] (the address in use, not this machine's, ...).
    pub fn start(listen: SocketAddr, upstream: SocketAddr) -> io::Result<Self> {
        let listener = TcpListener::bind(listen)?;
        let addr = listener.local_addr()?;
        listener.set_nonblocking(true)?;
        let stop = Arc::new(AtomicBool::new(false));
        let open = Arc::new(Mutex::new(Vec::new()));
        let active = Arc::new(AtomicUsize::new(0));
        let (s, o, a) = (Arc::clone(&stop), Arc::clone(&open), Arc::clone(&active));
        let accept = std::thread::Builder::new().name("live-relay".into()).spawn(move || accept_loop(&listener, upstream, &s, &o, &a))?;
        Ok(Self { addr, stop, open, active, accept: Some(accept) })
    }

    /// The address the relay listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Stops accepting, waits until every viewer's connection has ended (the SDK's
    /// close passed on and taken), at most until `deadline` or until `stop` is set,
    /// then cuts the connections still open: a viewer that stopped reading would hold
    /// its copy thread, and its socket, forever. Returns how many were cut.
    pub fn finish(&mut self, deadline: Instant, stop: &AtomicBool) -> usize {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.accept.take() {
            let _ = t.join();
        }
        // Polled: the copy threads end on their sockets, not on a signal to this one.
        while self.active.load(Ordering::SeqCst) > 0 && Instant::now() < deadline && !stop.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(10));
        }
        let cut = self.active.load(Ordering::SeqCst);
        for s in self.open.lock().unwrap_or_else(PoisonError::into_inner).drain(..) {
            let _ = s.shutdown(Shutdown::Both);
        }
        cut
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        self.finish(Instant::now(), &AtomicBool::new(true));
    }
}

fn accept_loop(
    listener: &TcpListener,
    upstream: SocketAddr,
    stop: &AtomicBool,
    open: &Arc<Mutex<Vec<TcpStream>>>,
    active: &Arc<AtomicUsize>,
) {
    while !stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((client, _)) => {
                let (open, active) = (Arc::clone(open), Arc::clone(active));
                // A connection the relay cannot serve (no thread) is dropped: the client sees it closed.
                let _ = std::thread::Builder::new().name("live-relay-conn".into()).spawn(move || {
                    let _ = serve(client, upstream, &open, &active);
                });
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => std::thread::sleep(ACCEPT_POLL),
            // A connection reset before it was accepted, too many files open for now, ...: go on.
            Err(_) => std::thread::sleep(ACCEPT_POLL),
        }
    }
}

/// One viewer: the handshake passed on (renamed when needed), then the bytes both ways.
fn serve(client: TcpStream, upstream: SocketAddr, open: &Mutex<Vec<TcpStream>>, active: &AtomicUsize) -> io::Result<()> {
    client.set_nonblocking(false)?;
    client.set_nodelay(true)?;
    socket2::SockRef::from(&client).set_send_buffer_size(RELAY_BUFFER)?;
    client.set_read_timeout(Some(HEAD_TIMEOUT))?;
    let mut client_r = client.try_clone()?;
    let (head, rest) = read_head(&mut client_r)?;
    let (request, renamed) = rewrite_request(&head)?;
    let mut server = connect_small(upstream)?;
    server.set_nodelay(true)?;
    server.set_read_timeout(Some(HEAD_TIMEOUT))?;
    server.write_all(&request)?;
    server.write_all(&rest)?;
    let (answer, rest) = read_head(&mut server)?;
    let answer = if renamed { rewrite_answer(&answer)? } else { answer };
    let mut client_w = client.try_clone()?;
    client_w.write_all(&answer)?;
    client_w.write_all(&rest)?;
    client.set_read_timeout(None)?;
    server.set_read_timeout(None)?;
    open.lock().unwrap_or_else(PoisonError::into_inner).push(client.try_clone()?);
    active.fetch_add(1, Ordering::SeqCst);
    let _ended = Ended(active);
    // Viewer to server on a thread of its own, server to viewer here; either ending ends both.
    let (mut server_w, mut server_r) = (server.try_clone()?, server.try_clone()?);
    let (c, s) = (client.try_clone()?, server.try_clone()?);
    let up = std::thread::Builder::new().name("live-relay-up".into()).spawn(move || {
        let _ = io::copy(&mut client_r, &mut server_w);
        let _ = c.shutdown(Shutdown::Both);
        let _ = s.shutdown(Shutdown::Both);
    })?;
    let _ = io::copy(&mut server_r, &mut client_w);
    let _ = client.shutdown(Shutdown::Both);
    let _ = server.shutdown(Shutdown::Both);
    let _ = up.join();
    // This connection's and any other ended one's entries go (a shut socket has no peer).
    open.lock().unwrap_or_else(PoisonError::into_inner).retain(|s| s.peer_addr().is_ok());
    Ok(())
}

/// Counts a viewer's connection as ended when dropped (however `serve` returns).
struct Ended<'a>(&'a AtomicUsize);

impl Drop for Ended<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A connection to the SDK's server with a receive buffer of [`RELAY_BUFFER`] (set
/// before the connection, so the window it advertises is that small from the start).
fn connect_small(upstream: SocketAddr) -> io::Result<TcpStream> {
    let socket = socket2::Socket::new(socket2::Domain::for_address(upstream), socket2::Type::STREAM, Some(socket2::Protocol::TCP))?;
    socket.set_recv_buffer_size(RELAY_BUFFER)?;
    socket.connect(&upstream.into())?;
    Ok(socket.into())
}

/// Reads an HTTP head (through its blank line) from `from`: the head, and the bytes
/// read past it (the first frames, if the peer sent them at once).
fn read_head(from: &mut TcpStream) -> io::Result<(Vec<u8>, Vec<u8>)> {
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 1024];
    loop {
        if let Some(end) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            let rest = buf.split_off(end + 4);
            return Ok((buf, rest));
        }
        if buf.len() > HEAD_LIMIT {
            return Err(io::Error::new(io::ErrorKind::InvalidData, "an HTTP head over 16 KiB"));
        }
        let n = from.read(&mut chunk)?;
        if n == 0 {
            return Err(io::ErrorKind::UnexpectedEof.into());
        }
        buf.extend_from_slice(&chunk[..n]);
    }
}

/// The subprotocols a head offers or names (every `Sec-WebSocket-Protocol` header,
/// comma-separated, trimmed).
fn protocols(headers: &[httparse::Header<'_>]) -> Vec<String> {
    headers
        .iter()
        .filter(|h| h.name.eq_ignore_ascii_case("sec-websocket-protocol"))
        .flat_map(|h| String::from_utf8_lossy(h.value).split(',').map(|p| p.trim().to_string()).collect::<Vec<_>>())
        .collect()
}

/// The head again with its `Sec-WebSocket-Protocol` headers replaced by one naming
/// `protocol`, every other header as it came.
fn with_protocol(first_line: &str, headers: &[httparse::Header<'_>], protocol: &str) -> Vec<u8> {
    let mut out = format!("{first_line}\r\n").into_bytes();
    for h in headers.iter().filter(|h| !h.name.eq_ignore_ascii_case("sec-websocket-protocol")) {
        out.extend_from_slice(h.name.as_bytes());
        out.extend_from_slice(b": ");
        out.extend_from_slice(h.value);
        out.extend_from_slice(b"\r\n");
    }
    out.extend_from_slice(format!("Sec-WebSocket-Protocol: {protocol}\r\n\r\n").as_bytes());
    out
}

fn bad(what: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, what)
}

/// A viewer's upgrade request as the SDK gets it, and whether it was renamed: one that
/// offers [`PUBLISHED_V1`] and none of the SDK's names offers `foxglove.sdk.v1` instead.
///
/// # Errors
/// A head `httparse` does not read as a whole HTTP/1.x request.
pub(crate) fn rewrite_request(head: &[u8]) -> io::Result<(Vec<u8>, bool)> {
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut req = httparse::Request::new(&mut headers);
    match req.parse(head) {
        Ok(httparse::Status::Complete(_)) => {}
        Ok(httparse::Status::Partial) => return Err(bad("a partial HTTP request".into())),
        Err(e) => return Err(bad(format!("not an HTTP request: {e}"))),
    }
    let offered = protocols(req.headers);
    if !offered.iter().any(|p| p == PUBLISHED_V1) || offered.iter().any(|p| SDK_NAMES.contains(&p.as_str())) {
        return Ok((head.to_vec(), false));
    }
    let first = format!("{} {} HTTP/1.{}", req.method.unwrap_or("GET"), req.path.unwrap_or("/"), req.version.unwrap_or(1));
    Ok((with_protocol(&first, req.headers, SDK_V1), true))
}

/// The SDK's answer to a renamed request as the viewer gets it: the switch to
/// `foxglove.sdk.v1` named [`PUBLISHED_V1`]; any other answer (a refusal) as it came.
///
/// # Errors
/// A head `httparse` does not read as a whole HTTP/1.x response.
pub(crate) fn rewrite_answer(head: &[u8]) -> io::Result<Vec<u8>> {
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut res = httparse::Response::new(&mut headers);
    match res.parse(head) {
        Ok(httparse::Status::Complete(_)) => {}
        Ok(httparse::Status::Partial) => return Err(bad("a partial HTTP response".into())),
        Err(e) => return Err(bad(format!("not an HTTP response: {e}"))),
    }
    if res.code != Some(101) || protocols(res.headers) != [SDK_V1] {
        return Ok(head.to_vec());
    }
    let first = format!("HTTP/1.{} 101 {}", res.version.unwrap_or(1), res.reason.unwrap_or("Switching Protocols"));
    Ok(with_protocol(&first, res.headers, PUBLISHED_V1))
}

#[cfg(test)]
mod tests {
    use super::*;

    const OFFER_V1: &[u8] = b"GET /ws?x=1 HTTP/1.1\r\nHost: 127.0.0.1:8765\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\nsec-websocket-protocol: foxglove.websocket.v1\r\n\r\n";

    fn header(head: &[u8], name: &str) -> Vec<String> {
        String::from_utf8(head.to_vec())
            .unwrap()
            .lines()
            .filter_map(|l| l.split_once(": ").filter(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, v)| v.to_string()))
            .collect()
    }

    /// The published name alone is offered as the SDK's, every other header and
    /// the request line kept, in order.
    #[test]
    fn a_request_offering_the_published_name_alone_offers_the_sdks() {
        let (out, renamed) = rewrite_request(OFFER_V1).unwrap();
        assert!(renamed);
        let text = String::from_utf8(out.clone()).unwrap();
        assert!(text.starts_with("GET /ws?x=1 HTTP/1.1\r\nHost: 127.0.0.1:8765\r\n"), "{text}");
        assert_eq!(header(&out, "sec-websocket-protocol"), ["foxglove.sdk.v1"]);
        assert_eq!(header(&out, "sec-websocket-key"), ["dGhlIHNhbXBsZSBub25jZQ=="]);
        assert!(text.ends_with("\r\n\r\n") && !text.contains("websocket.v1"), "{text}");
    }

    /// A request that offers one of the SDK's names, or no Foxglove name, goes
    /// through byte for byte (the SDK negotiates or refuses it).
    #[test]
    fn other_requests_go_through_unchanged() {
        for offer in ["foxglove.websocket.v1, foxglove.sdk.v1", "foxglove.sdk.v1.1", "chat"] {
            let head = String::from_utf8(OFFER_V1.to_vec()).unwrap().replace("foxglove.websocket.v1", offer).into_bytes();
            assert_eq!(rewrite_request(&head).unwrap(), (head.clone(), false), "{offer}");
        }
        assert!(rewrite_request(b"\x16\x03\x01 not http\r\n\r\n").is_err());
    }

    /// The SDK's switch to its v1 is named back; a refusal is passed on as it came.
    #[test]
    fn the_answer_names_the_published_protocol_back() {
        let ok = b"HTTP/1.1 101 Switching Protocols\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\nSec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n";
        let out = rewrite_answer(ok).unwrap();
        assert_eq!(header(&out, "sec-websocket-protocol"), [PUBLISHED_V1]);
        assert_eq!(header(&out, "sec-websocket-accept"), ["s3pPLMBiTxaQ9kYGzzhZRbK+xOo="]);
        assert!(out.starts_with(b"HTTP/1.1 101 Switching Protocols\r\n"));
        let refused = b"HTTP/1.1 400 Bad Request\r\ncontent-length: 5\r\n\r\n";
        assert_eq!(rewrite_answer(refused).unwrap(), refused.to_vec());
    }
}
