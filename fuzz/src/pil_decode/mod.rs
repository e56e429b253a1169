//! Target `pil-decode`: the PIL wire's decoder ([`firmware::pil::decode`], with
//! [`firmware::pil::FrameBuffer`]) under mutated and random frames.
//!
//! Messages are [`Downlink`]s and [`Uplink`]s with arbitrary contents: every float
//! any bit pattern (NaN payloads, infinities, subnormals), every integer any value,
//! so every varint length occurs. A case is one of:
//!
//! - **mutated**: a message is encoded, then 1 to 6 mutations hit its frame (flip a
//!   bit, set, insert or delete bytes, append bytes, truncate, duplicate a run, swap
//!   two bytes). Decoded as its own type, the frame must be refused or give exactly
//!   the original message; decoded as the other direction's type, it must not panic
//!   and anything accepted must round-trip.
//! - **trailing**: bytes (1 to 16, any values) appended inside the frame after a
//!   valid message and its CRC, then COBS-encoded again: must be refused with
//!   [`WireError::Message`] (a frame is exactly one message).
//! - **raw**: arbitrary bytes, straight and through a [`FrameBuffer`], decoded as
//!   both types: no panic; anything accepted round-trips.
//! - **stream**: 1 to 6 messages of one direction, framed back to back, 0 to 4
//!   mutations of the byte stream, split by a [`FrameBuffer`]: every message decoded
//!   is one of those sent; without mutations exactly those, in order.
//!
//! For every generated message: it encodes within [`MAX_FRAME`] bytes, with one
//! `0x00` (the terminator), and decodes to exactly itself ("exactly" is compared
//! on the canonical encoding, so NaN payloads count).
//!
//! Why "refused or the original" can be asserted: a mutated frame that COBS-decodes
//! to other bytes is accepted only if postcard reads a message that ends exactly 4
//! bytes before the end and the CRC-32C of the message bytes matches those 4 bytes.
//! Errors confined to 32 consecutive bits are always detected by a 32-bit CRC; a
//! mutation that moves bytes or changes a COBS code byte spreads its error over the
//! frame, and a random error pattern passes the CRC with probability `2^-32`. Over
//! the 10^6 cases of a long run (about 10^6 to 6 x 10^6 corrupted frames) the
//! expected number of such false acceptances is below `1.4e-3`; a failure here is
//! therefore a defect, not bad luck, unless it reproduces only on one seed and the
//! frame's CRC is shown to collide.

use firmware::pil::{self, Downlink, FrameBuffer, MAX_FRAME, Push, Uplink, WireError};
use serde::Serialize;

use crate::ensure;

mod generators;

pub use generators::strategy;

/// A change to a frame's bytes. Positions are taken modulo the frame's length (plus
/// one where the end is a position).
#[derive(Debug, Clone)]
pub enum Mutation {
    /// Flips bit `bit % 8` of the byte at `at`.
    Flip {
        /// Position.
        at: usize,
        /// Bit.
        bit: u8,
    },
    /// Sets the byte at `at`.
    Set {
        /// Position.
        at: usize,
        /// New value.
        byte: u8,
    },
    /// Inserts a byte before `at`.
    Insert {
        /// Position.
        at: usize,
        /// The byte.
        byte: u8,
    },
    /// Deletes `len` bytes from `at`.
    Delete {
        /// Position.
        at: usize,
        /// How many (1 to 8).
        len: u8,
    },
    /// Appends bytes after the frame's last byte.
    Append(Vec<u8>),
    /// Cuts the frame at `at`.
    Truncate {
        /// New length.
        at: usize,
    },
    /// Repeats `len` bytes from `at` right after them.
    Duplicate {
        /// Position.
        at: usize,
        /// How many.
        len: u8,
    },
    /// Swaps two bytes.
    Swap {
        /// First position.
        a: usize,
        /// Second position.
        b: usize,
    },
}

impl Mutation {
    /// Applies the mutation.
    pub fn apply(&self, f: &mut Vec<u8>) {
        let n = f.len();
        let pos = |at: usize| if n == 0 { 0 } else { at % n };
        match *self {
            Self::Flip { at, bit } if n > 0 => f[pos(at)] ^= 1 << (bit % 8),
            Self::Set { at, byte } if n > 0 => f[pos(at)] = byte,
            Self::Insert { at, byte } => f.insert(at % (n + 1), byte),
            Self::Delete { at, len } if n > 0 => {
                let a = pos(at);
                f.drain(a..(a + usize::from(len.max(1))).min(n));
            }
            Self::Append(ref bytes) => f.extend_from_slice(bytes),
            Self::Truncate { at } => f.truncate(at % (n + 1)),
            Self::Duplicate { at, len } if n > 0 => {
                let a = pos(at);
                let run: Vec<u8> = f[a..(a + usize::from(len.max(1))).min(n)].to_vec();
                let end = a + run.len();
                f.splice(end..end, run);
            }
            Self::Swap { a, b } if n > 0 => f.swap(pos(a), pos(b)),
            _ => {}
        }
    }
}

/// A message of either direction.
#[derive(Debug, Clone, Copy)]
pub enum Msg {
    /// Bridge to image.
    Down(Downlink),
    /// Image to bridge.
    Up(Uplink),
}

/// One case (module docs).
#[derive(Debug, Clone)]
pub enum Case {
    /// A message's frame, mutated.
    Mutated {
        /// The message.
        msg: Msg,
        /// The mutations, in order.
        mutations: Vec<Mutation>,
    },
    /// A message with bytes after its CRC, inside the frame.
    Trailing {
        /// The message.
        msg: Msg,
        /// The bytes after the CRC.
        junk: Vec<u8>,
    },
    /// Arbitrary bytes.
    Raw {
        /// The bytes.
        bytes: Vec<u8>,
    },
    /// Downlink messages framed back to back, the stream mutated.
    StreamDown {
        /// The messages.
        msgs: Vec<Downlink>,
        /// The mutations of the stream.
        mutations: Vec<Mutation>,
    },
    /// Uplink messages framed back to back, the stream mutated.
    StreamUp {
        /// The messages.
        msgs: Vec<Uplink>,
        /// The mutations of the stream.
        mutations: Vec<Mutation>,
    },
}

/// The decoders under test: [`Decoders::FIRMWARE`], or others in the tests (a
/// decoder that ignores trailing bytes must fail the property).
#[derive(Clone, Copy)]
pub struct Decoders {
    /// Decodes a frame (terminator excluded) as a [`Downlink`].
    pub down: fn(&mut [u8]) -> Result<Downlink, WireError>,
    /// Decodes a frame (terminator excluded) as an [`Uplink`].
    pub up: fn(&mut [u8]) -> Result<Uplink, WireError>,
}

impl Decoders {
    /// [`firmware::pil::decode`].
    pub const FIRMWARE: Decoders = Decoders { down: |f| pil::decode(f), up: |f| pil::decode(f) };
}

/// The frame of `msg` with room to spare (the canonical bytes a message is
/// compared by), terminator included.
fn canon<T: Serialize>(msg: &T) -> Vec<u8> {
    let mut buf = [0u8; 4 * MAX_FRAME];
    pil::encode(msg, &mut buf).map(<[u8]>::to_vec).unwrap_or_default()
}

/// A message type of the wire: its decoder among [`Decoders`].
trait Wire: Serialize + Copy + std::fmt::Debug {
    fn decoder(d: &Decoders) -> fn(&mut [u8]) -> Result<Self, WireError>;
}

impl Wire for Downlink {
    fn decoder(d: &Decoders) -> fn(&mut [u8]) -> Result<Self, WireError> {
        d.down
    }
}

impl Wire for Uplink {
    fn decoder(d: &Decoders) -> fn(&mut [u8]) -> Result<Self, WireError> {
        d.up
    }
}

/// Encodes `msg` into a [`MAX_FRAME`] buffer and checks the frame: it fits, ends
/// with the only `0x00`, and decodes to exactly `msg`. Returns the frame,
/// terminator included.
fn framed<T: Wire>(msg: &T, d: &Decoders) -> Result<Vec<u8>, String> {
    let mut buf = [0u8; MAX_FRAME];
    let frame =
        pil::encode(msg, &mut buf).map_err(|e| format!("{msg:?} does not encode within MAX_FRAME = {MAX_FRAME} bytes: {e}"))?.to_vec();
    ensure(frame.last() == Some(&0) && frame.iter().filter(|&&b| b == 0).count() == 1, || {
        format!("frame {frame:?} is not one COBS frame")
    })?;
    let mut f = frame[..frame.len() - 1].to_vec();
    match T::decoder(d)(&mut f) {
        Ok(back) => ensure(canon(&back) == frame, || format!("round trip changed {msg:?} into {back:?}"))?,
        Err(e) => return Err(format!("the frame of {msg:?} does not decode: {e}")),
    }
    Ok(frame)
}

/// Decodes `bytes` as `T`: whatever is accepted must round-trip.
fn accepted_round_trips<T: Wire>(bytes: &[u8], d: &Decoders) -> Result<Option<T>, String> {
    let mut f = bytes.to_vec();
    match T::decoder(d)(&mut f) {
        Ok(m) => {
            framed(&m, d).map_err(|e| format!("accepted {m:?} from {bytes:?}, then: {e}"))?;
            Ok(Some(m))
        }
        Err(_) => Ok(None),
    }
}

fn mutated<T: Wire, U: Wire>(msg: &T, mutations: &[Mutation], d: &Decoders) -> Result<(), String> {
    let frame = framed(msg, d)?;
    let original = &frame[..frame.len() - 1];
    let mut f = original.to_vec();
    for m in mutations {
        m.apply(&mut f);
    }
    let mut g = f.clone();
    match T::decoder(d)(&mut g) {
        Ok(back) => ensure(canon(&back) == frame, || format!("mutated frame {f:?} accepted as {back:?}, not the original {msg:?}"))?,
        Err(e) => ensure(f != original, || format!("the unmutated frame of {msg:?} was refused: {e}"))?,
    }
    // The other direction's decoder: no panic, and what it accepts round-trips.
    accepted_round_trips::<U>(&f, d)?;
    Ok(())
}

fn trailing<T: Wire>(msg: &T, junk: &[u8], d: &Decoders) -> Result<(), String> {
    let frame = framed(msg, d)?;
    let mut raw = frame[..frame.len() - 1].to_vec();
    let n = cobs::decode_in_place(&mut raw).map_err(|e| format!("COBS of our own frame: {e:?}"))?;
    raw.truncate(n);
    raw.extend_from_slice(junk);
    let mut enc = vec![0u8; cobs::max_encoding_length(raw.len())];
    let m = cobs::encode(&raw, &mut enc);
    enc.truncate(m);
    let got = T::decoder(d)(&mut enc);
    ensure(matches!(got, Err(WireError::Message)), || format!("{junk:?} after the CRC of {msg:?}: {got:?}, expected Err(Message)"))
}

fn stream<T: Wire>(msgs: &[T], mutations: &[Mutation], d: &Decoders) -> Result<(), String> {
    let mut bytes = Vec::new();
    let mut sent = Vec::new();
    for m in msgs {
        let f = framed(m, d)?;
        bytes.extend_from_slice(&f);
        sent.push(f);
    }
    for m in mutations {
        m.apply(&mut bytes);
    }
    let mut fb = FrameBuffer::default();
    let mut got = Vec::new();
    let mut overflows = 0;
    for &b in &bytes {
        match fb.push(b) {
            Push::Frame(f) => {
                ensure(f.len() <= MAX_FRAME, || format!("a frame of {} bytes", f.len()))?;
                if let Ok(m) = T::decoder(d)(f) {
                    got.push(m);
                }
            }
            Push::Overflow => overflows += 1,
            Push::Pending => {}
        }
    }
    for m in &got {
        ensure(sent.contains(&canon(m)), || format!("decoded {m:?}, which was never sent"))?;
    }
    if mutations.is_empty() {
        let got: Vec<Vec<u8>> = got.iter().map(canon).collect();
        ensure(got == sent && overflows == 0, || {
            format!("an unmutated stream decoded to {got:?} ({overflows} overflows), not what was sent")
        })?;
    }
    Ok(())
}

fn raw(bytes: &[u8], d: &Decoders) -> Result<(), String> {
    accepted_round_trips::<Downlink>(bytes, d)?;
    accepted_round_trips::<Uplink>(bytes, d)?;
    let mut fb = FrameBuffer::default();
    for &b in bytes {
        if let Push::Frame(f) = fb.push(b) {
            let f = f.to_vec();
            accepted_round_trips::<Downlink>(&f, d)?;
            accepted_round_trips::<Uplink>(&f, d)?;
        }
    }
    Ok(())
}

/// The property with the decoders `d`.
///
/// # Errors
/// What is wrong.
pub fn check_with(case: &Case, d: &Decoders) -> Result<(), String> {
    match case {
        Case::Mutated { msg: Msg::Down(m), mutations } => mutated::<Downlink, Uplink>(m, mutations, d),
        Case::Mutated { msg: Msg::Up(m), mutations } => mutated::<Uplink, Downlink>(m, mutations, d),
        Case::Trailing { msg: Msg::Down(m), junk } => trailing(m, junk, d),
        Case::Trailing { msg: Msg::Up(m), junk } => trailing(m, junk, d),
        Case::Raw { bytes } => raw(bytes, d),
        Case::StreamDown { msgs, mutations } => stream(msgs, mutations, d),
        Case::StreamUp { msgs, mutations } => stream(msgs, mutations, d),
    }
}

/// The property of this target (module docs), on [`Decoders::FIRMWARE`].
///
/// # Errors
/// What is wrong.
pub fn check(case: &Case) -> Result<(), String> {
    check_with(case, &Decoders::FIRMWARE)
}
