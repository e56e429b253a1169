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
//! [`crate::BusFaults::acquisition`]). No frame then reaches the encoders, and
//! both readings of the period are invalid, as on the image.

use arm_app::{Blocking, EncoderAcquisition, EncoderFault};
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
        if let Some(fault) = crate::bench::lock(&self.bench).acquisition {
            return [Err(EncoderFault::Acquisition(fault)); 2];
        }
        Blocking.acquire(theta1, elbow)
    }
}
