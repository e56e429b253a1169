//! A table file written by a thread of its own ([`WriterThread`]), whatever its
//! format ([`RowSink`]: CSV's [`crate::csv::CsvFile`], Arrow's
//! `crate::arrow::ArrowFile`): the caller hands over chunks of rows and goes on
//! (the simulation) while the thread formats and writes them, so on two cores a
//! long table costs little more than the simulation alone. At most
//! [`WriterThread::DEPTH`] chunks wait in the channel (bounded memory); emptied
//! chunks come back for reuse; the join reports the writer's error.
//!
//! The thread only moves the sink's calls to another thread: the file is the same,
//! byte for byte, as the sink writes given the same rows in the same chunks
//! (tested for both formats).

use std::{
    marker::PhantomData,
    path::{Path, PathBuf},
    sync::mpsc::{Receiver, SyncSender, sync_channel},
    thread::JoinHandle,
};

use crate::error::{Error, io_err};

/// A table file that takes rows of `T` a chunk at a time: what a [`WriterThread`]
/// writes to.
pub trait RowSink<T>: Send + 'static {
    /// The writer thread's name (`csv-writer`), as the OS and a debugger show it.
    const THREAD_NAME: &'static str;
    /// The format's name in the error of a writer thread that panicked (`CSV`).
    const FORMAT: &'static str;

    /// The file's path, for error messages.
    fn path(&self) -> &Path;

    /// Takes every row of `rows` in order, leaving it empty (its capacity kept).
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    fn write_rows(&mut self, rows: &mut Vec<T>) -> Result<(), Error>;

    /// Writes what is still waiting (and a format's footer) and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    fn finish(self) -> Result<(), Error>;
}

/// A [`RowSink`] written by a thread of its own (module docs): [`crate::csv::CsvThread`]
/// for CSV, `crate::arrow::ArrowThread` for an Arrow IPC file.
pub struct WriterThread<T: Send + 'static, S: RowSink<T>> {
    to_writer: Option<SyncSender<Vec<T>>>,
    from_writer: Receiver<Vec<T>>,
    writer: Option<JoinHandle<Result<(), Error>>>,
    path: PathBuf,
    sink: PhantomData<fn(S)>,
}

impl<T: Send + 'static, S: RowSink<T>> WriterThread<T, S> {
    /// Chunks waiting in the channel at most.
    pub const DEPTH: usize = 4;

    /// Starts the thread that writes `sink` (a file just made, its header written).
    ///
    /// # Errors
    /// [`Error::Io`] on `sink`'s path when the thread cannot be started.
    pub fn spawn(mut sink: S) -> Result<Self, Error> {
        let (to_writer, rx) = sync_channel::<Vec<T>>(Self::DEPTH);
        let (back, from_writer) = sync_channel::<Vec<T>>(Self::DEPTH + 2);
        let path = sink.path().to_path_buf();
        let writer = std::thread::Builder::new()
            .name(S::THREAD_NAME.into())
            .spawn(move || {
                for mut rows in rx {
                    sink.write_rows(&mut rows)?;
                    // The caller may have stopped taking them back: then drop it.
                    let _ = back.try_send(rows);
                }
                sink.finish()
            })
            .map_err(io_err(&path))?;
        Ok(Self { to_writer: Some(to_writer), from_writer, writer: Some(writer), path, sink: PhantomData })
    }

    /// Hands `rows` to the writer and returns an empty chunk to fill next (one
    /// the writer is done with, or a new one of the same capacity).
    ///
    /// # Errors
    /// The writer's [`Error::Io`] if it has stopped on one.
    pub fn send(&mut self, rows: Vec<T>) -> Result<Vec<T>, Error> {
        let capacity = rows.capacity();
        let sent = self.to_writer.as_ref().is_some_and(|tx| tx.send(rows).is_ok());
        if !sent {
            // The writer only hangs up on an error: report it.
            self.join()?;
        }
        Ok(self.from_writer.try_recv().unwrap_or_else(|_| Vec::with_capacity(capacity)))
    }

    /// Waits for the writer to write every row (and the format's footer) and
    /// close the file.
    ///
    /// # Errors
    /// The writer's [`Error::Io`], if any; [`Error::Io`] on the file's path if
    /// the writer thread panicked.
    pub fn finish(mut self) -> Result<(), Error> {
        self.join()
    }

    fn join(&mut self) -> Result<(), Error> {
        self.to_writer = None;
        match self.writer.take() {
            Some(h) => h.join().unwrap_or_else(|_| {
                Err(Error::Io {
                    path: self.path.clone(),
                    source: std::io::Error::other(format!("the {} writer thread panicked", S::FORMAT)),
                })
            }),
            None => Ok(()),
        }
    }
}

impl<T: Send + 'static, S: RowSink<T>> Drop for WriterThread<T, S> {
    fn drop(&mut self) {
        // Unwinding or an early return: let the writer finish its rows, ignore errors.
        let _ = self.join();
    }
}

#[cfg(test)]
mod tests {
    use std::sync::{Arc, Mutex};

    use super::*;

    /// What a [`Recorder`] saw: the rows, the chunks' sizes, whether it was finished.
    type Seen = Arc<Mutex<(Vec<u32>, Vec<usize>, bool)>>;

    /// A sink that keeps what it is given: the rows, in order, and the chunks'
    /// sizes; fails on the row `fail_at`, panics on the row `panic_at`.
    struct Recorder {
        path: PathBuf,
        seen: Seen,
        fail_at: Option<u32>,
        panic_at: Option<u32>,
    }

    impl RowSink<u32> for Recorder {
        const THREAD_NAME: &'static str = "test-writer";
        const FORMAT: &'static str = "test";

        fn path(&self) -> &Path {
            &self.path
        }

        fn write_rows(&mut self, rows: &mut Vec<u32>) -> Result<(), Error> {
            assert_eq!(std::thread::current().name(), Some(Self::THREAD_NAME));
            let mut seen = self.seen.lock().unwrap();
            seen.1.push(rows.len());
            for r in rows.drain(..) {
                if Some(r) == self.fail_at {
                    return Err(Error::other(&self.path, "the disk is full"));
                }
                assert!(Some(r) != self.panic_at, "a broken sink");
                seen.0.push(r);
            }
            Ok(())
        }

        fn finish(self) -> Result<(), Error> {
            self.seen.lock().unwrap().2 = true;
            Ok(())
        }
    }

    fn recorder(fail_at: Option<u32>, panic_at: Option<u32>) -> (Recorder, Seen) {
        let seen = Arc::new(Mutex::new((Vec::new(), Vec::new(), false)));
        (Recorder { path: "t.rows".into(), seen: seen.clone(), fail_at, panic_at }, seen)
    }

    #[test]
    fn every_row_reaches_the_sink_in_order_in_the_chunks_sent() {
        let (sink, seen) = recorder(None, None);
        let mut w = WriterThread::spawn(sink).unwrap();
        let mut next = 0u32;
        let mut chunk = Vec::with_capacity(10);
        for size in [3usize, 10, 1, 7, 10, 10, 2] {
            chunk.extend(next..next + size as u32);
            next += size as u32;
            chunk = w.send(chunk).unwrap();
            // An empty chunk back, of the capacity sent (the writer's or a new one).
            assert!(chunk.is_empty() && chunk.capacity() >= 10);
        }
        w.finish().unwrap();
        let seen = seen.lock().unwrap();
        assert_eq!(seen.0, (0..next).collect::<Vec<u32>>());
        assert_eq!(seen.1, [3, 10, 1, 7, 10, 10, 2]);
        assert!(seen.2, "finished");
    }

    #[test]
    fn the_sinks_error_is_reported_by_send_or_finish() {
        let (sink, seen) = recorder(Some(25), None);
        let mut w = WriterThread::spawn(sink).unwrap();
        let mut error = None;
        for c in 0..100u32 {
            if let Err(e) = w.send((c * 10..c * 10 + 10).collect()) {
                error = Some(e);
                break;
            }
        }
        let error = error.or_else(|| w.finish().err()).expect("an error");
        assert!(error.to_string().contains("the disk is full") && error.to_string().contains("t.rows"), "{error}");
        let seen = seen.lock().unwrap();
        // The rows before the failing one were written, the file was not finished.
        assert_eq!(seen.0, (0..25).collect::<Vec<u32>>());
        assert!(!seen.2);
    }

    #[test]
    fn a_writer_that_panics_is_an_error_naming_the_format_and_the_file() {
        let (sink, _) = recorder(None, Some(3));
        let mut w = WriterThread::spawn(sink).unwrap();
        let _ = w.send(vec![1, 2, 3, 4]);
        let error = w.finish().unwrap_err();
        assert_eq!(error.to_string(), "cannot write t.rows: the test writer thread panicked");
    }
}
