//! A closed-loop run's two streamed tables (`run`, `pil`): the trace, one
//! [`PeriodRecord`] per control period, and what crossed the wire, one
//! [`FrameRow`] per period (the frame the firmware read and its answer, for
//! `sil-host replay`). As `trace.csv` and `frames.csv`, as `trace.arrow` and
//! `frames.arrow`, or both in one `trace.mcap` ([`McapPairStream`]: the frames on
//! the `/wire/...` channels), each written as the run makes it.

use crate::{
    error::CliError,
    output::{OutputSet, StreamedTable, View},
};
use rig::{frames::FrameRow, record::PeriodRecord};
use tables::TableFormat;
#[cfg(feature = "formats")]
use tables::mcap::{McapPairStream, McapView};

/// The trace and the frames of a run being written.
pub enum RunTables {
    /// A file each (CSV or Arrow), each a [`StreamedTable`]: `trace.csv` and
    /// `frames.csv`, or `trace.arrow` and `frames.arrow` (boxed: the pair is
    /// larger than the MCAP stream's box).
    Two(Box<(StreamedTable<PeriodRecord>, StreamedTable<FrameRow>)>),
    /// One `trace.mcap`, and the first write error, kept for [`RunTables::finish`].
    #[cfg(feature = "formats")]
    Mcap(Box<McapPairStream<PeriodRecord, FrameRow>>, Option<CliError>),
}

impl RunTables {
    /// Starts the tables in `out` in `format`; an MCAP file carries the trace's
    /// `view` (the arm in Foxglove's schemas). CSV and Arrow are flushed every
    /// `flush_every` of wall time ([`StreamedTable`]); MCAP every
    /// [`tables::mcap::STREAM_CHUNK_ROWS`] periods.
    ///
    /// # Errors
    /// [`CliError::Io`] when a file cannot be created or its header written;
    /// [`CliError::BadInput`] for Arrow or MCAP in a build without `formats`.
    pub fn new(
        out: &mut OutputSet,
        format: TableFormat,
        flush_every: std::time::Duration,
        view: View<PeriodRecord>,
    ) -> Result<Self, CliError> {
        crate::features::require_format(format)?;
        #[cfg(feature = "formats")]
        if format == TableFormat::Mcap {
            let (path, file) = out.create_streamed(&format.file("trace"))?;
            let views = (view, None::<Box<dyn McapView<FrameRow>>>);
            return Ok(Self::Mcap(Box::new(McapPairStream::new(path, file, views)?), None));
        }
        let trace = StreamedTable::new(out, "trace", format, flush_every, view)?;
        #[cfg(feature = "formats")]
        let no_view = None;
        #[cfg(not(feature = "formats"))]
        let no_view = std::marker::PhantomData;
        let frames = StreamedTable::new(out, "frames", format, flush_every, no_view)?;
        Ok(Self::Two(Box::new((trace, frames))))
    }

    /// Appends a period's record. A write error is kept (and later rows
    /// dropped) for [`RunTables::finish`]: a run is not stopped by its files.
    pub fn push_record(&mut self, r: &PeriodRecord) {
        match self {
            Self::Two(two) => two.0.push(r),
            #[cfg(feature = "formats")]
            Self::Mcap(stream, error) => {
                if error.is_none()
                    && let Err(e) = stream.push_a(*r)
                {
                    *error = Some(e.into());
                }
            }
        }
    }

    /// Appends a period's frame and answer.
    pub fn push_frame(&mut self, f: &FrameRow) {
        match self {
            Self::Two(two) => two.1.push(f),
            #[cfg(feature = "formats")]
            Self::Mcap(stream, error) => {
                if error.is_none() {
                    stream.push_b(*f);
                }
            }
        }
    }

    /// Writes the rest and closes the files.
    ///
    /// # Errors
    /// The first write error, if any.
    pub fn finish(self) -> Result<(), CliError> {
        match self {
            Self::Two(two) => {
                let (trace, frames) = *two;
                trace.finish()?;
                frames.finish()
            }
            #[cfg(feature = "formats")]
            Self::Mcap(stream, error) => match error {
                Some(e) => Err(e),
                None => Ok(stream.finish()?),
            },
        }
    }
}
