//! The settings record in flash (issue 23; docs/board.md "Bring-up", step 6):
//! the calibration and the firmware's configuration, saved by the bring-up
//! protocol's `Save` and loaded at reset. Until a valid record is in force the
//! drivers stay locked out (the enable button and `Enable` are refused, saying
//! why: [`Settings`]).
//!
//! The flash is any embedded-storage `NorFlash` (on the reference board sector 4
//! of the STM32F405, 64 KiB at `0x0801_0000`, just above the images' 64 KiB
//! budget; on the board twin a model of it). The record sits at offset 0:
//!
//! | bytes | field |
//! |---|---|
//! | 0..4 | magic `b"PLVS"` (an erased sector reads `0xFF`: no record) |
//! | 4..6 | [`RECORD_VERSION`], little-endian |
//! | 6..8 | the frame's length `n`, little-endian |
//! | 8..8+n | [`Stored`] as one PIL wire frame (`firmware::pil::encode`: postcard, CRC-32C, COBS, the `0x00` terminator) |
//!
//! then `0xFF` up to the flash's write granularity. A save erases the sector,
//! writes the record and reads it back.

use embedded_storage::nor_flash::NorFlash;
use firmware::{Config, pil};
use serde::{Deserialize, Serialize};

/// The record's format version: a record of another version is refused as
/// corrupt (re-run the bring-up's calibration and save). 4: the
/// configuration's `law` (issue 70).
pub const RECORD_VERSION: u16 = 4;

/// The record's magic.
pub const MAGIC: [u8; 4] = *b"PLVS";

/// The largest record, bytes (header, payload, CRC), rounded up to a word.
pub const MAX_RECORD: usize = 256;

const HEADER: usize = 8;

/// How a load-cell axis's gain was set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SpanStep {
    /// Not yet: the gain is the compiled-in nominal one and nobody said to keep it.
    NotDone,
    /// Measured with a known force (`Request::Span`).
    Measured,
    /// The operator kept the nominal gain (`Request::SkipSpan`: no weight at hand);
    /// the record says so.
    Skipped,
}

/// The bring-up steps a calibration still lacks, as a bit set: the drivers
/// unlock only with a saved calibration that lacks none (docs/board.md
/// "Bring-up").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Missing(pub u8);

impl Missing {
    /// The encoders' zeros were never set (`Request::SetZeros`).
    pub const ZEROS: u8 = 1 << 0;
    /// Not both joints' directions were checked by a jog with these zeros.
    pub const DIRECTIONS: u8 = 1 << 1;
    /// The load cell was never tared (`Request::Tare`).
    pub const TARE: u8 = 1 << 2;
    /// The tangential axis's span was neither measured nor skipped.
    pub const SPAN_T: u8 = 1 << 3;
    /// The normal axis's span was neither measured nor skipped.
    pub const SPAN_N: u8 = 1 << 4;

    /// Nothing is missing.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Each missing step's name with the command that does it, in bring-up
    /// order (no `core::fmt` on the image: the host joins them).
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        [
            (Self::ZEROS, "the encoders' zeros (`sil-host board calibrate`)"),
            (Self::DIRECTIONS, "both joints' direction checks (`sil-host board calibrate`)"),
            (Self::TARE, "the load cell's tare (`sil-host board calibrate`, without --no-tare)"),
            (Self::SPAN_T, "the tangential span (`sil-host board span --axis tangential`, or --skip)"),
            (Self::SPAN_N, "the normal span (`sil-host board span --axis normal`, or --skip)"),
        ]
        .into_iter()
        .filter(move |(bit, _)| self.0 & bit != 0)
        .map(|(_, name)| name)
    }
}

/// The firmware's calibration as it crosses the wire and sits in flash, with
/// the bring-up steps it went through.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationRecord {
    /// Each encoder's raw count at its joint's zero `[theta1, elbow]`.
    pub zero_counts: [u16; 2],
    /// Each encoder counts against its joint `[theta1, elbow]`.
    pub reversed: [bool; 2],
    /// The load cell's ADC count at zero force `[f_t, f_n]`.
    pub load_zero_counts: [f32; 2],
    /// The load cell's gain `[f_t, f_n]`, N per count.
    pub load_newtons_per_count: [f32; 2],
    /// Belt travel per quadrature count, m.
    pub belt_metres_per_count: f32,
    /// The encoders' zeros were set at the calibration pose (or restored).
    pub zeros_set: bool,
    /// Both joints' directions were checked by a jog with these zeros.
    pub directions_checked: bool,
    /// The load cell's zero counts come from a tare (nothing on it).
    pub tared: bool,
    /// How each axis's gain was set `[f_t, f_n]`.
    pub span: [SpanStep; 2],
}

impl CalibrationRecord {
    /// The record of calibration `cal` with no bring-up step done: what a board
    /// runs with before its bring-up (the compiled-in defaults).
    pub fn uncalibrated(cal: &crate::calibration::ArmCalibration) -> Self {
        Self {
            zero_counts: [cal.encoders.theta1.zero_count, cal.encoders.elbow.zero_count],
            reversed: [cal.encoders.theta1.reversed, cal.encoders.elbow.reversed],
            load_zero_counts: cal.load_cell.zero_counts,
            load_newtons_per_count: cal.load_cell.newtons_per_count,
            belt_metres_per_count: cal.belt_metres_per_count,
            zeros_set: false,
            directions_checked: false,
            tared: false,
            span: [SpanStep::NotDone; 2],
        }
    }

    /// The record of calibration `cal` with every bring-up step done and both
    /// spans measured: a board brought up before (the twin's `--flash saved`,
    /// tests).
    pub fn brought_up(cal: &crate::calibration::ArmCalibration) -> Self {
        Self { zeros_set: true, directions_checked: true, tared: true, span: [SpanStep::Measured; 2], ..Self::uncalibrated(cal) }
    }

    /// The bring-up steps this calibration lacks (empty: it may be saved and
    /// unlock the drivers).
    pub fn missing(&self) -> Missing {
        // Bit by bit, no table: the control interrupt asks at the enable
        // button's press (issue 56: the table's loop cost 130 cycles there).
        let bit = |lacks: bool, b: u8| if lacks { b } else { 0 };
        Missing(
            bit(!self.zeros_set, Missing::ZEROS)
                | bit(!self.directions_checked, Missing::DIRECTIONS)
                | bit(!self.tared, Missing::TARE)
                | bit(self.span[0] == SpanStep::NotDone, Missing::SPAN_T)
                | bit(self.span[1] == SpanStep::NotDone, Missing::SPAN_N),
        )
    }

    /// The calibration this record holds.
    pub fn arm_calibration(&self) -> crate::calibration::ArmCalibration {
        use drivers::{EncoderCalibration, frame::FrameCalibration, load_cell::Calibration};
        crate::calibration::ArmCalibration {
            encoders: FrameCalibration {
                theta1: EncoderCalibration { zero_count: self.zero_counts[0], reversed: self.reversed[0] },
                elbow: EncoderCalibration { zero_count: self.zero_counts[1], reversed: self.reversed[1] },
            },
            load_cell: Calibration { zero_counts: self.load_zero_counts, newtons_per_count: self.load_newtons_per_count },
            belt_metres_per_count: self.belt_metres_per_count,
        }
    }
}

/// What the record holds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stored {
    /// The calibration.
    pub calibration: CalibrationRecord,
    /// The firmware's configuration.
    pub config: Config,
}

/// Why a stored record was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RecordFault {
    /// The header's magic is neither the record's nor erased flash.
    Magic,
    /// The record is of another format version (the one found).
    Version(u16),
    /// The payload's length is out of range.
    Length,
    /// The frame's CRC-32C does not match, or its COBS or message is broken:
    /// the record is damaged.
    Crc,
    /// The payload passed its CRC but does not decode, or its values are invalid
    /// (the configuration or the calibration is refused).
    Content,
    /// The flash failed to read, erase or write.
    Flash,
    /// After a save the record read back differs from what was written.
    Verify,
    /// The record's calibration lacks bring-up steps (`CalibrationRecord::missing`).
    Incomplete(Missing),
    /// The record's configuration turns the runaway limits off, which a board
    /// never runs (`crate::bringup::Refusal::ProtectionOff`).
    ProtectionOff,
}

/// The settings in force, against the record in flash: the drivers enable only
/// when [`Settings::Saved`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Settings {
    /// The settings in force are the record in flash (loaded at reset or saved since).
    Saved,
    /// The settings were changed since the last load or save: save them
    /// (`sil-host board save`) before enabling.
    Unsaved,
    /// The flash holds no record (erased): the compiled-in defaults are in
    /// force, which are not this arm's calibration. Run the bring-up.
    Missing,
    /// The record in flash was refused, and why; the compiled-in defaults are in force.
    Corrupt(RecordFault),
}

impl Settings {
    /// Whether the drivers may enable.
    pub fn allows_enable(self) -> bool {
        self == Self::Saved
    }

    /// What it means for the operator, in a few words (no `core::fmt` on the image).
    pub fn describe(self) -> &'static str {
        match self {
            Self::Saved => "the settings in flash are in force",
            Self::Unsaved => "the settings changed since the last save: drivers locked out until `sil-host board save`",
            Self::Missing => "no settings in flash: drivers locked out until the bring-up's calibration is saved",
            Self::Corrupt(f) => f.describe(),
        }
    }
}

impl RecordFault {
    /// Why the record was refused, in a few words; the drivers are locked out.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Magic => "the settings sector holds something else than a settings record: drivers locked out",
            Self::Version(_) => "the settings record is of another format version: drivers locked out; calibrate and save again",
            Self::Length => "the settings record's length is out of range: drivers locked out",
            Self::Crc => "the settings record is damaged (CRC-32C mismatch): drivers locked out; calibrate and save again",
            Self::Content => "the settings record's values are invalid: drivers locked out",
            Self::Flash => "the flash failed",
            Self::Verify => "the settings record read back differs from what was written",
            Self::Incomplete(_) => "the calibration lacks bring-up steps: drivers locked out; finish the bring-up and save",
            Self::ProtectionOff => {
                "the settings record turns the runaway limits off, which a board never runs: drivers locked out; \
                 configure with them on (`controller.runaway_limits = true`) and save"
            }
        }
    }
}

/// Encodes `stored` into `buf` as the record, padded with `0xFF` to a multiple
/// of `word` bytes. Returns the record's bytes. The frame is the PIL wire's, so
/// that the image carries one serde path for the wire and the record.
///
/// # Errors
/// [`RecordFault::Length`] when it does not fit [`MAX_RECORD`].
pub fn encode<'a>(stored: &Stored, buf: &'a mut [u8; MAX_RECORD], word: usize) -> Result<&'a [u8], RecordFault> {
    buf.fill(0xFF);
    let n = pil::encode(stored, &mut buf[HEADER..]).map_err(|_| RecordFault::Length)?.len();
    buf[..4].copy_from_slice(&MAGIC);
    buf[4..6].copy_from_slice(&RECORD_VERSION.to_le_bytes());
    buf[6..8].copy_from_slice(&(n as u16).to_le_bytes());
    let word = word.max(1);
    let len = (HEADER + n).div_ceil(word) * word;
    if len > MAX_RECORD {
        return Err(RecordFault::Length);
    }
    Ok(&buf[..len])
}

/// Decodes a record from the start of `bytes` (in place: the frame's COBS is
/// undone there): `Ok(None)` when the flash is erased there (no record).
///
/// # Errors
/// [`RecordFault`]: what is wrong with the record.
pub fn decode(bytes: &mut [u8]) -> Result<Option<Stored>, RecordFault> {
    if bytes.len() < HEADER {
        return Err(RecordFault::Length);
    }
    if bytes[..HEADER].iter().all(|&b| b == 0xFF) {
        return Ok(None);
    }
    if bytes[..4] != MAGIC {
        return Err(RecordFault::Magic);
    }
    let version = u16::from_le_bytes([bytes[4], bytes[5]]);
    if version != RECORD_VERSION {
        return Err(RecordFault::Version(version));
    }
    let n = usize::from(u16::from_le_bytes([bytes[6], bytes[7]]));
    if !(2..=MAX_RECORD - HEADER).contains(&n) || HEADER + n > bytes.len() || bytes[HEADER + n - 1] != 0 {
        return Err(RecordFault::Length);
    }
    // The frame without its terminator.
    pil::decode(&mut bytes[HEADER..HEADER + n - 1]).map(Some).map_err(|_| RecordFault::Crc)
}

/// Reads the record from `flash` (offset 0).
///
/// # Errors
/// As [`decode`]; [`RecordFault::Flash`] when the read fails.
pub fn load<F: NorFlash>(flash: &mut F) -> Result<Option<Stored>, RecordFault> {
    let mut buf = [0u8; MAX_RECORD];
    let len = MAX_RECORD.min(flash.capacity());
    flash.read(0, &mut buf[..len]).map_err(|_| RecordFault::Flash)?;
    decode(&mut buf[..len])
}

/// Erases the record's sector, writes `stored` at offset 0 and reads it back.
///
/// # Errors
/// [`RecordFault::Flash`] when the flash fails, [`RecordFault::Verify`] when the
/// record read back is not the one written, [`RecordFault::Length`] when the
/// flash is smaller than the record.
pub fn save<F: NorFlash>(flash: &mut F, stored: &Stored) -> Result<(), RecordFault> {
    let mut buf = [0u8; MAX_RECORD];
    let bytes = encode(stored, &mut buf, F::WRITE_SIZE)?;
    if bytes.len() > flash.capacity() || F::ERASE_SIZE > flash.capacity() {
        return Err(RecordFault::Length);
    }
    flash.erase(0, F::ERASE_SIZE as u32).map_err(|_| RecordFault::Flash)?;
    flash.write(0, bytes).map_err(|_| RecordFault::Flash)?;
    match load(flash) {
        Ok(Some(back)) if back == *stored => Ok(()),
        _ => Err(RecordFault::Verify),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored() -> Stored {
        Stored {
            calibration: CalibrationRecord {
                zero_counts: [5000, 12000],
                reversed: [false, true],
                load_zero_counts: [2048.0, 2047.5],
                load_newtons_per_count: [0.01, -0.012],
                belt_metres_per_count: 1e-6,
                zeros_set: true,
                directions_checked: true,
                tared: true,
                span: [SpanStep::Measured, SpanStep::Skipped],
            },
            config: Config::default(),
        }
    }

    #[test]
    fn a_record_round_trips_and_every_damage_is_named() {
        let mut buf = [0u8; MAX_RECORD];
        let bytes = encode(&stored(), &mut buf, 4).unwrap().to_vec();
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(decode(&mut bytes.clone()), Ok(Some(stored())));
        assert_eq!(decode(&mut [0xFF; 64]), Ok(None));
        // Any single flipped bit in the frame (before its terminator) is caught.
        let n = usize::from(u16::from_le_bytes([bytes[6], bytes[7]]));
        for i in HEADER..HEADER + n - 1 {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                assert_eq!(decode(&mut b), Err(RecordFault::Crc), "byte {i} bit {bit}");
            }
        }
        let mut b = bytes.clone();
        b[4] = 7;
        assert_eq!(decode(&mut b), Err(RecordFault::Version(7)));
        let mut b = bytes.clone();
        b[0] = b'X';
        assert_eq!(decode(&mut b), Err(RecordFault::Magic));
        let mut b = bytes;
        b[6] = 0xF0;
        assert_eq!(decode(&mut b), Err(RecordFault::Length));
    }
}
