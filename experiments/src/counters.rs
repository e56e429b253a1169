//! The plant's event counters as the outputs publish them (`simulate`'s
//! `summary.json` `counters`, the Python package's `Plant.counters`): one name,
//! one meaning (issue 67). `lift_offs` is every departure of the tip from the
//! belt ([`analyses::lift_offs::of`]), as in `sweep.csv` and every other output;
//! the plant's own `lift_offs` (the departures of a tip in contact, without the
//! bounces) is published as `lift_offs_from_contact`, right after it. The other
//! counters are the plant's ([`plant::Counters`]), under its names and in its
//! order (docs/plant.md "Counting lift-offs").

use std::fmt;

use plant::Counters;
use serde::{
    Deserialize, Deserializer, Serialize, Serializer,
    de::{MapAccess, Visitor},
    ser::{Error as _, SerializeMap},
};

/// The name the plant's own `lift_offs` (departures without the bounces) is
/// published under.
pub const FROM_CONTACT: &str = "lift_offs_from_contact";

/// [`plant::Counters`] as published: serialises as the plant's counters with
/// `lift_offs` every departure and the plant's own count as
/// [`FROM_CONTACT`] (module docs).
#[derive(Debug, Clone, Copy)]
pub struct Published<'a>(pub &'a Counters);

impl Serialize for Published<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let fields = plant_fields(self.0).map_err(S::Error::custom)?;
        let mut map = serializer.serialize_map(Some(fields.len() + 1))?;
        for (name, value) in &fields {
            if name == "lift_offs" {
                map.serialize_entry("lift_offs", &analyses::lift_offs::of(self.0))?;
                map.serialize_entry(FROM_CONTACT, value)?;
            } else {
                map.serialize_entry(name, value)?;
            }
        }
        map.end()
    }
}

/// `#[serde(serialize_with = "experiments::counters::published")]` for a field of
/// type [`plant::Counters`]: writes it as [`Published`].
///
/// # Errors
/// The serializer's.
pub fn published<S: Serializer>(c: &Counters, serializer: S) -> Result<S::Ok, S::Error> {
    Published(c).serialize(serializer)
}

/// The plant's counters as `(name, value)` in its declared order (its own
/// `Serialize`: a counter added to the plant is published without a change here).
fn plant_fields(c: &Counters) -> Result<Vec<(String, serde_json::Value)>, serde_json::Error> {
    /// A JSON object's entries in the order written.
    struct Ordered(Vec<(String, serde_json::Value)>);
    impl<'de> Deserialize<'de> for Ordered {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct Entries;
            impl<'de> Visitor<'de> for Entries {
                type Value = Ordered;
                fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                    f.write_str("the plant's counters as an object")
                }
                fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Ordered, A::Error> {
                    let mut v = Vec::new();
                    while let Some(entry) = m.next_entry()? {
                        v.push(entry);
                    }
                    Ok(Ordered(v))
                }
            }
            d.deserialize_map(Entries)
        }
    }
    Ok(serde_json::from_str::<Ordered>(&serde_json::to_string(c)?)?.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every counter of the plant's is published once, in its order, with
    /// `lift_offs` the sum of the plant's `lift_offs` and `bounces` and the
    /// plant's own `lift_offs` right after it; floats keep their bits.
    #[test]
    fn the_plant_counters_are_published_with_lift_offs_every_departure() {
        let c = Counters { lift_offs: 1, bounces: 1899, touchdowns: 1899, bridged_s: 0.1 + 0.2, ..Counters::default() };
        let published = serde_json::to_string(&Published(&c)).unwrap();
        let plant = serde_json::to_string(&c).unwrap();
        let expected = plant.replacen("\"lift_offs\":1,", "\"lift_offs\":1900,\"lift_offs_from_contact\":1,", 1);
        assert_ne!(expected, plant);
        assert_eq!(published, expected);
        let v: serde_json::Value = serde_json::from_str(&published).unwrap();
        assert_eq!(v["bridged_s"].as_f64().unwrap().to_bits(), (0.1f64 + 0.2).to_bits());
    }
}
