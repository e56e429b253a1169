//! Target `scenario`: [`Scenario::from_toml`] and [`Scenario::from_toml_with`]
//! (the command line's `--set KEY=VALUE`, `rig::overrides`) under hostile input.
//!
//! A case is either
//!
//! - **a document**: one of `scenarios/*.toml` (or the default with three valid
//!   `[[faults]]`) as a TOML table, changed by up to 8 edits (a key of the
//!   scenario's key set, an unknown key, or a key 3 to 300 tables deep set to a
//!   hostile value or removed; a `[[faults]]` entry added), written back as TOML
//!   and then changed line by line (lines repeated, removed or replaced by
//!   hostile ones); or
//! - **bytes**: a scenario file with 1 to 8 byte mutations (those of
//!   [`crate::pil_decode::Mutation`]), read as UTF-8 with replacement characters,
//!
//! and up to 4 `--set` arguments (a known, unknown, malformed or very deep key
//! with a TOML, bare-word or malformed value).
//!
//! Hostile values: floats at and one or two ulps around every documented bound
//! (and the `f32` range's), NaN, infinities, `-0.0`, subnormals, any bits; integers
//! at the ends of `u8`, `u16`, `u32` and `i64`; the enum words of every key,
//! `"nan"`, `""`, strings up to 100 000 characters, odd Unicode; booleans; arrays
//! (up to 100 000 elements) and inline tables, nested up to 300 levels.
//!
//! The property ([`check`]): no panic, no stack overflow (on the 8 MiB stack of
//! [`crate::on_harness_thread`]); an accepted scenario satisfies every bound of
//! docs/rig.md's tables, re-checked here independently ([`violations`]), its
//! firmware configuration is one the firmware accepts, and it round-trips (written
//! with `toml` and read again it is the same scenario, bit for bit: the firmware
//! process gets its scenario that way); `from_toml_with` and
//! `from_toml` followed by [`Scenario::with_overrides`] agree when both accept;
//! without overrides `from_toml_with` is `from_toml`; an error's message is not
//! empty and names a key (in backticks, or the `--set` argument) or where the
//! TOML is malformed (line and column) ([`error_names_its_place`]).

use firmware::Firmware;
use proptest::{collection::vec, prelude::*, sample::select};
use rig::{
    faults::FaultKind,
    overrides::Override,
    scenario::{Scenario, ScenarioError},
    setup::firmware_config,
};
use toml::{Table, Value};

use crate::{ensure, pil_decode::Mutation};

/// The repository's scenario files.
pub const FILES: [&str; 5] = [
    include_str!("../../scenarios/default.toml"),
    include_str!("../../scenarios/hybrid-x0d.toml"),
    include_str!("../../scenarios/hybrid-x0u.toml"),
    include_str!("../../scenarios/pid-x0d.toml"),
    include_str!("../../scenarios/pid-x0u.toml"),
];

/// Three valid faults appended to the default scenario (the sixth base document).
const FAULTS: &str = r#"
[[faults]]
kind = "late_command"
at_s = 3.0
duration_s = 0.005
delay_s = 0.0015

[[faults]]
kind = "stuck_sensor"
at_s = 1.0
signal = "f_n"

[[faults]]
kind = "stall"
at_s = 2.0
duration_s = 0.5
"#;

/// Every key of a scenario file, dotted (docs/rig.md "The scenario file"), and the
/// old `controller.hybrid_ki`.
pub const KEYS: &[&str] = &[
    "name",
    "plant.mu",
    "plant.v_belt",
    "plant.x0",
    "plant.impact_law",
    "plant.e_n",
    "plant.iwc",
    "plant.rtol",
    "plant.atol",
    "plant.m",
    "plant.l",
    "plant.sigma",
    "plant.k",
    "plant.h",
    "plant.alpha0",
    "plant.g",
    "controller.kind",
    "controller.target_z_t",
    "controller.move_time_s",
    "controller.f_n_ref",
    "controller.friction",
    "controller.mu_hat",
    "controller.hybrid_ki",
    "controller.pid.kp",
    "controller.pid.ki",
    "controller.pid.kd",
    "controller.hybrid.kp",
    "controller.hybrid.kd",
    "controller.hybrid.ki",
    "controller.model.m",
    "controller.model.l",
    "controller.model.sigma",
    "controller.model.k",
    "controller.model.h",
    "controller.model.alpha0",
    "controller.model.g",
    "timing.rate_hz",
    "timing.delta_s",
    "timing.duration_s",
    "sensors.seed",
    "sensors.load_noise_n",
    "sensors.encoder_bits",
    "rig.command_timeout_s",
    "rig.spin_us",
    "rig.peer_check_s",
    "rig.max_consecutive_timeouts",
    "rig.realtime_cpu",
    "rig.realtime_fifo_priority",
    "rig.connect_timeout_s",
    "plant",
    "controller",
    "controller.pid",
    "controller.hybrid",
    "controller.model",
    "timing",
    "sensors",
    "rig",
    "faults",
];

/// The tables of a scenario (where unknown keys go).
pub const TABLES: &[&str] =
    &["", "plant", "controller", "controller.pid", "controller.hybrid", "controller.model", "timing", "sensors", "rig"];

/// The keys of a `[[faults]]` entry.
pub const FAULT_KEYS: &[&str] = &["kind", "at_s", "duration_s", "delay_s", "signal"];

/// The words the scenario's string keys take, and near misses.
pub const WORDS: &[&str] = &[
    "pid",
    "hybrid",
    "lqr",
    "a",
    "d",
    "u",
    "x0d",
    "newton",
    "poisson",
    "energetic",
    "restitution",
    "plastic",
    "commanded",
    "measured",
    "measured_normal",
    "none",
    "last",
    "first",
    " last ",
    "0",
    "3",
    "+3",
    "-1",
    "1023",
    "1024",
    "99999999999999999999999",
    "late_command",
    "drop_command",
    "stall",
    "kill_firmware",
    "stuck_sensor",
    "nan_sensor",
    "out_of_range",
    "theta1",
    "elbow",
    "f_t",
    "f_n",
    "belt",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e999",
    "",
    " ",
    "Pid",
    "\u{0}",
    "\u{202e}evil",
    "é",
    "\u{1F600}",
    "\"",
    "\\",
    "'",
    "\n",
    "\t",
    "#",
    "=",
    "[",
    "]]",
    "\u{feff}",
];

/// Documented bounds (docs/rig.md) and the `f32` range's, each tried exactly and
/// a few ulps off, with both signs.
const BOUNDS: &[f64] = &[
    0.0,
    1.0,
    0.1,
    1e-14,
    0.21,
    0.42,
    0.3775,
    0.6,
    2.0,
    3.0,
    5.0,
    10.0,
    25.0,
    60.0,
    99.0,
    100.0,
    250.0,
    600.0,
    1000.0,
    4000.0,
    10_000.0,
    1e5,
    1e6,
    0.0001,
    0.0002,
    0.000_166_666_666_666_666_66,
    0.001,
    0.004,
    0.05,
    1024.0,
    65536.0,
    2_147_483_648.0,
    4_294_967_296.0,
    9_007_199_254_740_992.0,
    9_223_372_036_854_775_808.0,
    18_446_744_073_709_551_616.0,
    f32::MAX as f64,
    // The midpoint between f32::MAX and 2^128: from here up, f32 rounds to infinity.
    3.402_823_567_797_336_6e38,
    1e39,
    1e300,
    f64::MAX,
    1e-38,
    1e-45,
    1e-46,
    f64::MIN_POSITIVE,
    5e-324,
];

const INTS: &[i64] = &[
    0,
    1,
    -1,
    2,
    9,
    10,
    16,
    17,
    99,
    100,
    255,
    256,
    1000,
    1001,
    1023,
    1024,
    65535,
    65536,
    4_294_967_295,
    4_294_967_296,
    i64::MAX,
    i64::MIN,
];

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
    fn parts(&self) -> Vec<String> {
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

/// The documented range of a key (docs/rig.md), to draw values that are accepted.
#[derive(Debug, Clone, Copy)]
enum Domain {
    /// A float in `[lo, hi]`.
    F(f64, f64),
    /// An integer in `[lo, hi]`.
    I(i64, i64),
    /// One of these words.
    E(&'static [&'static str]),
    /// Two floats in `[lo, hi]`.
    Pair(f64, f64),
}

use Domain::{E, F, I, Pair};

/// The keys with their documented ranges (`faults.K`: key `K` of a `[[faults]]` entry).
const DOMAINS: &[(&str, Domain)] = &[
    ("name", E(&["x", "hybrid-x0d", "é\u{1F600}", "sixty-four characters, exactly: ................................."])),
    ("plant.mu", F(0.0, 10.0)),
    ("plant.v_belt", F(-5.0, 5.0)),
    ("plant.x0", E(&["a", "d", "u"])),
    ("plant.impact_law", E(&["newton", "poisson", "energetic"])),
    ("plant.e_n", F(0.0, 1.0)),
    ("plant.iwc", E(&["restitution", "plastic"])),
    ("plant.rtol", F(1e-14, 0.1)),
    ("plant.atol", F(1e-14, 0.1)),
    ("plant.m", F(1e-3, 100.0)),
    ("plant.l", F(0.19, 2.0)),
    ("plant.sigma", F(0.0, 10.0)),
    ("plant.k", F(0.0, 100.0)),
    ("plant.h", F(1e-3, 0.42)),
    ("plant.alpha0", F(-7.0, 7.0)),
    ("plant.g", F(1e-3, 100.0)),
    ("controller.kind", E(&["pid", "hybrid"])),
    ("controller.target_z_t", F(-0.42, 0.42)),
    ("controller.move_time_s", F(1e-300, 1e5)),
    ("controller.f_n_ref", F(0.0, 25.0)),
    ("controller.friction", E(&["commanded", "measured_normal", "measured", "none"])),
    ("controller.mu_hat", F(0.0, 10.0)),
    ("controller.hybrid_ki", F(0.0, 1e4)),
    ("controller.pid.kp", Pair(0.0, 1e4)),
    ("controller.pid.ki", Pair(0.0, 1e4)),
    ("controller.pid.kd", Pair(0.0, 1e3)),
    ("controller.hybrid.kp", F(0.0, 1e38)),
    ("controller.hybrid.kd", F(0.0, 1e4)),
    ("controller.hybrid.ki", F(0.0, 1e4)),
    ("controller.model.m", F(1e-50, 100.0)),
    ("controller.model.l", F(0.19, 2.0)),
    ("controller.model.sigma", F(0.0, 10.0)),
    ("controller.model.k", F(0.0, 100.0)),
    ("controller.model.h", F(1e-3, 0.42)),
    ("controller.model.alpha0", F(-7.0, 7.0)),
    ("controller.model.g", F(1e-3, 100.0)),
    ("timing.rate_hz", F(250.0, 10_000.0)),
    ("timing.delta_s", F(0.0, 1e-4)),
    ("timing.duration_s", F(1e-3, 1e5)),
    ("sensors.seed", I(0, i64::MAX)),
    ("sensors.load_noise_n", F(0.0, 25.0)),
    ("sensors.encoder_bits", I(10, 16)),
    ("rig.command_timeout_s", F(1e-3, 60.0)),
    ("rig.spin_us", F(0.0, 1e6)),
    ("rig.peer_check_s", F(1e-3, 60.0)),
    ("rig.max_consecutive_timeouts", I(1, 4_294_967_295)),
    ("rig.realtime_cpu", E(&["last", "none", "0", "3", "1023", " last"])),
    ("rig.realtime_fifo_priority", I(0, 99)),
    ("rig.connect_timeout_s", F(1e-3, 600.0)),
    ("faults.kind", E(&["late_command", "drop_command", "stall", "kill_firmware", "stuck_sensor", "nan_sensor", "out_of_range"])),
    ("faults.at_s", F(0.0, 12.0)),
    ("faults.duration_s", F(0.0, 60.0)),
    ("faults.delay_s", F(1e-6, 9.99)),
    ("faults.signal", E(&["theta1", "elbow", "f_t", "f_n", "belt"])),
];

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

fn in_range() -> impl Strategy<Value = InRange> {
    (0..DOMAINS.len(), 0.0f64..1.0, any::<u8>()).prop_map(|(key, t, pick)| InRange { key, t, pick })
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
    /// A base document (0 to 4: [`FILES`]; 5: the default with three faults) with edits.
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
        /// Index into [`FILES`].
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

fn ulps(x: f64, k: i8) -> f64 {
    if !x.is_finite() || k == 0 {
        return x;
    }
    // Steps along the ordered floats (k > 0 up).
    let mut y = x;
    for _ in 0..k.unsigned_abs() {
        y = if k > 0 { y.next_up() } else { y.next_down() };
    }
    y
}

fn float() -> impl Strategy<Value = f64> {
    let special = vec![f64::NAN, -f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 0.0];
    prop_oneof![
        6 => (select(BOUNDS.to_vec()), -2i8..=2, any::<bool>()).prop_map(|(b, k, neg)| ulps(if neg { -b } else { b }, k)),
        1 => select(special),
        1 => any::<u64>().prop_map(f64::from_bits),
        2 => -1e3f64..1e3,
    ]
}

fn int() -> impl Strategy<Value = i64> {
    prop_oneof![3 => (select(INTS.to_vec()), -1i64..=1).prop_map(|(i, d)| i.saturating_add(d)), 1 => any::<i64>()]
}

fn string() -> impl Strategy<Value = String> {
    prop_oneof![4 => select(WORDS.to_vec()).prop_map(String::from), 1 => ".{0,12}", 1 => "[a-z_]{1,70}"]
}

fn leaf() -> impl Strategy<Value = Val> {
    prop_oneof![
        8 => float().prop_map(Val::Float),
        4 => int().prop_map(Val::Int),
        5 => string().prop_map(Val::Str),
        1 => any::<bool>().prop_map(Val::Bool),
        1 => Just(Val::Datetime),
    ]
}

fn val() -> impl Strategy<Value = Val> {
    prop_oneof![
        40 => leaf(),
        4 => vec(leaf(), 0..4).prop_map(Val::Array),
        2 => vec(("[a-z_]{1,8}", leaf()), 0..4).prop_map(Val::Table),
        1 => (1u16..=300, any::<bool>()).prop_map(|(depth, arrays)| Val::Nested { depth, arrays }),
        // Huge values are rare: one of 100 000 elements costs as much as 2000 cases.
        1 => (select(vec!['x', 'é', '\u{1F600}', '"', '\n']), prop_oneof![100 => 0u32..100, 100 => 60u32..70, 4 => Just(10_000u32), 1 => Just(100_000u32)])
            .prop_map(|(c, len)| Val::BigStr { c, len }),
        1 => prop_oneof![200 => 0u32..4, 4 => Just(1000u32), 1 => Just(100_000u32)].prop_map(|len| Val::BigArray { len }),
    ]
}

fn unknown_name() -> impl Strategy<Value = String> {
    prop_oneof![
        select(vec!["muu", "x", "", " ", "a.b", "plant", "Name", "faults", "ключ", "\"q\"", "\u{0}", "hybrid_ki"]).prop_map(String::from),
        "[a-z_]{1,12}",
        "x{1000}"
    ]
}

fn path() -> impl Strategy<Value = Path> {
    prop_oneof![
        12 => (0..KEYS.len()).prop_map(Path::Known),
        2 => (0..TABLES.len(), unknown_name()).prop_map(|(table, name)| Path::Unknown { table, name }),
        3 => (0u8..5, 0..FAULT_KEYS.len()).prop_map(|(index, key)| Path::Fault { index, key }),
        1 => (prop_oneof![2u16..8, 8u16..=300], any::<bool>()).prop_map(|(depth, in_plant)| Path::Deep { depth, in_plant }),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![6 => (path(), val()).prop_map(|(p, v)| Edit::Set(p, v)), 6 => in_range().prop_map(Edit::InRange), 1 => path().prop_map(Edit::Remove)]
}

fn line() -> impl Strategy<Value = String> {
    let hostile = vec![
        "[plant]",
        "[[faults]]",
        "[controller.pid",
        "name = 1",
        "name = \"x\"",
        "x = ",
        "mu = 0.6",
        "= 1",
        "\u{feff}",
        "[rig]\nrig = 1",
        "plant.mu = 1",
        "\"plant\".\"mu\" = 0.5",
        "[timing]\nrate_hz = 1e999",
        "faults = []",
        "a = [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]",
    ];
    prop_oneof![3 => select(hostile).prop_map(String::from), 1 => ".{0,20}"]
}

fn line_edit() -> impl Strategy<Value = LineEdit> {
    prop_oneof![
        1 => any::<usize>().prop_map(LineEdit::Repeat),
        1 => any::<usize>().prop_map(LineEdit::Remove),
        1 => (any::<usize>(), line()).prop_map(|(i, l)| LineEdit::Insert(i, l)),
    ]
}

fn byte_mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), any::<u8>()).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        2 => (any::<usize>(), prop_oneof![select(b"0123456789.-+eE\"'[]=#\n {},_".to_vec()), any::<u8>()])
            .prop_map(|(at, byte)| Mutation::Set { at, byte }),
        2 => (any::<usize>(), prop_oneof![select(b"0123456789.-+eE\"'[]=#\n {},_".to_vec()), any::<u8>()])
            .prop_map(|(at, byte)| Mutation::Insert { at, byte }),
        2 => (any::<usize>(), 1u8..=8).prop_map(|(at, len)| Mutation::Delete { at, len }),
        1 => (any::<usize>(), 1u8..=64).prop_map(|(at, len)| Mutation::Duplicate { at, len }),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::Swap { a, b }),
        1 => any::<usize>().prop_map(|at| Mutation::Truncate { at }),
    ]
}

fn set_arg() -> impl Strategy<Value = SetArg> {
    let key = prop_oneof![
        8 => in_range().prop_map(SetKey::InRange),
        4 => path().prop_map(SetKey::Path),
        1 => select(vec!["", ".", "plant.", ".plant.m", "plant..m", "plant. m", " plant.m ", "plant.m=1", "faults.0.kind", "faults"])
            .prop_map(|s| SetKey::Raw(s.into())),
        1 => prop_oneof![3u32..10, 10u32..1000, 60_000u32..=70_000].prop_map(SetKey::Deep),
    ];
    let raw = select(vec![
        "",
        " ",
        "[1",
        "pid",
        "x0d",
        "nan",
        "-nan",
        "1_000",
        "0x10",
        "1e",
        "\"open",
        "'lit'",
        "[1,]",
        "{a=1",
        "true",
        "=",
        "1979-05-27",
        "inf",
    ]);
    let value = prop_oneof![6 => val().prop_map(SetValue::Val), 2 => raw.prop_map(|s| SetValue::Raw(s.into())), 1 => ".{0,12}".prop_map(SetValue::Raw)];
    (key, value, prop::bool::weighted(0.03)).prop_map(|(key, value, no_equals)| SetArg { key, value, no_equals })
}

/// The cases of this target.
pub fn strategy() -> impl Strategy<Value = Case> {
    // Half the documents get only in-range values, so that accepted scenarios (and
    // the properties on them) are frequent.
    let edits = prop_oneof![vec(edit(), 0..=8), vec(in_range().prop_map(Edit::InRange), 0..=8)];
    let doc = (0usize..6, edits, vec(line_edit(), 0..=2)).prop_map(|(base, edits, lines)| Source::Doc { base, edits, lines });
    let bytes = (0..FILES.len(), vec(byte_mutation(), 1..=8)).prop_map(|(file, mutations)| Source::Bytes { file, mutations });
    let source = prop_oneof![3 => doc, 1 => bytes];
    let in_range_set = in_range().prop_map(|r| SetArg { key: SetKey::InRange(r), value: SetValue::Raw(String::new()), no_equals: false });
    let sets = prop_oneof![2 => Just(Vec::new()), 1 => vec(set_arg(), 1..=4), 1 => vec(in_range_set, 1..=4)];
    (source, sets).prop_map(|(source, sets)| Case { source, sets })
}

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

/// Every documented bound (docs/rig.md, "The scenario file") that `s` breaks,
/// checked here without `Scenario::validate`.
pub fn violations(s: &Scenario) -> Vec<String> {
    let mut v = Vec::new();
    let mut need = |ok: bool, what: &str| {
        if !ok {
            v.push(what.to_string());
        }
    };
    let fin = |x: f64| x.is_finite();
    let within = |x: f64, lo: f64, hi: f64| x.is_finite() && lo <= x && x <= hi;
    let name_chars = s.name.chars().count();
    need((1..=64).contains(&name_chars), "name: 1 to 64 characters");
    need(s.faults.len() <= 1000, "faults: at most 1000");
    let p = &s.plant;
    need(within(p.mu, 0.0, 10.0), "plant.mu in [0, 10]");
    need(within(p.v_belt, -5.0, 5.0), "plant.v_belt within +-5");
    need(within(p.e_n, 0.0, 1.0), "plant.e_n in [0, 1]");
    need(within(p.rtol, 1e-14, 0.1), "plant.rtol in [1e-14, 0.1]");
    need(within(p.atol, 1e-14, 0.1), "plant.atol in [1e-14, 0.1]");
    let arm = |need: &mut dyn FnMut(bool, &str), prefix: &str, m: f64, l: f64, sigma: f64, k: f64, h: f64, alpha0: f64, g: f64| {
        for (name, x) in [("m", m), ("l", l), ("h", h), ("g", g)] {
            need(fin(x) && x > 0.0, &format!("{prefix}.{name} finite and > 0"));
        }
        for (name, x) in [("sigma", sigma), ("k", k)] {
            need(fin(x) && x >= 0.0, &format!("{prefix}.{name} finite and >= 0"));
        }
        need(fin(alpha0), &format!("{prefix}.alpha0 finite"));
        need(h < 2.0 * l, &format!("{prefix}.h < 2 l"));
    };
    arm(&mut need, "plant", p.m, p.l, p.sigma, p.k, p.h, p.alpha0, p.g);
    let c = &s.controller;
    need(fin(c.target_z_t) && c.target_z_t.abs() < 2.0 * p.l, "controller.target_z_t: |z_t*| < 2 l");
    need(fin(c.move_time_s) && c.move_time_s > 0.0 && c.move_time_s <= 1e5, "controller.move_time_s in (0, 1e5]");
    need(within(c.f_n_ref, 0.0, 25.0), "controller.f_n_ref in [0, 25]");
    need(within(c.mu_hat, 0.0, 10.0), "controller.mu_hat in [0, 10]");
    // The firmware's f32 (docs/rig.md): at most 3.4e38, positive values not rounding to 0.
    let f32_fin = |x: f64| (x as f32).is_finite();
    let gain = |x: f64| fin(x) && x >= 0.0 && f32_fin(x);
    for (name, g) in [("kp", c.pid.kp), ("ki", c.pid.ki), ("kd", c.pid.kd)] {
        need(g.iter().all(|&x| gain(x)), &format!("controller.pid.{name}: finite gains >= 0"));
    }
    need(gain(c.hybrid.kp) && gain(c.hybrid.kd), "controller.hybrid.kp, kd: finite >= 0");
    need(c.hybrid.ki.is_none_or(gain), "controller.hybrid.ki: finite >= 0");
    if let Some(m) = &c.model {
        let g = |x: Option<f64>, plant: f64| x.unwrap_or(plant);
        let l = g(m.l, p.l);
        arm(
            &mut need,
            "controller.model",
            g(m.m, p.m),
            l,
            g(m.sigma, p.sigma),
            g(m.k, p.k),
            g(m.h, p.h),
            g(m.alpha0, p.alpha0),
            g(m.g, p.g),
        );
        need(c.target_z_t.abs() < 2.0 * l, "controller.target_z_t: |z_t*| < 2 controller.model.l");
    }
    let model = c.model.unwrap_or_default();
    let fw = |x: Option<f64>, plant: f64| x.unwrap_or(plant) as f32;
    let (m, l, h, g) = (fw(model.m, p.m), fw(model.l, p.l), fw(model.h, p.h), fw(model.g, p.g));
    let (sigma, k, alpha0) = (fw(model.sigma, p.sigma), fw(model.k, p.k), fw(model.alpha0, p.alpha0));
    need([m, l, h, g, sigma, k, alpha0].iter().all(|x| x.is_finite()), "the firmware's model finite in f32");
    need(m > 0.0 && l > 0.0 && h > 0.0 && g > 0.0, "the firmware's m, l, h, g > 0 in f32");
    need(h < 2.0 * l, "the firmware's h < 2 l in f32");
    need((c.target_z_t as f32).abs() < 2.0 * l, "controller.target_z_t: |z_t*| < 2 l in f32");
    need((c.move_time_s as f32) > 0.0, "controller.move_time_s > 0 in f32");
    let t = &s.timing;
    need(within(t.rate_hz, 250.0, 10_000.0), "timing.rate_hz in [250, 10000]");
    // One period: the rate's, rounded to whole microseconds (shared::time).
    let period_s = (1e6 / t.rate_hz).round() / 1e6;
    need(fin(t.delta_s) && t.delta_s >= 0.0 && t.delta_s < period_s, "timing.delta_s in [0, one period)");
    need(fin(t.duration_s) && t.duration_s > 0.0 && t.duration_s <= 1e5, "timing.duration_s in (0, 1e5]");
    need(within(s.sensors.load_noise_n, 0.0, 25.0), "sensors.load_noise_n in [0, 25]");
    need((10..=16).contains(&s.sensors.encoder_bits), "sensors.encoder_bits 10 to 16");
    let r = &s.rig;
    need(fin(r.command_timeout_s) && r.command_timeout_s > 0.0 && r.command_timeout_s <= 60.0, "rig.command_timeout_s in (0, 60]");
    need(within(r.spin_us, 0.0, 1e6), "rig.spin_us in [0, 1e6]");
    need(fin(r.peer_check_s) && r.peer_check_s > 0.0 && r.peer_check_s <= 60.0, "rig.peer_check_s in (0, 60]");
    need(r.max_consecutive_timeouts >= 1, "rig.max_consecutive_timeouts >= 1");
    let cpu = r.realtime_cpu.trim();
    let digits = cpu.strip_prefix('+').unwrap_or(cpu);
    let number = !digits.is_empty()
        && digits.bytes().all(|b| b.is_ascii_digit())
        && digits.trim_start_matches('0').len() <= 4
        && digits.parse::<u32>().is_ok_and(|n| n < 1024);
    need(cpu == "last" || cpu == "none" || number, "rig.realtime_cpu: last, none or a CPU number below 1024");
    need(r.realtime_fifo_priority <= 99, "rig.realtime_fifo_priority 0 to 99");
    need(fin(r.connect_timeout_s) && r.connect_timeout_s > 0.0 && r.connect_timeout_s <= 600.0, "rig.connect_timeout_s in (0, 600]");
    for (i, f) in s.faults.iter().enumerate() {
        need(fin(f.at_s) && f.at_s >= 0.0 && f.at_s < t.duration_s, &format!("faults[{i}].at_s in [0, timing.duration_s)"));
        need(within(f.duration_s, 0.0, 1e5), &format!("faults[{i}].duration_s in [0, 1e5]"));
        let sensor = matches!(f.kind, FaultKind::StuckSensor | FaultKind::NanSensor | FaultKind::OutOfRange);
        need(!sensor || f.signal.is_some(), &format!("faults[{i}]: a sensor fault has a signal"));
        need(fin(f.delay_s) && f.delay_s >= 0.0 && f.delay_s < 10.0, &format!("faults[{i}].delay_s in [0, 10)"));
        need(f.kind != FaultKind::LateCommand || f.delay_s > 0.0, &format!("faults[{i}].delay_s of a late_command in (0, 10)"));
        need(
            f.kind != FaultKind::Stall || (f.duration_s > 0.0 && f.duration_s <= 60.0),
            &format!("faults[{i}].duration_s of a stall in (0, 60]"),
        );
    }
    v
}

/// Whether an error message names its place: not empty, and a key in backticks
/// (`scenario key \`plant.m\``, ``unknown field `muu` ``), a `--set` argument, a
/// line and column of the TOML text, or, for the one TOML error without a place
/// (the reader's nesting limit), that the scenario is not valid TOML and why.
pub fn error_names_its_place(msg: &str) -> bool {
    let backticked = msg.split('`').count() >= 3;
    let located = msg.contains("at line ") && msg.contains(", column ");
    let said = msg.strip_prefix("the scenario is not valid TOML: ").is_some_and(|why| !why.trim().is_empty());
    !msg.trim().is_empty() && (backticked || located || said || msg.contains("--set "))
}

/// The paths of the non-finite floats in `v`.
fn non_finite(v: &Value, at: &str, out: &mut Vec<String>) {
    match v {
        Value::Float(x) if !x.is_finite() => out.push(at.to_string()),
        Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| non_finite(x, &format!("{at}[{i}]"), out)),
        Value::Table(t) => t.iter().for_each(|(k, x)| non_finite(x, &format!("{at}.{k}"), out)),
        _ => {}
    }
}

/// Checks an accepted scenario: bounds, firmware configuration, round trip.
///
/// # Errors
/// What is wrong.
pub fn check_accepted(s: &Scenario) -> Result<(), String> {
    let v = violations(s);
    ensure(v.is_empty(), || format!("accepted a scenario that breaks documented bounds: {v:?}"))?;
    // Every number, used or not (a NaN in an unused field reads back as `null` from summary.json).
    let table = toml::Table::try_from(s).map_err(|e| format!("an accepted scenario is not a TOML table: {e}"))?;
    let mut odd = Vec::new();
    non_finite(&Value::Table(table), "", &mut odd);
    ensure(odd.is_empty(), || format!("accepted a scenario with non-finite numbers at {odd:?}"))?;
    Firmware::new(firmware_config(s)).map_err(|e| format!("accepted a scenario whose firmware configuration the firmware refuses: {e}"))?;
    let written = toml::to_string(s).map_err(|e| format!("an accepted scenario cannot be written as TOML: {e}"))?;
    match Scenario::from_toml(&written) {
        Ok(back) => ensure(format!("{back:?}") == format!("{s:?}"), || {
            format!("round trip changed the scenario:\n{written}\nread back as {back:?}")
        }),
        Err(e) => Err(format!("an accepted scenario, written as TOML, is refused: {e}\n{written}")),
    }
}

fn check_refused(e: &ScenarioError) -> Result<(), String> {
    let msg = e.to_string();
    ensure(error_names_its_place(&msg), || format!("the error names no key nor place: {msg:?}"))?;
    if let ScenarioError::OutOfRange { key, .. } = e {
        let known = KEYS.contains(&key.as_str()) || key == "faults" || key == "controller.hybrid.ki";
        ensure(known, || format!("out-of-range error names `{key}`, not a scenario key"))?;
    }
    Ok(())
}

/// The property of this target (module docs).
///
/// # Errors
/// What is wrong.
pub fn check(case: &Case) -> Result<(), String> {
    let text = text(&case.source);
    let mut overrides = Vec::new();
    for arg in &case.sets {
        match arg.text().parse::<Override>() {
            Ok(o) => overrides.push(o),
            Err(e) => {
                let msg = e.to_string();
                ensure(error_names_its_place(&msg) && msg.contains("--set"), || format!("--set error names no argument: {msg:?}"))?;
            }
        }
    }
    let plain = Scenario::from_toml(&text);
    let with = Scenario::from_toml_with(&text, &overrides);
    for r in [&plain, &with] {
        match r {
            Ok(s) => check_accepted(s)?,
            Err(e) => check_refused(e)?,
        }
    }
    if overrides.is_empty() {
        let same = match (&plain, &with) {
            (Ok(a), Ok(b)) => a == b,
            (Err(a), Err(b)) => a.to_string() == b.to_string(),
            _ => false,
        };
        ensure(same, || format!("from_toml gives {plain:?}, from_toml_with without overrides {with:?}"))?;
    } else if let (Ok(base), Ok(s)) = (&plain, &with) {
        match base.with_overrides(&overrides) {
            Ok(again) => ensure(&again == s, || format!("with_overrides gives {again:?}, from_toml_with {s:?}"))?,
            Err(e) => return Err(format!("from_toml_with accepts, from_toml + with_overrides refuses: {e}")),
        }
    }
    Ok(())
}
