//! A recorded run, read back for `sil-host replay`: the scenario as run (its
//! `summary.json`'s `scenario_used`) and every period's frame and answer (its
//! `frames.csv`, `frames.arrow`, or the `frames` table of its `trace.mcap`),
//! each [`FrameRow`] bit for bit as the run wrote it.
//!
//! Every file is read as a regular file within its bound (`tables::input`:
//! [`tables::input::SUMMARY`], [`tables::input::RECORDING`]), and a recording
//! is held to its summary and to the scenario the replay runs (issue 80): a
//! frames table with no rows, fewer or more rows than the summary's `periods`,
//! a last row cut mid-line, or frames of another rate, length or initial state
//! than the scenario's is bad input (exit 2) saying so, never "identical" nor a
//! firmware divergence.

use std::path::{Path, PathBuf};

use rig::{
    frames::{Answer, FrameRow},
    scenario::Scenario,
};
use tables::Declared;
#[cfg(feature = "full")]
use tables::{Column, Table};

use crate::error::CliError;

/// A run's folder, read.
pub struct Recording {
    /// The scenario the run ran (after its own `--set`s).
    pub scenario: Scenario,
    /// The file the frames came from.
    pub source: PathBuf,
    /// Every period's frame and answer, in order.
    pub rows: Vec<FrameRow>,
}

/// Reads the run in folder `dir`.
///
/// # Errors
/// [`CliError::BadInput`] (exit 2): `dir` is not a run's folder (no
/// `summary.json`, or one without the scenario), it holds no frames (a run of a
/// `sil-host` before replay), a file is not a regular file within its bound,
/// a frames file is not the table (a column missing or of another kind, a
/// value out of its wire type's range, an answer not named), holds no row, or
/// holds another number of rows than the summary's `periods` (cut off, or
/// another run's); the readers' own errors for a file that does not parse.
pub fn read(dir: &Path) -> Result<Recording, CliError> {
    let bad = |what: String| CliError::bad_input(format!("{}: {what}", dir.display()));
    if !dir.is_dir() {
        return Err(bad("no such folder (give the --out folder of a `sil-host run` or `pil`)".into()));
    }
    let summary_path = dir.join("summary.json");
    let text = match tables::input::read_to_string(&summary_path, tables::input::SUMMARY) {
        Ok(text) => text,
        Err(e) if e.is_not_found() => {
            return Err(bad("no summary.json: not the folder of a `sil-host run` or `pil`".into()));
        }
        Err(e) => return Err(e.into()),
    };
    let summary: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(format!("summary.json is not JSON ({e})")))?;
    let used = summary
        .get("scenario_used")
        .ok_or_else(|| bad("summary.json has no `scenario_used`: not the folder of a closed-loop run (`sil-host run` or `pil`)".into()))?;
    let scenario: Scenario = serde_json::from_value(used.clone())
        .map_err(|e| bad(format!("summary.json's `scenario_used` is not a scenario this sil-host reads ({e})")))?;
    let (source, rows) = frames_of(dir)?;
    let named = |what: String| CliError::bad_input(format!("{}: {what}", source.display()));
    if rows.is_empty() {
        return Err(named(
            "no frames: a header only (the run wrote none, or the file was cut off); nothing to replay, which is not \"identical\"".into(),
        ));
    }
    // The run's own count: a table cut off (a disk full, a copy stopped) or
    // another run's frames beside this summary.
    if let Some(periods) = summary.get("periods").and_then(serde_json::Value::as_u64)
        && periods != rows.len() as u64
    {
        return Err(named(format!(
            "{} rows, but the run's summary.json says it ran {periods} periods: {}",
            rows.len(),
            if (rows.len() as u64) < periods {
                "the recording is cut off (truncated)"
            } else {
                "the frames are not this run's (another recording beside its summary)"
            }
        )));
    }
    Ok(Recording { scenario, source, rows })
}

/// Holds a recording's frames to `scenario`, the one the replay configures
/// the firmware from (the recorded one after `--set`): the frames' spacing is
/// its control period (`timing.rate_hz`), there are no more of them than it
/// runs (`timing.duration_s`), and the first frame's state is its plant's
/// initial state (`plant.x0`).
///
/// # Errors
/// [`CliError::BadInput`] (exit 2) naming the setting that differs: the
/// recording is of another scenario, which would replay as a divergence of
/// the firmware.
pub fn check_scenario(rec: &Recording, setup: &rig::setup::RunSetup) -> Result<(), CliError> {
    let s = setup.scenario();
    let mismatch = |what: String| {
        CliError::bad_input(format!(
            "{}: the recording is not of the scenario the replay runs (`{}`, summary.json's `scenario_used` after any --set): {what}",
            rec.source.display(),
            s.name
        ))
    };
    let period_us = s.timing.period().as_us();
    if let Some(w) = rec.rows.windows(2).find(|w| w[1].t_us - w[0].t_us != period_us as i64) {
        let step = w[1].t_us - w[0].t_us;
        return Err(mismatch(format!(
            "timing.rate_hz: its frames are {step} us apart (period {} to {}), the scenario's control period is {period_us} us \
             (timing.rate_hz = {})",
            w[0].seq, w[1].seq, s.timing.rate_hz
        )));
    }
    let periods = s.timing.periods();
    if rec.rows.len() as u64 > periods {
        return Err(mismatch(format!(
            "timing.duration_s: it holds {} periods, the scenario runs {periods} (timing.duration_s = {})",
            rec.rows.len(),
            s.timing.duration_s
        )));
    }
    let first = &rec.rows[0];
    let recorded = [first.theta1, first.theta1_dot, first.theta2, first.theta2_dot];
    let initial = setup.plant().state();
    if first.seq == 0 && recorded != initial {
        return Err(mismatch(format!(
            "plant.x0: its first frame's state (theta1, theta1_dot, theta2, theta2_dot) is {recorded:?}, the scenario's initial \
             state (plant.x0 = \"{}\") is {initial:?}",
            s.plant.x0.letter()
        )));
    }
    Ok(())
}

/// The frames of `dir`: `frames.csv` (every build), `frames.arrow` or
/// `trace.mcap`'s `frames` table (a build with the table readers, `full`).
fn frames_of(dir: &Path) -> Result<(PathBuf, Vec<FrameRow>), CliError> {
    // `exists`, not `is_file`: a FIFO or a device in a file's place is refused
    // by the reader, naming the bound, rather than passed over.
    let csv = dir.join("frames.csv");
    if csv.exists() {
        return Ok((csv.clone(), read_csv(&csv)?));
    }
    let arrow = dir.join("frames.arrow");
    let mcap = dir.join("trace.mcap");
    #[cfg(feature = "full")]
    {
        let named = |path: &Path, what: String| CliError::bad_input(format!("{}: {what}", path.display()));
        if arrow.exists() {
            let t = tables::arrow::read_arrow(&arrow)?;
            return Ok((arrow.clone(), rows_of(&t).map_err(|what| named(&arrow, what))?));
        }
        if mcap.exists() {
            return match tables::mcap::read_mcap(&mcap)?.into_iter().find(|(name, _)| name == "frames") {
                Some((_, t)) => Ok((mcap.clone(), rows_of(&t).map_err(|what| named(&mcap, what))?)),
                None => {
                    Err(named(&mcap, "no `frames` table (the /wire channels): written by a sil-host before replay; run it again".into()))
                }
            };
        }
    }
    #[cfg(not(feature = "full"))]
    if arrow.exists() || mcap.exists() {
        return Err(crate::features::missing("full", "replaying frames.arrow or trace.mcap (the table readers)"));
    }
    Err(CliError::bad_input(format!(
        "{}: no frames recorded (frames.csv, frames.arrow or trace.mcap): not a run's folder, or one written by a sil-host before replay; run it again",
        dir.display()
    )))
}

/// A row of `frames.csv` as text reads it (the answer owned).
#[derive(serde::Deserialize)]
struct CsvFrame {
    t: f64,
    seq: u32,
    t_us: i64,
    theta1_count: u16,
    elbow_count: u16,
    f_t_code: i16,
    f_n_code: i16,
    belt_count: i16,
    flags: u16,
    theta1: f64,
    theta1_dot: f64,
    theta2: f64,
    theta2_dot: f64,
    f_t: f64,
    f_n: f64,
    answer: String,
    u1_code: i16,
    u2_code: i16,
    status: u32,
    overruns: u32,
    z_t_ref: f64,
    f_n_ref: f64,
    q1: f64,
    q2: f64,
    qd1: f64,
    qd2: f64,
    f_t_meas: f64,
    f_n_meas: f64,
    u1_raw: f64,
    u2_raw: f64,
}

/// The rows of `frames.csv` at `path` (the `csv` crate; Rust's float parsing
/// reads the shortest text back to its bits), read within
/// [`tables::input::RECORDING`]'s bound. The header must be the table's, and
/// the file must end with a whole row: a last row cut mid-line (a run killed
/// while writing, a copy stopped) would read as a row of cut numbers.
fn read_csv(path: &Path) -> Result<Vec<FrameRow>, CliError> {
    use std::io::{Read, Seek, SeekFrom};
    let named = |what: String| CliError::bad_input(format!("{}: {what}", path.display()));
    let bound = tables::input::RECORDING;
    let mut file = tables::input::open(path, bound)?;
    let io = |e: std::io::Error| CliError::from(tables::input::into_input_error(e, path, bound));
    let mut last = [0u8];
    if file.seek(SeekFrom::End(-1)).and_then(|_| file.read_exact(&mut last)).is_ok() && last[0] != b'\n' {
        return Err(named("its last row is cut mid-line (no newline at its end): the recording is truncated".into()));
    }
    file.rewind().map_err(io)?;
    let mut reader = csv::Reader::from_reader(tables::input::BoundedReader::new(file, path, bound));
    let header: Vec<String> = reader.headers().map_err(|e| named(e.to_string()))?.iter().map(String::from).collect();
    if header != FrameRow::NAMES {
        let missing: Vec<&str> = FrameRow::NAMES.iter().copied().filter(|n| !header.iter().any(|h| h == n)).collect();
        return Err(named(match missing.first() {
            Some(name) => format!("no column `{name}`"),
            None => format!("its columns are not the frames table's ({})", FrameRow::NAMES.join(",")),
        }));
    }
    reader
        .deserialize::<CsvFrame>()
        .enumerate()
        .map(|(i, r)| {
            let r = r.map_err(|e| format!("row {}: {e}", i + 1))?;
            let answer = Answer::of_name(&r.answer)
                .map(Answer::name)
                .ok_or_else(|| format!("row {}: answer `{}` is none of answered, dropped, none", i + 1, r.answer))?;
            if r.t_us < 0 {
                return Err(format!("row {}: `t_us` = {} is outside its wire type's range", i + 1, r.t_us));
            }
            Ok(FrameRow {
                t: r.t,
                seq: r.seq,
                t_us: r.t_us,
                theta1_count: r.theta1_count,
                elbow_count: r.elbow_count,
                f_t_code: r.f_t_code,
                f_n_code: r.f_n_code,
                belt_count: r.belt_count,
                flags: r.flags,
                theta1: r.theta1,
                theta1_dot: r.theta1_dot,
                theta2: r.theta2,
                theta2_dot: r.theta2_dot,
                f_t: r.f_t,
                f_n: r.f_n,
                answer,
                u1_code: r.u1_code,
                u2_code: r.u2_code,
                status: r.status,
                overruns: r.overruns,
                z_t_ref: r.z_t_ref,
                f_n_ref: r.f_n_ref,
                q1: r.q1,
                q2: r.q2,
                qd1: r.qd1,
                qd2: r.qd2,
                f_t_meas: r.f_t_meas,
                f_n_meas: r.f_n_meas,
                u1_raw: r.u1_raw,
                u2_raw: r.u2_raw,
            })
        })
        .collect::<Result<_, String>>()
        .map_err(named)
}

/// The column `name` of `t`.
#[cfg(feature = "full")]
fn column<'a>(t: &'a Table, name: &str) -> Result<&'a Column, String> {
    t.columns.iter().find(|(n, _)| n == name).map(|(_, c)| c).ok_or_else(|| format!("no column `{name}`"))
}

/// The rows of a frames table (Arrow, MCAP).
#[cfg(feature = "full")]
fn rows_of(t: &Table) -> Result<Vec<FrameRow>, String> {
    let n = t.rows();
    let real = |name: &str| match column(t, name)? {
        Column::F64(v) => Ok(v.as_slice()),
        _ => Err(format!("column `{name}` is not of numbers")),
    };
    let int = |name: &str| match column(t, name)? {
        Column::I64(v) => Ok(v.as_slice()),
        _ => Err(format!("column `{name}` is not of integers")),
    };
    // Every declared column is there, and no other (a table of another kind).
    for name in FrameRow::NAMES {
        column(t, name)?;
    }
    let answers = match column(t, "answer")? {
        Column::Str(v) => v
            .iter()
            .enumerate()
            .map(|(i, a)| {
                Answer::of_name(a)
                    .map(Answer::name)
                    .ok_or_else(|| format!("row {}: answer `{a}` is none of answered, dropped, none", i + 1))
            })
            .collect::<Result<Vec<_>, _>>()?,
        _ => return Err("column `answer` is not of text".into()),
    };
    let (t_col, seq, t_us) = (real("t")?, int("seq")?, int("t_us")?);
    let (th1c, elc, ftc, fnc, belt, flags) =
        (int("theta1_count")?, int("elbow_count")?, int("f_t_code")?, int("f_n_code")?, int("belt_count")?, int("flags")?);
    let (x1, x2, x3, x4, f_t, f_n) =
        (real("theta1")?, real("theta1_dot")?, real("theta2")?, real("theta2_dot")?, real("f_t")?, real("f_n")?);
    let (u1c, u2c, status, overruns) = (int("u1_code")?, int("u2_code")?, int("status")?, int("overruns")?);
    let tel: Vec<&[f64]> = ["z_t_ref", "f_n_ref", "q1", "q2", "qd1", "qd2", "f_t_meas", "f_n_meas", "u1_raw", "u2_raw"]
        .iter()
        .map(|c| real(c))
        .collect::<Result<_, _>>()?;
    /// `v` in the wire type `T`, or the row and column that does not fit.
    fn narrow<T: TryFrom<i64>>(name: &str, i: usize, v: i64) -> Result<T, String> {
        T::try_from(v).map_err(|_| format!("row {}: `{name}` = {v} is outside its wire type's range", i + 1))
    }
    (0..n)
        .map(|i| {
            Ok(FrameRow {
                t: t_col[i],
                seq: narrow("seq", i, seq[i])?,
                // Held as the table's integer; a stamp is never negative.
                t_us: narrow::<u64>("t_us", i, t_us[i]).map(|_| t_us[i])?,
                theta1_count: narrow("theta1_count", i, th1c[i])?,
                elbow_count: narrow("elbow_count", i, elc[i])?,
                f_t_code: narrow("f_t_code", i, ftc[i])?,
                f_n_code: narrow("f_n_code", i, fnc[i])?,
                belt_count: narrow("belt_count", i, belt[i])?,
                flags: narrow("flags", i, flags[i])?,
                theta1: x1[i],
                theta1_dot: x2[i],
                theta2: x3[i],
                theta2_dot: x4[i],
                f_t: f_t[i],
                f_n: f_n[i],
                answer: answers[i],
                u1_code: narrow("u1_code", i, u1c[i])?,
                u2_code: narrow("u2_code", i, u2c[i])?,
                status: narrow("status", i, status[i])?,
                overruns: narrow("overruns", i, overruns[i])?,
                z_t_ref: tel[0][i],
                f_n_ref: tel[1][i],
                q1: tel[2][i],
                q2: tel[3][i],
                qd1: tel[4][i],
                qd2: tel[5][i],
                f_t_meas: tel[6][i],
                f_n_meas: tel[7][i],
                u1_raw: tel[8][i],
                u2_raw: tel[9][i],
            })
        })
        .collect()
}

#[cfg(all(test, feature = "full"))]
mod tests {
    use super::*;

    fn row(k: u32) -> FrameRow {
        use shared::wire::{GroundTruth, SensorFrame};
        let frame = SensorFrame {
            t_us: u64::from(k) * 1000,
            seq: k,
            theta1_count: 16383,
            elbow_count: 1,
            f_t_code: -2048,
            f_n_code: 2047,
            belt_count: -400,
            flags: 3,
        };
        let truth = GroundTruth { t: f64::from(k) * 1e-3, seq: k, x: [0.1, 0.2, 0.3, 0.4], f: [0.5, 0.6], ..GroundTruth::default() };
        FrameRow::of(&frame, &truth, &rig::Exchange::NoAnswer)
    }

    #[test]
    fn a_table_of_rows_reads_back_as_the_rows() {
        let rows: Vec<FrameRow> = (0..5).map(row).collect();
        let t = Table::of_columns(&rows);
        assert_eq!(rows_of(&t).expect("reads"), rows);
    }

    #[test]
    fn a_value_outside_its_wire_type_and_a_missing_column_are_refused() {
        let rows: Vec<FrameRow> = (0..2).map(row).collect();
        let mut t = Table::of_columns(&rows);
        let i = FrameRow::NAMES.iter().position(|n| *n == "theta1_count").expect("declared");
        t.columns[i].1 = Column::I64(vec![0, 70_000]);
        assert_eq!(rows_of(&t).unwrap_err(), "row 2: `theta1_count` = 70000 is outside its wire type's range");
        t.columns.remove(i);
        assert_eq!(rows_of(&t).unwrap_err(), "no column `theta1_count`");
    }
}

#[cfg(all(test, feature = "full"))]
mod csv_tests {
    use super::*;

    /// The CSV path (every build) and the tables' reader (Arrow, MCAP, `full`)
    /// read the same rows, bit for bit, from a run's files.
    #[test]
    fn the_csv_reader_and_the_tables_reader_agree_bit_for_bit() {
        use rig::frames::FrameRow;
        use shared::wire::{GroundTruth, SensorFrame};
        let rows: Vec<FrameRow> = (0..50u32)
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
                FrameRow::of(&frame, &truth, &rig::Exchange::NoAnswer)
            })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frames.csv");
        let file = std::fs::File::create(&path).unwrap();
        let mut csv = tables::csv::CsvFile::new(path.clone(), file, <FrameRow as tables::csv::CsvRow>::HEADER);
        rows.iter().for_each(|r| csv.row(r).unwrap());
        csv.finish().unwrap();
        let by_csv = read_csv(&path).unwrap();
        let by_tables = rows_of(&tables::read::read_csv_table(&path, experiments::DECLARED).unwrap()).unwrap();
        let bits = |rs: &[FrameRow]| {
            rs.iter()
                .map(|r| {
                    format!(
                        "{:?}",
                        r.signals().map(|(_, s)| match s {
                            rig::frames::Signal::Int(v) => v as u64,
                            rig::frames::Signal::Real(v) => v.to_bits(),
                        })
                    )
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(by_csv, rows);
        assert_eq!(by_tables, rows);
        assert_eq!(bits(&by_csv), bits(&rows));
    }
}
