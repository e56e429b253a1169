//! The scenario text of a case: the base document's TOML table edited and
//! written back, then its lines edited; or a file's bytes mutated.

use toml::{Table, Value};

use super::{
    case::{Edit, LineEdit, Source},
    keys::{FAULTS, FILES},
};

fn set(doc: &mut Table, parts: &[String], value: Option<Value>) {
    let Some((last, path)) = parts.split_last() else { return };
    let mut table = doc;
    for (i, part) in path.iter().enumerate() {
        // faults.N: the N-th entry of the array of tables (a new one past its end).
        if part == "faults" && i + 1 < path.len() {
            let index: usize = path[i + 1].parse().unwrap_or(0);
            let faults = table.entry("faults").or_insert_with(|| Value::Array(Vec::new()));
            if !faults.is_array() {
                *faults = Value::Array(Vec::new());
            }
            let Value::Array(entries) = faults else { return };
            if index >= entries.len() {
                entries.push(Value::Table(Table::new()));
            }
            let at = index.min(entries.len() - 1);
            if !entries[at].is_table() {
                entries[at] = Value::Table(Table::new());
            }
            let Value::Table(t) = &mut entries[at] else { return };
            set(t, &parts[i + 2..], value);
            return;
        }
        let entry = table.entry(part.clone()).or_insert_with(|| Value::Table(Table::new()));
        if !entry.is_table() {
            *entry = Value::Table(Table::new());
        }
        let Value::Table(t) = entry else { return };
        table = t;
    }
    match value {
        Some(v) => {
            table.insert(last.clone(), v);
        }
        None => {
            table.remove(last);
        }
    }
}

/// The scenario text of a case.
pub fn text(source: &Source) -> String {
    match source {
        Source::Doc { base, edits, lines } => {
            let base_text = match base % 6 {
                5 => format!("{}{FAULTS}", FILES[0]),
                i => FILES[i].to_string(),
            };
            let mut doc: Table = toml::from_str(&base_text).unwrap_or_default();
            for e in edits {
                match e {
                    Edit::Set(p, v) => set(&mut doc, &p.parts(), Some(v.to_toml())),
                    Edit::InRange(r) => {
                        let (parts, v) = r.resolve();
                        set(&mut doc, &parts, Some(v.to_toml()));
                    }
                    Edit::Remove(p) => set(&mut doc, &p.parts(), None),
                }
            }
            // What toml cannot write (none known) is left as the base text.
            let written = toml::to_string(&doc).unwrap_or(base_text);
            let mut ls: Vec<String> = written.lines().map(String::from).collect();
            for e in lines {
                let n = ls.len();
                match e {
                    LineEdit::Repeat(i) if n > 0 => ls.insert(i % n, ls[i % n].clone()),
                    LineEdit::Remove(i) if n > 0 => {
                        ls.remove(i % n);
                    }
                    LineEdit::Insert(i, l) => ls.insert(i % (n + 1), l.clone()),
                    _ => {}
                }
            }
            let mut out = ls.join("\n");
            out.push('\n');
            out
        }
        Source::Bytes { file, mutations } => {
            let mut bytes = FILES[file % FILES.len()].as_bytes().to_vec();
            for m in mutations {
                m.apply(&mut bytes);
            }
            String::from_utf8_lossy(&bytes).into_owned()
        }
    }
}
