//! `simulate --format arrow` and `--format mcap` (and `run`'s) against `--format csv`: the
//! same tables, column for column, every float with the same bits (the CSV's shortest
//! round-trip digits read back by the `csv` crate and Rust's parser, the Arrow columns by
//! `tables::arrow::read_arrow`, the MCAP messages' JSON by
//! `tables::mcap::read_mcap` and serde_json: independent paths), and the CSV read back by
//! `tables::read::read_csv` with the Arrow file's schema.

use std::{path::Path, process::Command};

use tables::{
    Column, Table,
    arrow::{read_arrow, read_arrow_batch, table_of},
    mcap::read_mcap,
    read::read_csv as read_csv_batch,
};

fn simulate(format: &str, out: &Path) {
    sil_host(&["simulate", "--x0", "a", "--v-belt", "-0.5", "--duration", "2", "--format", format, "--json", "--out"], out);
}

fn sil_host(args: &[&str], out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).arg(out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Each column of the Arrow table equals the CSV's: floats to the bit, text as
/// written, integers and flags as the CSV's cells. The CSV read back by the
/// `tables` reader (its declaration found by its header) has the Arrow file's
/// schema and the same values.
fn assert_same(table: &str, csv: &Path, arrow: &Path) {
    assert_same_table(table, csv, read_arrow(arrow).unwrap());
    let (from_csv, from_arrow) = (read_csv_batch(csv, experiments::DECLARED).unwrap(), read_arrow_batch(arrow).unwrap());
    assert_eq!(from_csv.schema(), from_arrow.schema(), "{table}: the declared schema");
    assert_same_table(table, csv, table_of(&from_csv).unwrap());
}

/// Each column of `got` equals the CSV's, as [`assert_same`].
fn assert_same_table(table: &str, csv: &Path, got: Table) {
    let (header, cells) = read_csv(csv);
    let columns = got.columns;
    assert_eq!(columns.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), header, "{table}");
    assert!(cells[0].len() > 1, "{table}: rows");
    for ((name, col), cells) in columns.iter().zip(&cells) {
        assert_eq!(col.len(), cells.len(), "{table}.{name}");
        match col {
            Column::F64(v) => {
                for (x, cell) in v.iter().zip(cells) {
                    let y: f64 = cell.parse().unwrap();
                    assert_eq!(x.to_bits(), y.to_bits(), "{table}.{name}: {x:e} against `{cell}`");
                }
            }
            Column::Str(v) => assert_eq!(v, cells, "{table}.{name}"),
            Column::I64(v) => assert_eq!(v.iter().map(i64::to_string).collect::<Vec<_>>(), *cells, "{table}.{name}"),
            Column::Bool(v) => assert_eq!(v.iter().map(bool::to_string).collect::<Vec<_>>(), *cells, "{table}.{name}"),
        }
    }
}

/// `run --format arrow` (issue 43): the closed-loop trace as an Arrow IPC file
/// (record batches as the run goes, the footer at the end; one `.arrow`
/// convention with `simulate`, issue 55), the CSV's table bit for bit.
#[test]
fn a_runs_arrow_file_holds_its_csv_trace_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (c, a) = (dir.path().join("csv"), dir.path().join("arrow"));
    sil_host(&["run", "--in-process", "--duration", "1", "--format", "csv", "--out"], &c);
    sil_host(&["run", "--in-process", "--duration", "1", "--format", "arrow", "--out"], &a);
    assert!(!a.join("trace.csv").exists() && !c.join("trace.arrow").exists());
    let bytes = std::fs::read(a.join("trace.arrow")).unwrap();
    assert!(bytes.starts_with(b"ARROW1") && bytes.ends_with(b"ARROW1"), "the IPC file format, as simulate's");
    assert_same("trace", &c.join("trace.csv"), &a.join("trace.arrow"));
}

/// The CSV table's header and its cells by column.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let mut cols = vec![Vec::new(); header.len()];
    for rec in r.records() {
        for (c, cell) in cols.iter_mut().zip(rec.unwrap().iter()) {
            c.push(cell.to_string());
        }
    }
    (header, cols)
}

#[test]
fn arrow_tables_hold_the_csv_tables_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (c, a) = (dir.path().join("csv"), dir.path().join("arrow"));
    simulate("csv", &c);
    simulate("arrow", &a);
    for table in ["trace", "events"] {
        assert_same(table, &c.join(format!("{table}.csv")), &a.join(format!("{table}.arrow")));
    }
    // The summary names the files written.
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(a.join("summary.json")).unwrap()).unwrap();
    let files: Vec<String> =
        summary["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap().rsplit('/').next().unwrap().to_string()).collect();
    assert_eq!(files, ["trace.arrow", "events.arrow", "trace.svg", "trace.pdf", "trace.html", "summary.json"]);
}

/// `simulate --format mcap` (issue 44): one `trace.mcap` holding both tables, each
/// the CSV's bit for bit; the summary names the files written.
#[test]
fn an_mcap_file_holds_the_csv_tables_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (c, m) = (dir.path().join("csv"), dir.path().join("mcap"));
    simulate("csv", &c);
    simulate("mcap", &m);
    let mut names: Vec<String> = std::fs::read_dir(&m).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    assert_eq!(names, ["summary.json", "trace.html", "trace.mcap", "trace.pdf", "trace.svg"]);
    let tables = read_mcap(&m.join("trace.mcap")).unwrap();
    assert_eq!(tables.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["trace", "events"]);
    for (name, table) in tables {
        assert_same_table(&name, &c.join(format!("{name}.csv")), table);
    }
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(m.join("summary.json")).unwrap()).unwrap();
    let files: Vec<String> =
        summary["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap().rsplit('/').next().unwrap().to_string()).collect();
    assert_eq!(files, ["trace.mcap", "trace.svg", "trace.pdf", "trace.html", "summary.json"]);
}

/// `run --format mcap`: the closed-loop trace and frames bit for bit, and the same bytes
/// in-process and over iceoryx2 (chunks closed by row count, zstd single-threaded).
#[test]
fn a_runs_mcap_trace_is_its_csv_and_the_same_bytes_over_both_links() {
    let dir = tempfile::tempdir().unwrap();
    let (c, m, i) = (dir.path().join("csv"), dir.path().join("mcap"), dir.path().join("ipc"));
    sil_host(&["run", "--in-process", "--duration", "1", "--format", "csv", "--out"], &c);
    sil_host(&["run", "--in-process", "--duration", "1", "--format", "mcap", "--out"], &m);
    sil_host(&["run", "--duration", "1", "--format", "mcap", "--out"], &i);
    // The trace and the frames the firmware read and answered (issue 69: `sil-host replay`'s record).
    let tables = read_mcap(&m.join("trace.mcap")).unwrap();
    assert_eq!(tables.iter().map(|(n, t)| (n.as_str(), t.rows())).collect::<Vec<_>>(), [("trace", 1000), ("frames", 1000)]);
    for (name, table) in tables {
        assert_same_table(&name, &c.join(format!("{name}.csv")), table);
    }
    assert!(std::fs::read(m.join("trace.mcap")).unwrap() == std::fs::read(i.join("trace.mcap")).unwrap(), "in-process and iceoryx2 differ");
}
