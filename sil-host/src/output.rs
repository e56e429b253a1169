//! Output folders whose files appear whole or not at all.
//!
//! Every file is written under a temporary name in the target folder and
//! renamed into place by [`OutputSet::commit`]; if a command fails before it
//! commits, the temporary files are removed when the set is dropped, so a bad
//! run never leaves half-written results (or clobbers a previous run's).
//!
//! No file is written through a link (issue 52, 5): every temporary file is made
//! new ([`rig::private_files::create_new`]: `O_CREAT | O_EXCL | O_NOFOLLOW`) after
//! removing what a killed run left at its name (a link itself, never its target,
//! or a regular file of ours), and a rename replaces a link at the final name
//! rather than following it. A link planted in a shared `--out` folder (another
//! user's, in a folder with the sticky bit such as `/tmp/x`) therefore never
//! redirects an output; anything else in the way (a folder, another user's file)
//! is refused with the path named.

use std::{
    fs::File,
    io::{BufWriter, Write},
    path::{Path, PathBuf},
};

use crate::{error::CliError, folder_lock::FolderLock};
use tables::{
    TableFormat,
    csv::{CsvFile, CsvRow},
    mcap::McapRows,
};
#[cfg(feature = "formats")]
use tables::{
    arrow::StreamedArrowFile,
    mcap::{McapStream, McapView},
};

/// A set of output files written into one folder, committed together.
#[derive(Debug)]
pub struct OutputSet {
    dir: PathBuf,
    pending: Vec<(PathBuf, PathBuf)>,
    /// Files written as they are produced: renamed on commit, kept otherwise.
    streamed: Vec<(PathBuf, PathBuf)>,
    committed: bool,
    /// The folder's lock, held until the set is dropped.
    _lock: FolderLock,
}

impl OutputSet {
    /// Creates the folder `dir` (and its parents) if needed and locks it
    /// ([`FolderLock`]) until the set is dropped.
    ///
    /// # Errors
    /// [`CliError::Io`] when the folder cannot be created;
    /// [`CliError::FolderInUse`] (exit 2) when another process writes into it.
    pub fn new(dir: &Path) -> Result<Self, CliError> {
        let lock = FolderLock::acquire(dir)?;
        Ok(Self { dir: dir.to_path_buf(), pending: Vec::new(), streamed: Vec::new(), committed: false, _lock: lock })
    }

    /// The folder the files go to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The final path of output file `name`.
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// Opens `name` for writing (under a temporary name until [`OutputSet::commit`])
    /// and returns the temporary path with a buffered writer.
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created.
    pub fn create(&mut self, name: &str) -> Result<(PathBuf, BufWriter<File>), CliError> {
        let (tmp, file) = self.create_unbuffered(name)?;
        Ok((tmp, BufWriter::new(file)))
    }

    /// As [`OutputSet::create`], for writers that buffer themselves
    /// ([`tables::csv::CsvFile`]).
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created.
    pub fn create_unbuffered(&mut self, name: &str) -> Result<(PathBuf, File), CliError> {
        let tmp = self.dir.join(format!(".{name}.partial"));
        let file = create_new(&tmp)?;
        self.pending.push((tmp.clone(), self.dir.join(name)));
        Ok((tmp, file))
    }

    /// Starts the CSV file `name` ([`tables::csv::CsvFile`]) with its header row `header`.
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created.
    pub fn create_csv(&mut self, name: &str, header: &[&str]) -> Result<CsvFile, CliError> {
        let (tmp, file) = self.create_unbuffered(name)?;
        Ok(CsvFile::new(tmp, file, header))
    }

    /// Opens `name` for writing as it is produced: it is written as
    /// `name.partial` (visible) until [`OutputSet::commit`] renames it, and unlike
    /// the other files it is kept if the command fails or is killed, so rows
    /// already flushed survive even a SIGKILL.
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created.
    pub fn create_streamed(&mut self, name: &str) -> Result<(PathBuf, File), CliError> {
        let final_path = self.dir.join(name);
        let tmp = self.dir.join(format!("{name}.partial"));
        let file = create_new(&tmp)?;
        self.streamed.push((tmp.clone(), final_path));
        Ok((tmp, file))
    }

    /// Reserves a temporary path for `name` (for writers that open files themselves,
    /// such as plotters' SVG backend): the file is made there, new and empty, so
    /// that the writer opens a regular file of ours, not a link.
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be made (something not ours in the way).
    pub fn stage(&mut self, name: &str) -> Result<PathBuf, CliError> {
        let (tmp, _) = self.create_unbuffered(name)?;
        Ok(tmp)
    }

    /// Reserves temporary paths for the figure `name` (an `.svg`) and its PDF
    /// (the same name with `.pdf`, at [`figures::plot::print::pdf_path`] of the SVG's
    /// temporary path), both made as [`OutputSet::stage`] makes its file and
    /// renamed on commit; returns the SVG's. Built without the feature `pdf`, the
    /// SVG's alone (said once on standard error).
    ///
    /// # Errors
    /// As [`OutputSet::stage`].
    pub fn stage_figure(&mut self, name: &str) -> Result<PathBuf, CliError> {
        let svg = self.stage(name)?;
        if !figures::plot::print::WRITES_PDF {
            crate::features::note_svg_only();
            return Ok(svg);
        }
        let pdf_final = self.dir.join(Path::new(name).with_extension("pdf"));
        let pdf = figures::plot::print::pdf_path(&svg);
        create_new(&pdf)?;
        self.pending.push((pdf, pdf_final));
        Ok(svg)
    }

    /// Writes `bytes` as file `name`.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn write_bytes(&mut self, name: &str, bytes: &[u8]) -> Result<(), CliError> {
        let (tmp, mut w) = self.create(name)?;
        w.write_all(bytes).and_then(|_| w.flush()).map_err(|source| CliError::Io { path: tmp, source })
    }

    /// Writes `value` as pretty JSON in file `name` and returns the text (for
    /// `--json` on standard output).
    ///
    /// # Errors
    /// [`CliError::Io`] when serialising or writing fails.
    pub fn write_json<T: serde::Serialize>(&mut self, name: &str, value: &T) -> Result<String, CliError> {
        let json = serde_json::to_string_pretty(value).map_err(|e| CliError::Io { path: self.path(name), source: e.into() })?;
        self.write_bytes(name, json.as_bytes())?;
        Ok(json)
    }

    /// Renames every staged file to its final name.
    ///
    /// # Errors
    /// [`CliError::Io`] when a rename fails.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, CliError> {
        let mut done = Vec::new();
        let mut all = std::mem::take(&mut self.pending);
        all.append(&mut self.streamed);
        for (tmp, final_path) in all {
            std::fs::rename(&tmp, &final_path).map_err(|source| CliError::Io { path: final_path.clone(), source })?;
            done.push(final_path);
        }
        self.committed = true;
        Ok(done)
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.committed {
            for (tmp, _) in &self.pending {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}

pub use crate::error::io_err;

/// [`rig::private_files::create_new`] with the error naming `path`.
fn create_new(path: &Path) -> Result<File, CliError> {
    rig::private_files::create_new(path).map_err(io_err(path))
}

/// Writes `rows` as CSV file `name` of `out` (a header row from the field names).
///
/// # Errors
/// [`CliError::Io`] when writing fails.
pub fn write_csv<T: serde::Serialize>(out: &mut OutputSet, name: &str, rows: &[T]) -> Result<(), CliError> {
    let (tmp, w) = out.create(name)?;
    let mut csv_w = csv::Writer::from_writer(w);
    for row in rows {
        csv_w.serialize(row).map_err(|e| CliError::Io { path: tmp.clone(), source: e.into() })?;
    }
    csv_w.flush().map_err(io_err(&tmp))
}

/// The view of a table in an MCAP file ([`tables::mcap::McapView`]: channels drawn
/// from its rows), if any.
#[cfg(feature = "formats")]
pub type View<T> = Option<Box<dyn McapView<T>>>;

/// No view: a build without the feature `formats` writes no MCAP file.
#[cfg(not(feature = "formats"))]
pub type View<T> = std::marker::PhantomData<T>;

/// A table written row by row as a run produces it ([`OutputSet::create_streamed`]),
/// as CSV, as an Arrow IPC file or as MCAP (`--format`). CSV and Arrow are
/// flushed to the operating system at least every `flush_every` of wall time: a
/// process killed outright (SIGKILL) loses at most the rows of that interval. CSV
/// rows are formatted by [`tables::csv`] (the bytes of the `csv`
/// crate's serde path); Arrow rows go out one record batch per flush
/// ([`tables::arrow::StreamedArrowFile`], the footer at the end). MCAP rows go out one chunk per
/// [`tables::mcap::STREAM_CHUNK_ROWS`] rows, flushed at once
/// ([`tables::mcap::McapStream`]): counted in rows, not wall time, so
/// the file's bytes are the same over every link.
pub struct StreamedTable<T: CsvRow + McapRows + Copy + 'static> {
    writer: StreamedWriter<T>,
    flush_every: std::time::Duration,
    last_flush: std::time::Instant,
    error: Option<CliError>,
}

/// The file behind a [`StreamedTable`].
enum StreamedWriter<T: McapRows + 'static> {
    Csv(CsvFile),
    #[cfg(feature = "formats")]
    Arrow(Box<StreamedArrowFile<T>>),
    #[cfg(feature = "formats")]
    Mcap(Box<McapStream<T>>),
    /// Never made (keeps `T` used in a build without `formats`).
    #[cfg(not(feature = "formats"))]
    #[allow(dead_code)]
    Never(std::marker::PhantomData<T>),
}

impl<T: CsvRow + McapRows + Copy + 'static> StreamedTable<T> {
    /// Starts table `stem` (`trace`: `trace.csv`, `trace.arrow` or `trace.mcap`)
    /// in `out`, flushed every `flush_every` (CSV, Arrow); an MCAP file carries
    /// `view`'s channels too ([`tables::mcap::McapView`]: the arm in Foxglove's schemas).
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created (or the Arrow schema, the
    /// MCAP header and channels written); [`CliError::BadInput`] for Arrow or MCAP
    /// in a build without the feature `formats`.
    pub fn new(
        out: &mut OutputSet,
        stem: &str,
        format: TableFormat,
        flush_every: std::time::Duration,
        view: View<T>,
    ) -> Result<Self, CliError> {
        crate::features::require_format(format)?;
        let (path, file) = out.create_streamed(&format.file(stem))?;
        #[cfg(not(feature = "formats"))]
        let _ = view;
        let writer = match format {
            TableFormat::Csv => StreamedWriter::Csv(CsvFile::new(path, file, T::HEADER)),
            #[cfg(feature = "formats")]
            TableFormat::Arrow => StreamedWriter::Arrow(Box::new(StreamedArrowFile::new(path, file)?)),
            #[cfg(feature = "formats")]
            TableFormat::Mcap => StreamedWriter::Mcap(Box::new(McapStream::with_view(path, file, view)?)),
            #[cfg(not(feature = "formats"))]
            other @ (TableFormat::Arrow | TableFormat::Mcap) => return Err(crate::features::format_missing(other)),
        };
        Ok(Self { writer, flush_every, last_flush: std::time::Instant::now(), error: None })
    }

    /// Appends one row. The first write error is kept (and later rows dropped)
    /// for [`StreamedTable::finish`] to report: a run is not stopped by its trace.
    pub fn push(&mut self, row: &T) {
        if self.error.is_some() {
            return;
        }
        let flush = self.last_flush.elapsed() >= self.flush_every;
        if flush {
            self.last_flush = std::time::Instant::now();
        }
        let result = match &mut self.writer {
            StreamedWriter::Csv(csv) => csv.row(row).and_then(|()| if flush { csv.flush() } else { Ok(()) }),
            #[cfg(feature = "formats")]
            StreamedWriter::Arrow(arrow) => arrow.push(*row, flush),
            #[cfg(feature = "formats")]
            StreamedWriter::Mcap(mcap) => mcap.push(*row),
            #[cfg(not(feature = "formats"))]
            StreamedWriter::Never(_) => Ok(()),
        };
        if let Err(e) = result {
            self.error = Some(e.into());
        }
    }

    /// Writes the rest (and an Arrow stream's end marker, an MCAP file's summary and footer).
    ///
    /// # Errors
    /// The first write error, if any.
    pub fn finish(mut self) -> Result<(), CliError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        Ok(match self.writer {
            StreamedWriter::Csv(csv) => csv.finish(),
            #[cfg(feature = "formats")]
            StreamedWriter::Arrow(arrow) => arrow.finish(),
            #[cfg(feature = "formats")]
            StreamedWriter::Mcap(mcap) => mcap.finish(),
            #[cfg(not(feature = "formats"))]
            StreamedWriter::Never(_) => Ok(()),
        }?)
    }
}

/// A progress bar on stderr with the given message template, hidden when `hidden`
/// (JSON output) or when stderr is not a terminal.
pub fn progress_bar(len: u64, what: &str, unit: &str, hidden: bool) -> indicatif::ProgressBar {
    if hidden {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    let template = format!("{{spinner}} {what} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} elapsed, ETA {{eta}}");
    bar.set_style(indicatif::ProgressStyle::with_template(&template).unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()));
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    /// Issue 52, 5: `run` wrote its streamed trace through a link planted in
    /// `--out` (`trace.csv.partial`); the staged files could be redirected too.
    /// Every temporary file is made new: a planted link is replaced, its target
    /// (existing or not) untouched.
    #[test]
    fn no_output_is_written_through_a_link_planted_at_its_temporary_name() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        let victim = dir.path().join("victim");
        std::fs::write(&victim, "theirs").unwrap();
        let absent = dir.path().join("absent");
        for name in ["trace.csv.partial", ".summary.json.partial", ".trace.svg.partial", ".trace.pdf.partial", ".sil-host.owner"] {
            symlink(&victim, out.join(name)).unwrap();
        }
        symlink(&absent, out.join("trace.arrow.partial")).unwrap();
        let mut set = OutputSet::new(&out).unwrap();
        let (_, mut f) = set.create_streamed("trace.csv").unwrap();
        f.write_all(b"t\n").unwrap();
        let (_, mut f) = set.create_streamed("trace.arrow").unwrap();
        f.write_all(b"arrow").unwrap();
        set.write_bytes("summary.json", b"{}").unwrap();
        let svg = set.stage_figure("trace.svg").unwrap();
        std::fs::write(&svg, "<svg/>").unwrap();
        std::fs::write(figures::plot::print::pdf_path(&svg), "%PDF").unwrap();
        let files = set.commit().unwrap();
        assert_eq!(files.len(), 5, "{files:?}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "theirs", "nothing written through a link");
        assert!(!absent.exists(), "no file made through a dangling link");
        for (name, text) in
            [("trace.csv", "t\n"), ("trace.arrow", "arrow"), ("summary.json", "{}"), ("trace.svg", "<svg/>"), ("trace.pdf", "%PDF")]
        {
            let m = std::fs::symlink_metadata(out.join(name)).unwrap();
            assert!(m.is_file(), "{name} is a file of its own");
            assert_eq!(std::fs::read_to_string(out.join(name)).unwrap(), text, "{name}");
        }
    }

    /// What is in the way and is not a link or a file of ours is refused, naming it.
    #[test]
    fn a_folder_at_a_temporary_name_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("trace.csv.partial")).unwrap();
        let mut set = OutputSet::new(dir.path()).unwrap();
        let e = set.create_streamed("trace.csv").unwrap_err().to_string();
        assert!(e.contains("trace.csv.partial") && e.contains("in the way"), "{e}");
    }
}
