//! The frames table read back from a run's folder, beside its writer: the rows
//! of `frames.csv` (every build), `frames.arrow` or the `frames` table of
//! `trace.mcap` (rig's feature `read`, tables' readers), each [`FrameRow`] bit
//! for bit as the run wrote it. The reader is derived from the table's one
//! declaration (serde's `Deserialize` of [`FrameRow`]): the `csv` crate reads
//! the CSV file, `tables::Table::rows_as` the Arrow and MCAP tables.
//!
//! Every file is read as a regular file within [`tables::input::RECORDING`]'s
//! bound. A CSV file whose header is not the table's, or whose last row is cut
//! mid-line (a run killed while writing, a copy stopped), is refused: it would
//! read as a table of other or cut numbers.

use std::path::{Path, PathBuf};

use super::FrameRow;
use tables::{Declared, input};

/// Why a run's frames cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum FramesError {
    /// The folder holds no frames file.
    #[error(
        "{}: no frames recorded (frames.csv, frames.arrow or trace.mcap): not a run's folder, or one written by a sil-host before replay; run it again",
        dir.display()
    )]
    NotRecorded {
        /// The folder.
        dir: PathBuf,
    },
    /// The file is not the frames table: a column missing or of another kind,
    /// a value out of its wire type's range, an answer not named, a last row
    /// cut mid-line, an MCAP file without the `frames` table.
    #[error("{}: {what}", path.display())]
    NotTheTable {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the row and the column.
        what: String,
    },
    /// The file cannot be read: not a regular file within its bound, or a file
    /// its format's reader refuses.
    #[error(transparent)]
    Table(#[from] tables::Error),
    /// An Arrow or MCAP file in a build without rig's feature `read`.
    #[error("{}: reading frames.arrow or trace.mcap needs the table readers (rig's feature `read`)", path.display())]
    NotBuilt {
        /// The file.
        path: PathBuf,
    },
}

impl From<input::InputError> for FramesError {
    fn from(e: input::InputError) -> Self {
        Self::Table(tables::Error::Input(e))
    }
}

/// The frames of the run in folder `dir`: the file they came from and every
/// period's row, in order. `frames.csv` is read first, then `frames.arrow`,
/// then `trace.mcap`'s `frames` table.
///
/// # Errors
/// [`FramesError`]: no frames file in `dir`; a file that is not a regular file
/// within [`input::RECORDING`]'s bound, or that its reader refuses; a file that
/// is not the frames table (naming the row and column); an Arrow or MCAP file in
/// a build without the feature `read`.
pub fn read_frames(dir: &Path) -> Result<(PathBuf, Vec<FrameRow>), FramesError> {
    read_table(dir, "frames")?.ok_or_else(|| FramesError::NotRecorded { dir: dir.to_path_buf() })
}

/// The rows of table `stem` (`frames`, `trace`) of the run in folder `dir`, as
/// [`read_frames`] reads the frames: `STEM.csv`, then `STEM.arrow`, then
/// `trace.mcap`'s table `stem`; `None` when the folder has none of them. Rows of
/// any table declared once that derives `Deserialize` (`FrameRow`,
/// `crate::record::PeriodRecord`).
///
/// # Errors
/// As [`read_frames`], but for a folder without the table.
pub fn read_table<T: serde::de::DeserializeOwned + Declared>(dir: &Path, stem: &str) -> Result<Option<(PathBuf, Vec<T>)>, FramesError> {
    // `exists`, not `is_file`: a FIFO or a device in a file's place is refused
    // by the reader, naming the bound, rather than passed over.
    let csv = dir.join(format!("{stem}.csv"));
    if csv.exists() {
        let rows = read_csv(&csv)?;
        return Ok(Some((csv, rows)));
    }
    let arrow = dir.join(format!("{stem}.arrow"));
    if arrow.exists() {
        let rows = read_arrow(&arrow)?;
        return Ok(Some((arrow, rows)));
    }
    let mcap = dir.join("trace.mcap");
    if mcap.exists() {
        let rows = read_mcap(&mcap, stem)?;
        return Ok(Some((mcap, rows)));
    }
    Ok(None)
}

/// The rows of `frames.csv` at `path` (the `csv` crate; Rust's float parsing
/// reads the shortest text back to its bits).
fn read_csv<T: serde::de::DeserializeOwned + Declared>(path: &Path) -> Result<Vec<T>, FramesError> {
    use std::io::{Read, Seek, SeekFrom};
    let named = |what: String| FramesError::NotTheTable { path: path.to_path_buf(), what };
    let bound = input::RECORDING;
    let mut file = input::open(path, bound)?;
    let mut last = [0u8];
    if file.seek(SeekFrom::End(-1)).and_then(|_| file.read_exact(&mut last)).is_ok() && last[0] != b'\n' {
        return Err(named("its last row is cut mid-line (no newline at its end): the recording is truncated".into()));
    }
    file.rewind().map_err(|e| input::into_input_error(e, path, bound))?;
    let mut reader = csv::Reader::from_reader(input::BoundedReader::new(file, path, bound));
    let header: Vec<String> = reader.headers().map_err(|e| named(e.to_string()))?.iter().map(String::from).collect();
    if header != T::NAMES {
        let missing = T::NAMES.iter().find(|n| !header.iter().any(|h| h == *n));
        return Err(named(match missing {
            Some(name) => format!("no column `{name}`"),
            None => format!("its columns are not the table's ({})", T::NAMES.join(",")),
        }));
    }
    reader
        .deserialize::<T>()
        .enumerate()
        .map(|(i, r)| r.map_err(|e| named(format!("row {}: {}", i + 1, csv_error(&e, T::NAMES)))))
        .collect()
}

/// The `csv` crate's error without its position (the row is named instead),
/// with the column it names.
fn csv_error(e: &csv::Error, names: &[&str]) -> String {
    match e.kind() {
        csv::ErrorKind::Deserialize { err, .. } => match err.field() {
            Some(i) => format!("column `{}`: {}", names.get(i as usize).copied().unwrap_or("?"), err.kind()),
            None => err.kind().to_string(),
        },
        _ => e.to_string(),
    }
}

/// The rows of the Arrow file at `path`.
#[cfg(feature = "read")]
fn read_arrow<T: serde::de::DeserializeOwned + Declared>(path: &Path) -> Result<Vec<T>, FramesError> {
    let table = tables::arrow::read_arrow(path)?;
    table.rows_as().map_err(|e| FramesError::NotTheTable { path: path.to_path_buf(), what: e.0 })
}

/// The rows of table `stem` of `trace.mcap` at `path`.
#[cfg(feature = "read")]
fn read_mcap<T: serde::de::DeserializeOwned + Declared>(path: &Path, stem: &str) -> Result<Vec<T>, FramesError> {
    let named = |what: String| FramesError::NotTheTable { path: path.to_path_buf(), what };
    match tables::mcap::read_mcap(path)?.into_iter().find(|(name, _)| name == stem) {
        Some((_, table)) => table.rows_as().map_err(|e| named(e.0)),
        None if stem == "frames" => {
            Err(named("no `frames` table (the /wire channels): written by a sil-host before replay; run it again".into()))
        }
        None => Err(named(format!("no `{stem}` table"))),
    }
}

/// Without the table readers: [`FramesError::NotBuilt`].
#[cfg(not(feature = "read"))]
fn read_arrow<T>(path: &Path) -> Result<Vec<T>, FramesError> {
    Err(FramesError::NotBuilt { path: path.to_path_buf() })
}

/// Without the table readers: [`FramesError::NotBuilt`].
#[cfg(not(feature = "read"))]
fn read_mcap<T>(path: &Path, _stem: &str) -> Result<Vec<T>, FramesError> {
    Err(FramesError::NotBuilt { path: path.to_path_buf() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::Exchange;
    use shared::wire::{GroundTruth, SensorFrame};

    /// 50 rows whose floats need every digit, a subnormal, -0.0 among them.
    fn rows() -> Vec<FrameRow> {
        (0..50u32)
            .map(|k| {
                let frame = SensorFrame {
                    t_us: u64::from(k) * 1000,
                    seq: k,
                    theta1_count: 16383 - k as u16,
                    elbow_count: 1,
                    f_t_code: -2048,
                    f_n_code: 2047,
                    belt_count: -400,
                    flags: 3,
                };
                let truth = GroundTruth {
                    t: f64::from(k) * 1e-3,
                    seq: k,
                    x: [0.1 / f64::from(k + 1), 0.2, 1e-300, -0.0],
                    f: [0.5, f64::MIN_POSITIVE],
                    ..GroundTruth::default()
                };
                FrameRow::of(&frame, &truth, &Exchange::NoAnswer)
            })
            .collect()
    }

    fn write_csv(dir: &Path, rows: &[FrameRow]) -> PathBuf {
        let path = dir.join("frames.csv");
        let file = std::fs::File::create(&path).expect("creates");
        let mut csv = tables::csv::CsvFile::new(path.clone(), file, FrameRow::NAMES);
        rows.iter().for_each(|r| csv.row(r).expect("writes"));
        csv.finish().expect("finishes");
        path
    }

    fn bits(rows: &[FrameRow]) -> Vec<String> {
        rows.iter()
            .map(|r| {
                let ints = (r.seq, r.t_us, r.theta1_count, r.elbow_count, r.f_t_code, r.f_n_code, r.belt_count, r.flags);
                let reals = [r.t, r.theta1, r.theta1_dot, r.theta2, r.theta2_dot, r.f_t, r.f_n].map(f64::to_bits);
                let answer = r.signals().map(|(_, s)| match s {
                    crate::frames::Signal::Int(v) => v as u64,
                    crate::frames::Signal::Real(v) => v.to_bits(),
                });
                format!("{ints:?} {reals:?} {answer:?}")
            })
            .collect()
    }

    #[test]
    fn the_csv_file_reads_back_bit_for_bit() {
        let dir = tempfile::tempdir().expect("tempdir");
        let rows = rows();
        let path = write_csv(dir.path(), &rows);
        let (source, back) = read_frames(dir.path()).expect("reads");
        assert_eq!(source, path);
        assert_eq!(bits(&back), bits(&rows));
    }

    /// The CSV path (every build) and the tables' path (Arrow, MCAP) read the
    /// same rows, bit for bit.
    #[cfg(feature = "read")]
    #[test]
    fn the_csv_reader_and_the_tables_reader_agree_bit_for_bit() {
        let dir = tempfile::tempdir().expect("tempdir");
        let rows = rows();
        let path = write_csv(dir.path(), &rows);
        let declared = tables::Declaration::of::<FrameRow>();
        let by_tables: Vec<FrameRow> = tables::read::read_csv_table(&path, &[declared]).expect("reads").rows_as().expect("rows");
        let table = tables::Table::of_columns(&rows);
        assert_eq!(bits(&table.rows_as::<FrameRow>().expect("rows")), bits(&rows));
        assert_eq!(bits(&by_tables), bits(&rows));
    }

    #[test]
    fn a_cut_row_another_header_an_unknown_answer_and_a_value_out_of_range_are_refused_by_row_and_column() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_csv(dir.path(), &rows()[..3]);
        let text = std::fs::read_to_string(&path).expect("reads");
        let refused = |text: &str| {
            std::fs::write(&path, text).expect("writes");
            read_frames(dir.path()).expect_err("refused").to_string()
        };
        let e = refused(&text[..text.len() - 5]);
        assert!(e.ends_with("its last row is cut mid-line (no newline at its end): the recording is truncated"), "{e}");
        let e = refused(&text.replacen("elbow_count", "elbow", 1));
        assert!(e.ends_with("no column `elbow_count`"), "{e}");
        let e = refused(&text.replacen(",none,", ",maybe,", 2));
        assert!(e.contains("row 1: unknown variant `maybe`, expected one of `answered`, `dropped`, `none`"), "{e}");
        let e = refused(&text.replacen(",16382,", ",70000,", 1));
        assert!(e.contains("row 2: column `theta1_count`:"), "{e}");
        let e = refused(&text.replacen("\n2,2,2000,", "\n2,2,-2000,", 1).replacen("\n0.002,2,2000,", "\n0.002,2,-2000,", 1));
        assert!(e.contains("row 3: `t_us` = -2000 is outside its wire type's range"), "{e}");
        std::fs::remove_file(&path).expect("removes");
        let e = read_frames(dir.path()).expect_err("no frames").to_string();
        assert!(e.contains("no frames recorded"), "{e}");
    }
}
