//! Checks a protobuf message against the schema an MCAP channel carries (a
//! `FileDescriptorSet`, schema encoding `protobuf`), without the types that
//! wrote it: every field's number is declared in the message type, its wire
//! type is the declared type's, strings are UTF-8, enum values are declared,
//! nested messages are checked by their own types, and the bytes end on a
//! field's end. What `trace.mcap`'s Foxglove channels are tested with, against
//! the schemas Foxglove publishes (the SDK's descriptors, written in the file).
//!
//! Source: the protobuf wire format, <https://protobuf.dev/programming-guides/encoding/>.

use std::collections::BTreeMap;

use prost::Message as _;
use prost_types::{DescriptorProto, EnumDescriptorProto, FileDescriptorSet, field_descriptor_proto::Label, field_descriptor_proto::Type};

/// The message and enum types of a `FileDescriptorSet`, by full name (`.foxglove.SceneUpdate`).
pub struct Schema {
    messages: BTreeMap<String, DescriptorProto>,
    enums: BTreeMap<String, EnumDescriptorProto>,
}

impl Schema {
    /// The types of the encoded `FileDescriptorSet` `data` (an MCAP schema's bytes).
    ///
    /// # Errors
    /// A message when `data` is not a `FileDescriptorSet`.
    pub fn parse(data: &[u8]) -> Result<Self, String> {
        let set = FileDescriptorSet::decode(data).map_err(|e| format!("not a FileDescriptorSet: {e}"))?;
        let mut s = Self { messages: BTreeMap::new(), enums: BTreeMap::new() };
        for file in &set.file {
            let prefix = match file.package() {
                "" => String::new(),
                p => format!(".{p}"),
            };
            for e in &file.enum_type {
                s.enums.insert(format!("{prefix}.{}", e.name()), e.clone());
            }
            for m in &file.message_type {
                s.add(&prefix, m);
            }
        }
        Ok(s)
    }

    fn add(&mut self, prefix: &str, m: &DescriptorProto) {
        let name = format!("{prefix}.{}", m.name());
        for e in &m.enum_type {
            self.enums.insert(format!("{name}.{}", e.name()), e.clone());
        }
        for n in &m.nested_type {
            self.add(&name, n);
        }
        self.messages.insert(name, m.clone());
    }

    /// Checks `bytes` as a message of type `name` (`foxglove.SceneUpdate`, with
    /// or without the leading dot).
    ///
    /// # Errors
    /// What is wrong and where: an unknown type or field, a wrong wire type, a
    /// truncated field, a string that is not UTF-8, an undeclared enum value.
    pub fn check(&self, name: &str, bytes: &[u8]) -> Result<(), String> {
        let full = if name.starts_with('.') { name.to_string() } else { format!(".{name}") };
        self.check_message(&full, bytes)
    }

    fn check_message(&self, name: &str, mut bytes: &[u8]) -> Result<(), String> {
        let m = self.messages.get(name).ok_or_else(|| format!("type {name} is not in the schema"))?;
        while !bytes.is_empty() {
            let key = varint(&mut bytes).ok_or_else(|| format!("{name}: a truncated field key"))?;
            let (number, wire) = (key >> 3, key & 7);
            let field = m
                .field
                .iter()
                .find(|f| i64::from(f.number()) == i64::try_from(number).unwrap_or(-1))
                .ok_or_else(|| format!("{name}: field number {number} is not declared"))?;
            let at = format!("{name}.{}", field.name());
            let ty = field.r#type();
            let expected = match ty {
                Type::Double | Type::Fixed64 | Type::Sfixed64 => 1,
                Type::Float | Type::Fixed32 | Type::Sfixed32 => 5,
                Type::String | Type::Bytes | Type::Message | Type::Group => 2,
                _ => 0,
            };
            let packed = field.label() == Label::Repeated && expected != 2 && wire == 2;
            if wire != expected && !packed {
                return Err(format!("{at}: wire type {wire}, the schema's {ty:?} needs {expected}"));
            }
            match wire {
                0 => {
                    let v = varint(&mut bytes).ok_or_else(|| format!("{at}: a truncated varint"))?;
                    if ty == Type::Enum {
                        self.check_enum(&at, field.type_name(), v)?;
                    }
                }
                1 => bytes = bytes.get(8..).ok_or_else(|| format!("{at}: a truncated 64-bit value"))?,
                5 => bytes = bytes.get(4..).ok_or_else(|| format!("{at}: a truncated 32-bit value"))?,
                2 => {
                    let len =
                        varint(&mut bytes).and_then(|l| usize::try_from(l).ok()).ok_or_else(|| format!("{at}: a truncated length"))?;
                    let (body, rest) =
                        (bytes.get(..len).ok_or_else(|| format!("{at}: {len} bytes announced, {} left", bytes.len()))?, &bytes[len..]);
                    match ty {
                        Type::Message => self.check_message(field.type_name(), body)?,
                        Type::String => {
                            std::str::from_utf8(body).map_err(|e| format!("{at}: not UTF-8: {e}"))?;
                        }
                        _ if packed => {
                            let width = match expected {
                                1 => Some(8),
                                5 => Some(4),
                                _ => None,
                            };
                            match width {
                                Some(w) if body.len() % w != 0 => {
                                    return Err(format!("{at}: {} packed bytes, not a multiple of {w}", body.len()));
                                }
                                Some(_) => {}
                                None => {
                                    let mut b = body;
                                    while !b.is_empty() {
                                        varint(&mut b).ok_or_else(|| format!("{at}: a truncated packed varint"))?;
                                    }
                                }
                            }
                        }
                        _ => {}
                    }
                    bytes = rest;
                }
                other => return Err(format!("{at}: wire type {other} is not used by proto3")),
            }
        }
        Ok(())
    }

    fn check_enum(&self, at: &str, type_name: &str, v: u64) -> Result<(), String> {
        let e = self.enums.get(type_name).ok_or_else(|| format!("{at}: enum {type_name} is not in the schema"))?;
        // An enum is an int32 on the wire; a negative one is sign-extended to 64 bits.
        let value = v as i64 as i32;
        if e.value.iter().any(|x| x.number() == value) { Ok(()) } else { Err(format!("{at}: {value} is not a value of {type_name}")) }
    }
}

/// Reads a base-128 varint off the front of `bytes`; `None` when truncated or longer than 10 bytes.
fn varint(bytes: &mut &[u8]) -> Option<u64> {
    let mut v = 0u64;
    for i in 0..10 {
        let b = *bytes.get(i)?;
        v |= u64::from(b & 0x7f) << (7 * i);
        if b & 0x80 == 0 {
            *bytes = &bytes[i + 1..];
            return Some(v);
        }
    }
    None
}
