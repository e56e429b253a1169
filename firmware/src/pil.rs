//! The processor-in-the-loop wire: what crosses the USART between the plant's
//! bridge (`sil-host pil`) and the MCU image (`boards/stm32f405/src/bin/pil.rs`), and its framing.
//!
//! A message is a [`Downlink`] (bridge to image) or an [`Uplink`] (image to
//! bridge), serialised with postcard (varint integers, little-endian floats),
//! followed by the CRC-32/ISCSI (Castagnoli) of those bytes, little-endian, the
//! whole COBS-encoded and ended by one `0x00` byte. A receiver collects bytes up
//! to the `0x00` ([`FrameBuffer`]), decodes them ([`decode`]) and drops a frame
//! whose CRC does not match. Sizes: a frame is at most [`MAX_FRAME`] bytes.
//!
//! The exchange (lockstep, the plant owns time): the image says [`Uplink::Hello`]
//! at boot and whenever it is asked with [`Downlink::Hello`] (a board that booted
//! before the bridge opened its serial port); the bridge sends a lone `0x00` (it
//! ends any partial frame left on the line), asks for the Hello, then sends
//! [`Downlink::Configure`] and the image answers
//! [`Uplink::Configured`] (or [`Uplink::Rejected`]); then for each period the
//! bridge sends [`Downlink::Frame`] and the image answers [`Uplink::Answer`];
//! [`Downlink::End`] ends the run: the image logs its figures; under QEMU it exits,
//! on a board it waits for the next configuration.

use crc::{CRC_32_ISCSI, Crc};
use serde::{Deserialize, Serialize};
use shared::wire::{ActuatorCommand, FirmwareTelemetry, SensorFrame};

use crate::config::Config;

/// Version of this protocol, sent in [`Uplink::Hello`]; the bridge refuses an
/// image that speaks another. 7: [`Uplink::Hello`]'s `law_digest`; 6:
/// `Config::law` (issue 70).
pub const PROTOCOL_VERSION: u16 = 7;

/// Largest encoded frame, bytes (COBS overhead, CRC and the terminator included):
/// room for the largest message, [`Downlink::Configure`] (173 bytes for the
/// paper's laws, at most 188 with a law's own name and eight values).
pub const MAX_FRAME: usize = 256;

/// The CRC of the wire: CRC-32/ISCSI (Castagnoli), 1 KiB table in flash.
const CRC: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

/// What the image's tick counter counts (the unit of `step_ticks` and
/// `frame_ticks`), told in [`Uplink::Hello`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StepClock {
    /// SysTick at the core clock under an emulator (QEMU's `netduinoplus2`, whose
    /// DWT cycle counter reads 0): under `-icount shift=0` an instruction retires
    /// per virtual ns, so one 168 MHz tick is 5.95 retired instructions, not cycles.
    EmulatedSysTick,
    /// The DWT cycle counter (`CYCCNT`) on silicon: core clock cycles.
    DwtCycles,
    /// No clock: a host simulation of the board (the board twin) whose steps take
    /// no time; every count is 0.
    Simulated,
}

/// Bridge to image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Downlink {
    /// The firmware's configuration for this run (sent once, before any frame).
    Configure(Config),
    /// The sensor frame of period `frame.seq`.
    Frame {
        /// The frame.
        frame: SensorFrame,
        /// Injected fault (`late_command`): the step starts this many microseconds
        /// after `frame.t_us` on the frame's clock; 0 normally.
        start_delay_us: u32,
    },
    /// The run is over: no answer expected; the image logs its figures (and, under
    /// QEMU, exits).
    End,
    /// Asks the image to say [`Uplink::Hello`] (it may have booted long before).
    Hello,
}

/// Image to bridge.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Uplink {
    /// The image booted.
    Hello {
        /// [`PROTOCOL_VERSION`] of the image.
        protocol: u16,
        /// Frequency of the tick counter of `step_ticks` and `frame_ticks`, Hz
        /// (the core clock: 168 MHz on the STM32F405).
        ticks_per_second: u32,
        /// What that counter counts: emulated instructions or silicon cycles.
        clock: StepClock,
        /// The digest of the image's control law's declaration
        /// (`crate::LawSpec::digest`): the bridge holds the declaration it
        /// read from the image's ELF to it, before it configures the image.
        law_digest: u32,
    },
    /// The configuration is accepted; frames may come.
    Configured,
    /// The configuration is invalid (the image's defmt log names the setting), or
    /// a frame came before any configuration.
    Rejected,
    /// The answer to a frame.
    Answer {
        /// The command; its `step_ticks` is [`crate::Firmware::step`]'s own
        /// time (sensor decode to command encode), in ticks of the core clock.
        command: ActuatorCommand,
        /// The step's telemetry (the reference the trace records).
        telemetry: FirmwareTelemetry,
        /// Ticks from the frame's last byte to the answer ready to encode: COBS,
        /// CRC and postcard decoding of the frame plus the step.
        frame_ticks: u32,
    },
    /// A frame arrived damaged (bad COBS, CRC or message, or too long); it is ignored.
    Garbled,
}

/// Why a frame could not be encoded or decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    /// The COBS encoding is broken.
    #[error("broken COBS encoding")]
    Cobs,
    /// The CRC does not match, or the bytes are not a message.
    #[error("bad CRC or malformed message")]
    Message,
    /// The frame does not fit [`MAX_FRAME`] bytes.
    #[error("frame longer than {MAX_FRAME} bytes")]
    TooLong,
}

/// Encodes `msg` into `buf`: postcard, CRC-32, COBS and the `0x00` terminator.
/// Returns the frame (a prefix of `buf`).
///
/// # Errors
/// [`WireError::TooLong`] when `buf` is too small.
pub fn encode<'a, T: Serialize>(msg: &T, buf: &'a mut [u8]) -> Result<&'a [u8], WireError> {
    let flavor = postcard::ser_flavors::crc::CrcModifier::new(
        postcard::ser_flavors::Cobs::try_new(postcard::ser_flavors::Slice::new(buf)).map_err(|_| WireError::TooLong)?,
        CRC.digest(),
    );
    let out = postcard::serialize_with_flavor(msg, flavor).map_err(|_| WireError::TooLong)?;
    Ok(out)
}

/// Decodes one frame (its bytes without the `0x00` terminator), in place.
///
/// # Errors
/// [`WireError::Cobs`] or [`WireError::Message`] (CRC mismatch included, and bytes
/// left over after a valid message and its CRC: a frame is exactly one message).
pub fn decode<'a, T: Deserialize<'a>>(frame: &'a mut [u8]) -> Result<T, WireError> {
    let n = cobs::decode_in_place(frame).map_err(|_| WireError::Cobs)?;
    match postcard::take_from_bytes_crc32(&frame[..n], CRC.digest()) {
        Ok((msg, [])) => Ok(msg),
        _ => Err(WireError::Message),
    }
}

/// Collects received bytes into frames: fixed size, no heap.
#[derive(Debug, Clone)]
pub struct FrameBuffer {
    buf: [u8; MAX_FRAME],
    len: usize,
    overflow: bool,
}

impl Default for FrameBuffer {
    fn default() -> Self {
        Self { buf: [0; MAX_FRAME], len: 0, overflow: false }
    }
}

/// What one received byte did to a [`FrameBuffer`].
#[derive(Debug, PartialEq, Eq)]
pub enum Push<'a> {
    /// More bytes are needed.
    Pending,
    /// A frame is complete: its bytes, terminator excluded (decode with [`decode`]).
    Frame(&'a mut [u8]),
    /// A frame ended that did not fit [`MAX_FRAME`]; it was dropped.
    Overflow,
}

impl FrameBuffer {
    /// Takes one byte.
    pub fn push(&mut self, byte: u8) -> Push<'_> {
        if byte == 0 {
            let (len, overflow) = (self.len, self.overflow);
            self.len = 0;
            self.overflow = false;
            return match (overflow, len) {
                (true, _) => Push::Overflow,
                (false, 0) => Push::Pending,
                (false, n) => Push::Frame(&mut self.buf[..n]),
            };
        }
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
            }
            None => self.overflow = true,
        }
        Push::Pending
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame_through(bytes: &[u8]) -> Vec<Vec<u8>> {
        let mut fb = FrameBuffer::default();
        let mut out = Vec::new();
        for &b in bytes {
            if let Push::Frame(f) = fb.push(b) {
                out.push(f.to_vec());
            }
        }
        out
    }

    #[test]
    fn messages_round_trip_through_the_framing() {
        let msgs = [
            Downlink::Configure(Config::default()),
            Downlink::Frame {
                frame: SensorFrame { t_us: 1234, seq: 7, theta1_count: 16000, f_n_code: -5, ..SensorFrame::default() },
                start_delay_us: 0,
            },
            Downlink::End,
            Downlink::Hello,
        ];
        let mut wire = Vec::new();
        for m in &msgs {
            let mut buf = [0u8; MAX_FRAME];
            let f = encode(m, &mut buf).unwrap();
            assert_eq!(f.last(), Some(&0), "terminated");
            assert_eq!(f.iter().filter(|&&b| b == 0).count(), 1, "COBS leaves one zero");
            wire.extend_from_slice(f);
        }
        let frames = frame_through(&wire);
        assert_eq!(frames.len(), msgs.len());
        for (mut f, m) in frames.into_iter().zip(&msgs) {
            assert_eq!(decode::<Downlink>(&mut f).unwrap(), *m);
        }
    }

    /// A frame is exactly one message: bytes after a valid message and its CRC are
    /// refused, not ignored (issue 15).
    #[test]
    fn trailing_bytes_after_a_valid_message_are_refused() {
        let msg = Downlink::Frame { frame: SensorFrame { seq: 9, ..SensorFrame::default() }, start_delay_us: 3 };
        let mut buf = [0u8; MAX_FRAME];
        let framed = encode(&msg, &mut buf).unwrap().to_vec();
        // The raw message and CRC, without COBS and terminator.
        let mut raw = framed[..framed.len() - 1].to_vec();
        let n = cobs::decode_in_place(&mut raw).unwrap();
        raw.truncate(n);
        for junk in [&[0x01u8][..], &[0xff, 0x00, 0x7f], &[0u8; 5]] {
            let mut with = raw.clone();
            with.extend_from_slice(junk);
            let mut enc = vec![0u8; cobs::max_encoding_length(with.len())];
            let m = cobs::encode(&with, &mut enc);
            enc.truncate(m);
            assert_eq!(decode::<Downlink>(&mut enc), Err(WireError::Message), "junk {junk:?}");
        }
        let mut enc = vec![0u8; cobs::max_encoding_length(raw.len())];
        let m = cobs::encode(&raw, &mut enc);
        enc.truncate(m);
        assert_eq!(decode::<Downlink>(&mut enc), Ok(msg), "the message alone decodes");
    }

    #[test]
    fn a_flipped_bit_is_caught_by_the_crc() {
        let msg = Uplink::Answer {
            command: ActuatorCommand { seq: 3, u1_code: 100, ..Default::default() },
            telemetry: FirmwareTelemetry::default(),
            frame_ticks: 99,
        };
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(&msg, &mut buf).unwrap().len();
        let (mut caught, mut tried) = (0, 0);
        for i in 0..n - 1 {
            for bit in 0..8 {
                let mut f = buf[..n - 1].to_vec();
                f[i] ^= 1 << bit;
                if f[i] == 0 {
                    continue; // a zero would end the frame early: the receiver splits there
                }
                tried += 1;
                if decode::<Uplink>(&mut f).is_err() {
                    caught += 1;
                } else {
                    panic!("byte {i} bit {bit} flipped and still decoded");
                }
            }
        }
        assert_eq!(caught, tried);
        assert!(tried > 7 * (n - 1), "{tried} flips tried");
    }

    #[test]
    fn an_overlong_frame_is_dropped_and_the_next_one_decodes() {
        let mut wire = vec![1u8; MAX_FRAME + 10];
        wire.push(0);
        let mut buf = [0u8; MAX_FRAME];
        wire.extend_from_slice(encode(&Downlink::End, &mut buf).unwrap());
        let mut fb = FrameBuffer::default();
        let mut events = Vec::new();
        for &b in &wire {
            match fb.push(b) {
                Push::Overflow => events.push("overflow".to_string()),
                Push::Frame(f) => events.push(format!("{:?}", decode::<Downlink>(f))),
                Push::Pending => {}
            }
        }
        assert_eq!(events, ["overflow", "Ok(End)"]);
    }

    #[test]
    fn the_largest_message_fits() {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(&Downlink::Configure(Config::default()), &mut buf).unwrap().len();
        assert_eq!(n, 173);
        // The longest a law of one's own makes it: a 16-byte name, eight values
        // of the longest varint-free encoding (f32 is 4 bytes whatever its value).
        let law = crate::LawParams { name: crate::LawName::new("sixteen_chars_ok").unwrap(), values: [f32::MAX; 8] };
        let n = encode(&Downlink::Configure(Config { law, ..Config::default() }), &mut buf).unwrap().len();
        assert!(n <= MAX_FRAME - 64, "{n} bytes: keep a margin for Config to grow");
    }
}
