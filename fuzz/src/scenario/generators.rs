//! The proptest strategies of the cases (module docs of `scenario`): hostile
//! values, paths, edits, line edits, byte mutations and `--set` arguments.

use proptest::{collection::vec, prelude::*, sample::select};

use super::{
    case::{Case, Edit, InRange, LineEdit, Path, SetArg, SetKey, SetValue, Source, Val},
    hostile::{BOUNDS, INTS, WORDS},
    keys::{DOMAINS, FAULT_KEYS, FILES, KEYS, TABLES},
};
use crate::pil_decode::Mutation;

fn in_range() -> impl Strategy<Value = InRange> {
    (0..DOMAINS.len(), 0.0f64..1.0, any::<u8>()).prop_map(|(key, t, pick)| InRange { key, t, pick })
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
