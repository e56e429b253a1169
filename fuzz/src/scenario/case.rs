//! A case of the target: the scenario text's source (a document with edits, or
//! a file with byte mutations) and the `--set` arguments, with how each value and
//! argument is written.

use toml::{Table, Value};

use super::keys::{
    DOMAINS,
    Domain::{E, F, I, Pair},
    FAULT_KEYS, KEYS, TABLES,
};
use crate::pil_decode::Mutation;

/// A value to write.
#[derive(Debug, Clone)]
pub enum Val {
    /// A float.
    Float(f64),
    /// An integer.
    Int(i64),
    /// A string.
    Str(String),
    /// `len` copies of `c`.
    BigStr {
        /// The character.
        c: char,
        /// How many.
        len: u32,
    },
    /// A boolean.
    Bool(bool),
    /// An array.
    Array(Vec<Val>),
    /// `len` integers.
    BigArray {
        /// How many.
        len: u32,
    },
    /// An inline table.
    Table(Vec<(String, Val)>),
    /// A value nested `depth` levels deep in arrays or tables.
    Nested {
        /// Levels.
        depth: u16,
        /// Arrays (else tables).
        arrays: bool,
    },
    /// A TOML datetime.
    Datetime,
}

impl Val {
    /// As a TOML value.
    pub fn to_toml(&self) -> Value {
        match self {
            Self::Float(x) => Value::Float(*x),
            Self::Int(i) => Value::Integer(*i),
            Self::Str(s) => Value::String(s.clone()),
            Self::BigStr { c, len } => Value::String(std::iter::repeat_n(*c, *len as usize).collect()),
            Self::Bool(b) => Value::Boolean(*b),
            Self::Array(v) => Value::Array(v.iter().map(Self::to_toml).collect()),
            Self::BigArray { len } => Value::Array((0..i64::from(*len)).map(Value::Integer).collect()),
            Self::Table(kv) => Value::Table(kv.iter().map(|(k, v)| (k.clone(), v.to_toml())).collect()),
            Self::Nested { depth, arrays } => {
                let mut v = Value::Float(1.0);
                for _ in 0..*depth {
                    v = if *arrays { Value::Array(vec![v]) } else { Value::Table(Table::from_iter([("x".to_string(), v)])) };
                }
                v
            }
            Self::Datetime => Value::Datetime("1979-05-27T07:32:00Z".parse().unwrap_or_else(|_| unreachable!("a valid datetime"))),
        }
    }

    /// As the text of a `--set` value (TOML inline syntax, written here, not by
    /// `toml`: the writer must not be the parser under test).
    pub fn text(&self) -> String {
        match self {
            Self::Float(x) if x.is_nan() => if x.is_sign_negative() { "-nan" } else { "nan" }.into(),
            Self::Float(x) if x.is_infinite() => if *x > 0.0 { "inf" } else { "-inf" }.into(),
            Self::Float(x) => format!("{x:?}"),
            Self::Int(i) => i.to_string(),
            Self::Str(s) => quoted(s),
            Self::BigStr { c, len } => quoted(&std::iter::repeat_n(*c, *len as usize).collect::<String>()),
            Self::Bool(b) => b.to_string(),
            Self::Array(v) => format!("[{}]", v.iter().map(Self::text).collect::<Vec<_>>().join(", ")),
            Self::BigArray { len } => format!("[{}]", (0..*len).map(|i| i.to_string()).collect::<Vec<_>>().join(",")),
            Self::Table(kv) => {
                format!("{{{}}}", kv.iter().map(|(k, v)| format!("{} = {}", quoted(k), v.text())).collect::<Vec<_>>().join(", "))
            }
            Self::Nested { depth, arrays } => {
                let (open, close) = if *arrays { ("[", "]") } else { ("{x = ", "}") };
                format!("{}1.0{}", open.repeat(*depth as usize), close.repeat(*depth as usize))
            }
            Self::Datetime => "1979-05-27T07:32:00Z".into(),
        }
    }
}

/// A TOML basic string.
fn quoted(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Where an edit acts.
#[derive(Debug, Clone)]
pub enum Path {
    /// `KEYS[i]`.
    Known(usize),
    /// Key `name` in table `TABLES[table]`.
    Unknown {
        /// Index into [`TABLES`].
        table: usize,
        /// The key.
        name: String,
    },
    /// `faults[index].FAULT_KEYS[key]` (a new entry if there are fewer).
    Fault {
        /// The entry.
        index: u8,
        /// Index into [`FAULT_KEYS`].
        key: usize,
    },
    /// `plant.x.x.x...` (or at the top) `depth` tables deep.
    Deep {
        /// Tables.
        depth: u16,
        /// Under `[plant]` (else at the top).
        in_plant: bool,
    },
}

impl Path {
    pub(super) fn parts(&self) -> Vec<String> {
        match self {
            Self::Known(i) => KEYS[i % KEYS.len()].split('.').map(String::from).collect(),
            Self::Unknown { table, name } => {
                let t = TABLES[table % TABLES.len()];
                t.split('.').filter(|p| !p.is_empty()).map(String::from).chain([name.clone()]).collect()
            }
            Self::Fault { index, key } => vec!["faults".into(), index.to_string(), FAULT_KEYS[key % FAULT_KEYS.len()].into()],
            Self::Deep { depth, in_plant } => {
                let head = if *in_plant { "plant" } else { "zz" };
                std::iter::once(head.to_string()).chain(std::iter::repeat_n("x".to_string(), *depth as usize)).collect()
            }
        }
    }
}

/// A key with a value drawn from its documented range (`DOMAINS`): `t` in
/// `[0, 1)` places it, `pick` chooses a word, an end of the range (1 in 8 each) or
/// a `[[faults]]` entry.
#[derive(Debug, Clone)]
pub struct InRange {
    /// Index into the key table.
    pub key: usize,
    /// Where in the range.
    pub t: f64,
    /// Word, end or entry.
    pub pick: u8,
}

impl InRange {
    /// The key's path and the value.
    pub fn resolve(&self) -> (Vec<String>, Val) {
        let (name, domain) = DOMAINS[self.key % DOMAINS.len()];
        let path = match name.strip_prefix("faults.") {
            Some(k) => vec!["faults".to_string(), (self.pick / 8 % 4).to_string(), k.to_string()],
            None => name.split('.').map(String::from).collect(),
        };
        let float = |lo: f64, hi: f64, t: f64| match self.pick % 8 {
            0 => lo,
            1 => hi,
            _ => lo + t * (hi - lo),
        };
        let val = match domain {
            F(lo, hi) => Val::Float(float(lo, hi, self.t)),
            I(lo, hi) => Val::Int(lo.saturating_add(((hi as f64 - lo as f64) * self.t) as i64)),
            E(words) => Val::Str(words[usize::from(self.pick) % words.len()].to_string()),
            Pair(lo, hi) => Val::Array(vec![Val::Float(float(lo, hi, self.t)), Val::Float(lo + (self.t * 7.0).fract() * (hi - lo))]),
        };
        (path, val)
    }
}

/// A change to the document.
#[derive(Debug, Clone)]
pub enum Edit {
    /// Sets the value at a path (tables created on the way, a non-table crossed is replaced).
    Set(Path, Val),
    /// Sets a key to a value of its documented range.
    InRange(InRange),
    /// Removes the key at a path.
    Remove(Path),
}

/// A change to the written document's lines.
#[derive(Debug, Clone)]
pub enum LineEdit {
    /// Repeats line `i`.
    Repeat(usize),
    /// Removes line `i`.
    Remove(usize),
    /// Inserts a line before line `i`.
    Insert(usize, String),
}

/// The key of a `--set` argument.
#[derive(Debug, Clone)]
pub enum SetKey {
    /// A key with a value of its range (the argument's value is this one's).
    InRange(InRange),
    /// A path as in the edits.
    Path(Path),
    /// Any text.
    Raw(String),
    /// `plant.` followed by `depth` parts `x`: `depth + 1` parts, up to 70 000.
    Deep(u32),
}

/// The value of a `--set` argument.
#[derive(Debug, Clone)]
pub enum SetValue {
    /// A value in TOML inline syntax ([`Val::text`]).
    Val(Val),
    /// Any text (bare words, malformed TOML).
    Raw(String),
}

/// One `--set` argument.
#[derive(Debug, Clone)]
pub struct SetArg {
    /// The key.
    pub key: SetKey,
    /// The value.
    pub value: SetValue,
    /// Without `=` (a malformed argument).
    pub no_equals: bool,
}

impl SetArg {
    /// The argument as typed after `--set`.
    pub fn text(&self) -> String {
        let in_range = match &self.key {
            SetKey::InRange(r) => Some(r.resolve()),
            _ => None,
        };
        let key = match &self.key {
            SetKey::InRange(_) => in_range.as_ref().map(|(p, _)| p.join(".")).unwrap_or_default(),
            SetKey::Path(p) => p.parts().join("."),
            SetKey::Raw(s) => s.clone(),
            SetKey::Deep(depth) => format!("plant{}", ".x".repeat(*depth as usize)),
        };
        let value = match (&in_range, &self.value) {
            (Some((_, v)), _) => v.text(),
            (None, SetValue::Val(v)) => v.text(),
            (None, SetValue::Raw(s)) => s.clone(),
        };
        if self.no_equals { format!("{key}{value}") } else { format!("{key}={value}") }
    }
}

/// The scenario text of a case.
#[derive(Debug, Clone)]
pub enum Source {
    /// A base document (0 to 4: [`FILES`](super::FILES); 5: the default with three faults) with edits.
    Doc {
        /// The base.
        base: usize,
        /// Edits of the TOML table.
        edits: Vec<Edit>,
        /// Edits of the written lines.
        lines: Vec<LineEdit>,
    },
    /// A file with byte mutations.
    Bytes {
        /// Index into [`FILES`](super::FILES).
        file: usize,
        /// The mutations.
        mutations: Vec<Mutation>,
    },
}

/// One case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The scenario text.
    pub source: Source,
    /// `--set` arguments.
    pub sets: Vec<SetArg>,
}
