//! Tests of the AS5047P driver ([`super`]) against a mocked SPI bus: commands
//! and their parity, the read pipeline, diagnostics, error flags, bus errors.

use super::*;
use embedded_hal::spi::{ErrorKind, ErrorType, Operation};
use embedded_hal_mock::eh1::spi::{Mock, Transaction as T};
use proptest::prelude::*;

// Command words, parity computed by hand (datasheet examples agree).
// READ NOP: 0x4000 has one 1 -> parity 1 -> 0xC000.
const RD_NOP: u16 = 0xC000;
// READ ANGLECOM: 0x7FFF has fifteen 1s -> parity 1 -> 0xFFFF.
const RD_ANGLECOM: u16 = 0xFFFF;
// READ DIAAGC: 0x7FFC has thirteen 1s -> parity 1 -> 0xFFFC.
const RD_DIAAGC: u16 = 0xFFFC;
// READ ERRFL: 0x4001 has two 1s -> parity 0 -> 0x4001.
const RD_ERRFL: u16 = 0x4001;

/// One frame on the mock: CS assert, one word in and out, CS release.
fn xfer(out: u16, answer: u16) -> [T<u16>; 3] {
    [T::transaction_start(), T::transfer_in_place(vec![out], vec![answer]), T::transaction_end()]
}

fn mock(frames: &[(u16, u16)]) -> Mock<u16> {
    let t: Vec<T<u16>> = frames.iter().flat_map(|&(o, a)| xfer(o, a)).collect();
    Mock::new(&t)
}

/// An answer word with `data` in bits 0..13, `ef`, and the parity bit set right.
fn answer(data: u16, ef: bool) -> u16 {
    let w = data & DATA | if ef { EF } else { 0 };
    w | (parity_of(w) << 15)
}

#[test]
fn hand_computed_commands() {
    assert_eq!(read_command(REG_NOP), RD_NOP);
    assert_eq!(read_command(REG_ANGLECOM), RD_ANGLECOM);
    assert_eq!(read_command(REG_DIAAGC), RD_DIAAGC);
    assert_eq!(read_command(REG_ERRFL), RD_ERRFL);
}

#[test]
fn angle_reads_anglecom_then_nop() {
    // Angle 0x1234: bits 12, 9, 5, 4, 2 -> five 1s -> parity 1 -> 0x9234.
    let mut spi = mock(&[(RD_ANGLECOM, 0x0000), (RD_NOP, 0x9234)]);
    let mut enc = As5047p::new(spi.clone());
    assert_eq!(enc.angle(), Ok(0x1234));
    spi.done();
}

#[test]
fn sample_reads_angle_and_diagnostics_of_the_same_sample() {
    let diag = DIAAGC_LF | 0x40;
    let mut spi = mock(&[(RD_ANGLECOM, answer(0, false)), (RD_DIAAGC, answer(0x2ABC, false)), (RD_NOP, answer(diag, false))]);
    let mut enc = As5047p::new(spi.clone());
    assert_eq!(enc.sample(), Ok(0x2ABC));
    spi.done();
}

fn sample_with_diag(diag: u16) -> Result<u16, Error<ErrorKind>> {
    let mut spi = mock(&[(RD_ANGLECOM, answer(0, false)), (RD_DIAAGC, answer(0x0123, false)), (RD_NOP, answer(diag, false))]);
    let r = As5047p::new(spi.clone()).sample();
    spi.done();
    r
}

#[test]
fn sample_rejects_bad_diagnostics() {
    assert_eq!(sample_with_diag(0), Err(Error::NotReady));
    assert_eq!(sample_with_diag(DIAAGC_LF | DIAAGC_COF), Err(Error::CordicOverflow));
    assert_eq!(sample_with_diag(DIAAGC_LF | DIAAGC_MAGH), Err(Error::Magnet { too_strong: true, too_weak: false }));
    assert_eq!(sample_with_diag(DIAAGC_LF | DIAAGC_MAGL | 0xFF), Err(Error::Magnet { too_strong: false, too_weak: true }));
    // LF = 0 wins over the other bits: they mean nothing before it.
    assert_eq!(sample_with_diag(DIAAGC_MAGL | DIAAGC_COF), Err(Error::NotReady));
    assert_eq!(sample_with_diag(DIAAGC_LF | 0x80), Ok(0x0123));
}

#[test]
fn parity_error_in_any_answer_is_reported_with_the_frame() {
    // 0x0001 has one 1 and no parity bit: odd.
    let mut spi = mock(&[(RD_ANGLECOM, 0x0001)]);
    assert_eq!(As5047p::new(spi.clone()).angle(), Err(Error::Parity { frame: 0x0001 }));
    spi.done();
    let mut spi = mock(&[(RD_ANGLECOM, 0), (RD_NOP, 0x9235)]);
    assert_eq!(As5047p::new(spi.clone()).angle(), Err(Error::Parity { frame: 0x9235 }));
    spi.done();
}

#[test]
fn error_flag_reads_and_reports_errfl() {
    // EF in the angle's answer; ERRFL = PARERR: 0x0004 -> one 1 -> 0x8004.
    let mut spi = mock(&[(RD_ANGLECOM, 0), (RD_NOP, answer(0x1000, true)), (RD_ERRFL, answer(0, true)), (RD_NOP, 0x8004)]);
    assert_eq!(As5047p::new(spi.clone()).angle(), Err(Error::ErrorFlag { errfl: ERRFL_PARERR }));
    spi.done();
    // EF in the first (stale) answer counts too.
    let mut spi = mock(&[
        (RD_ANGLECOM, answer(0, true)),
        (RD_DIAAGC, answer(5, false)),
        (RD_NOP, answer(DIAAGC_LF, false)),
        (RD_ERRFL, answer(0, false)),
        (RD_NOP, answer(ERRFL_FRERR | ERRFL_INVCOMM, false)),
    ]);
    assert_eq!(As5047p::new(spi.clone()).sample(), Err(Error::ErrorFlag { errfl: ERRFL_FRERR | ERRFL_INVCOMM }));
    spi.done();
}

#[test]
fn error_flag_with_unreadable_errfl_reports_unknown() {
    let mut spi = mock(&[(RD_ANGLECOM, 0), (RD_NOP, answer(1, true)), (RD_ERRFL, 0), (RD_NOP, 0x0001)]);
    assert_eq!(As5047p::new(spi.clone()).angle(), Err(Error::ErrorFlag { errfl: ERRFL_UNKNOWN }));
    spi.done();
}

#[test]
fn miso_high_is_an_error_flag_and_miso_low_is_not_ready() {
    // Floating high: 0xFFFF has even parity and EF set; ERRFL reads 0x3FFF.
    let mut spi =
        mock(&[(RD_ERRFL, 0xFFFF), (RD_NOP, 0xFFFF), (RD_DIAAGC, 0xFFFF), (RD_NOP, 0xFFFF), (RD_ERRFL, 0xFFFF), (RD_NOP, 0xFFFF)]);
    assert_eq!(As5047p::new(spi.clone()).check_ready(), Err(Error::ErrorFlag { errfl: 0x3FFF }));
    spi.done();
    // No chip, MISO pulled low: every check passes but LF.
    let mut spi = mock(&[(RD_ERRFL, 0), (RD_NOP, 0), (RD_DIAAGC, 0), (RD_NOP, 0)]);
    assert_eq!(As5047p::new(spi.clone()).check_ready(), Err(Error::NotReady));
    spi.done();
}

#[test]
fn check_ready_clears_errfl_and_returns_diagnostics() {
    let diag = DIAAGC_LF | 0x5A;
    let mut spi = mock(&[(RD_ERRFL, answer(0, true)), (RD_NOP, answer(ERRFL_FRERR, true)), (RD_DIAAGC, 0), (RD_NOP, answer(diag, false))]);
    let d = As5047p::new(spi.clone()).check_ready().unwrap();
    assert_eq!(
        d,
        Diagnostics {
            agc: 0x5A,
            offset_compensation_finished: true,
            cordic_overflow: false,
            magnet_too_strong: false,
            magnet_too_weak: false
        }
    );
    spi.done();
}

#[test]
fn diagnostics_and_error_flags_and_read_register() {
    let spi = mock(&[
        (RD_DIAAGC, 0),
        (RD_NOP, answer(DIAAGC_COF | DIAAGC_MAGH | DIAAGC_MAGL | 0x12, false)),
        (RD_ERRFL, 0),
        (RD_NOP, answer(ERRFL_INVCOMM, true)),
        (read_command(0x0016), 0),
        (RD_NOP, answer(0x0ABC, false)),
    ]);
    let mut enc = As5047p::new(spi.clone());
    let d = enc.diagnostics().unwrap();
    assert_eq!(
        d,
        Diagnostics {
            agc: 0x12,
            offset_compensation_finished: false,
            cordic_overflow: true,
            magnet_too_strong: true,
            magnet_too_weak: true
        }
    );
    assert_eq!(enc.error_flags(), Ok(ERRFL_INVCOMM));
    assert_eq!(enc.read_register(0x0016), Ok(0x0ABC));
    // The released device shares the mock's expectations.
    enc.release().done();
}

/// A device that fails its `n`-th frame (counting from 0) and otherwise
/// forwards to the mock (the 0.11 SPI mock cannot inject errors).
struct FailAt {
    inner: Mock<u16>,
    n: usize,
    frames: usize,
}

impl ErrorType for FailAt {
    type Error = ErrorKind;
}

impl SpiDevice<u16> for FailAt {
    fn transaction(&mut self, ops: &mut [Operation<'_, u16>]) -> Result<(), ErrorKind> {
        let k = self.frames;
        self.frames += 1;
        if k == self.n { Err(ErrorKind::ModeFault) } else { self.inner.transaction(ops) }
    }
}

#[test]
fn bus_errors_propagate() {
    // Fails on the first frame.
    let mut spi = mock(&[]);
    let mut enc = As5047p::new(FailAt { inner: spi.clone(), n: 0, frames: 0 });
    assert_eq!(enc.angle(), Err(Error::Bus(ErrorKind::ModeFault)));
    spi.done();
    // Fails on the last frame of a sample.
    let mut spi = mock(&[(RD_ANGLECOM, 0), (RD_DIAAGC, 0)]);
    let mut enc = As5047p::new(FailAt { inner: spi.clone(), n: 2, frames: 0 });
    assert_eq!(enc.sample(), Err(Error::Bus(ErrorKind::ModeFault)));
    spi.done();
    // EF, then the ERRFL read fails on the bus: EF is still reported.
    let mut spi = mock(&[(RD_ANGLECOM, 0), (RD_NOP, answer(7, true)), (RD_ERRFL, 0)]);
    let mut enc = As5047p::new(FailAt { inner: spi.clone(), n: 3, frames: 0 });
    assert_eq!(enc.angle(), Err(Error::ErrorFlag { errfl: ERRFL_UNKNOWN }));
    spi.done();
}

#[test]
fn display_names_the_problem() {
    let e: Error<ErrorKind> = Error::Parity { frame: 0x0001 };
    assert_eq!(format!("{e}"), "AS5047P: parity error in answer 0x0001");
}

proptest! {
    #[test]
    fn commands_have_even_parity_and_keep_their_address(addr in any::<u16>()) {
        let c = read_command(addr);
        prop_assert!(has_even_parity(c));
        prop_assert_eq!(c & DATA, addr & DATA);
        prop_assert_eq!(c & READ, READ);
    }

    #[test]
    fn any_angle_round_trips(angle in 0u16..COUNTS_PER_REV) {
        let mut spi = mock(&[(RD_ANGLECOM, 0), (RD_NOP, answer(angle, false))]);
        prop_assert_eq!(As5047p::new(spi.clone()).angle(), Ok(angle));
        spi.done();
    }
}

mod sequence {
    use super::*;
    use crate::as5047p::{SAMPLE_MAX_FRAMES, SampleSequence};

    /// Runs a sequence against `answer_of(frame_index, command)`.
    fn run(mut answer_of: impl FnMut(usize, u16) -> Option<u16>) -> (Vec<u16>, Result<u16, Error<()>>) {
        let mut seq = SampleSequence::new();
        let mut sent = Vec::new();
        while let Some(c) = seq.command() {
            match answer_of(sent.len(), c) {
                Some(a) => seq.answer(a),
                None => seq.transfer_failed(),
            }
            sent.push(c);
            assert!(sent.len() <= SAMPLE_MAX_FRAMES);
        }
        (sent, seq.outcome().expect("a finished sequence has an outcome"))
    }

    #[test]
    fn a_clean_sample_is_three_frames() {
        let answers = [answer(0x155, false), answer(0x2ABC, false), answer(DIAAGC_LF | 0x80, false)];
        let (sent, out) = run(|i, _| Some(answers[i]));
        assert_eq!(sent, vec![read_command(REG_ANGLECOM), read_command(REG_DIAAGC), read_command(REG_NOP)]);
        assert_eq!(out, Ok(0x2ABC));
    }

    #[test]
    fn an_error_flag_reads_errfl_in_two_more_frames() {
        let answers = [answer(0, false), answer(0x10, true), answer(DIAAGC_LF, false), answer(0, true), answer(ERRFL_PARERR, false)];
        let (sent, out) = run(|i, _| Some(answers[i]));
        assert_eq!(sent.len(), 5);
        assert_eq!(sent[3], read_command(REG_ERRFL));
        assert_eq!(out, Err(Error::ErrorFlag { errfl: ERRFL_PARERR }));
    }

    #[test]
    fn a_failed_transfer_is_a_bus_error_then_unknown_errfl() {
        assert_eq!(run(|i, _| (i < 1).then_some(0)).1, Err(Error::Bus(())));
        let answers = [answer(0, true), answer(0, false), answer(DIAAGC_LF, false)];
        assert_eq!(run(|i, _| answers.get(i).copied()).1, Err(Error::ErrorFlag { errfl: ERRFL_UNKNOWN }));
        assert_eq!(Error::Bus(()).with_bus(Some(7u8)), Error::Bus(7));
    }

    proptest! {
        #[test]
        fn the_blocking_sample_sends_the_sequences_frames_and_returns_its_outcome(
            answers in proptest::collection::vec(any::<u16>(), SAMPLE_MAX_FRAMES),
        ) {
            // The sequence alone, then As5047p::sample over a mock expecting
            // exactly the sequence's frames: the same outcome.
            let (sent, out) = run(|i, _| Some(answers[i]));
            let frames: Vec<(u16, u16)> = sent.iter().zip(&answers).map(|(&c, &a)| (c, a)).collect();
            let mut spi = mock(&frames);
            let got = As5047p::new(spi.clone()).sample();
            spi.done();
            prop_assert_eq!(got, out.map_err(|e| e.with_bus(None::<ErrorKind>)));
        }
    }
}
