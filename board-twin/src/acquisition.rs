//! The encoders' acquisition as the `arm` image makes it (docs/board.md "The
//! encoders by DMA"), at the bus level: at the tick, theta1's frames of
//! `drivers::as5047p::SampleSequence`, then the elbow's, one chip-select
//! assertion each, on the AS5047P models ([`crate::as5047p`]). The image moves
//! the same frames by DMA2 (SPI1_TX on stream 3, SPI1_RX on stream 0, channel
//! 3; RM0090 10.3.3 table 43) and finds them in memory when its control
//! interrupt runs; the twin, whose step takes no time, exchanges them in the
//! tick.
//!
//! The acquisition's own faults act before the first frame: a stream's
//! TEIF, FEIF or DMEIF, frames not done by the deadline, a stuck chip select
//! ([`arm_app::AcquisitionFault`], set on the bench from
//! [`crate::BusFaults::acquisition`], or a stuck chip select from an encoder's
//! [`crate::bench::EncoderFaults::chip_select_stuck`]). No frame then reaches
//! the encoders, and both readings of the period are invalid, as on the image
//! (which, for the elbow's chip select, has sent theta1's frames first: the
//! period's readings are the same).

use arm_app::{AcquisitionFault, Blocking, EncoderAcquisition, EncoderFault};
use drivers::As5047p;

use crate::{as5047p::As5047pModel, bench::Shared};

/// The twin's acquisition of both encoders.
#[derive(Debug)]
pub struct TwinAcquisition {
    bench: Shared,
}

impl TwinAcquisition {
    /// The acquisition on `bench`'s encoders.
    pub fn new(bench: Shared) -> Self {
        Self { bench }
    }
}

impl EncoderAcquisition<As5047pModel> for TwinAcquisition {
    fn acquire(&mut self, theta1: &mut As5047p<As5047pModel>, elbow: &mut As5047p<As5047pModel>) -> [Result<u16, EncoderFault>; 2] {
        let fault = {
            let b = crate::bench::lock(&self.bench);
            b.acquisition.or_else(|| b.encoder_faults.iter().any(|f| f.chip_select_stuck).then_some(AcquisitionFault::StuckChipSelect))
        };
        if let Some(fault) = fault {
            return [Err(EncoderFault::Acquisition(fault)); 2];
        }
        Blocking.acquire(theta1, elbow)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{Bench, lock};
    use arm_app::AcquisitionFault as F;

    fn pair(bench: &Shared) -> (As5047p<As5047pModel>, As5047p<As5047pModel>) {
        (As5047p::new(As5047pModel::new(bench.clone(), 0)), As5047p::new(As5047pModel::new(bench.clone(), 1)))
    }

    #[test]
    fn a_clean_acquisition_samples_both_encoders_in_three_frames_each() {
        let bench: Shared = std::sync::Arc::new(std::sync::Mutex::new(Bench::default()));
        lock(&bench).magnet_counts = [1234.4, 16000.6];
        let (mut a, mut b) = pair(&bench);
        let got = TwinAcquisition::new(bench.clone()).acquire(&mut a, &mut b);
        assert_eq!(got, [Ok(1234), Ok(16001)]);
        assert_eq!([a.release().frames, b.release().frames], [3, 3]);
    }

    #[test]
    fn every_acquisition_fault_invalidates_both_encoders_and_sends_no_frame() {
        for fault in [F::TransferError, F::FifoError, F::DirectModeError, F::Timeout, F::StuckChipSelect] {
            let bench: Shared = std::sync::Arc::new(std::sync::Mutex::new(Bench::default()));
            lock(&bench).acquisition = Some(fault);
            let (mut a, mut b) = pair(&bench);
            let got = TwinAcquisition::new(bench.clone()).acquire(&mut a, &mut b);
            assert_eq!(got, [Err(EncoderFault::Acquisition(fault)); 2], "{fault:?}");
            assert_eq!([a.release().frames, b.release().frames], [0, 0], "{fault:?}");
            assert!(!fault.describe().is_empty());
        }
    }

    #[test]
    fn either_encoders_stuck_chip_select_fails_the_acquisition_by_name() {
        for chip in 0..2 {
            let bench: Shared = std::sync::Arc::new(std::sync::Mutex::new(Bench::default()));
            lock(&bench).encoder_faults[chip].chip_select_stuck = true;
            let (mut a, mut b) = pair(&bench);
            let got = TwinAcquisition::new(bench.clone()).acquire(&mut a, &mut b);
            assert_eq!(got, [Err(EncoderFault::Acquisition(F::StuckChipSelect)); 2], "chip {chip}");
            assert_eq!([a.release().frames, b.release().frames], [0, 0], "chip {chip}");
        }
    }
}
