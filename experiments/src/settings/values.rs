//! The settings' values that are more than a number, a flag or a path, as typed
//! values both fronts build: [`NumberList`] (`MIN,MAX`, four angles), and, with
//! the `clap` feature, the serde forms of a choice (the names clap shows) and of a
//! value with a text form (`KEY=VALUE`), so that the settings are built from a
//! document of keyword arguments (`painleve`, docs/python.md) with the same
//! values the command line parses.

use std::{fmt, str::FromStr};

/// Numbers given as one list: `--mu 0.1,1` on the command line, `mu=(0.1, 1.0)`
/// or `mu=0.5` in Python. How many it must hold, and in what order, is the
/// setting's own rule, checked by its experiment (e.g. [`crate::arm::parse_range`]),
/// which names the setting.
#[derive(Debug, Clone, PartialEq)]
pub struct NumberList(pub Vec<f64>);

impl FromStr for NumberList {
    type Err = String;

    /// Numbers separated by commas (spaces around each allowed), e.g. `-90,90`.
    ///
    /// # Errors
    /// A message quoting the text when a part is not a number.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        s.split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<Vec<_>, _>>()
            .map(NumberList)
            .map_err(|_| format!("expected numbers separated by commas, got `{s}`"))
    }
}

impl fmt::Display for NumberList {
    /// The numbers joined by commas, each in Rust's shortest round-trip form
    /// (`-90,90`, `18.27`): the text the messages quote.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, x) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            write!(f, "{x}")?;
        }
        Ok(())
    }
}

impl serde::Serialize for NumberList {
    /// A sequence of numbers.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for NumberList {
    /// A sequence of numbers, one number, or the command line's text (`"0.1,1"`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Given {
            One(f64),
            Many(Vec<f64>),
            Text(String),
        }
        match Given::deserialize(d).map_err(|_| serde::de::Error::custom("expected a number, a list of numbers or their text"))? {
            Given::One(x) => Ok(NumberList(vec![x])),
            Given::Many(v) => Ok(NumberList(v)),
            Given::Text(t) => t.parse().map_err(serde::de::Error::custom),
        }
    }
}

/// serde through a text form (`Display`/`FromStr`): `--set`'s `KEY=VALUE`
/// ([`rig::overrides::Override`]), one value or a list of them.
#[cfg(feature = "clap")]
pub mod text {
    use std::{fmt::Display, str::FromStr};

    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    /// Serializes a list as its items' texts.
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer, T: Display>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(ToString::to_string))
    }

    /// Deserializes a list of texts, each parsed by `FromStr`.
    ///
    /// # Errors
    /// The item's own parse error, as a message.
    pub fn deserialize<'de, D: Deserializer<'de>, T: FromStr>(d: D) -> Result<Vec<T>, D::Error>
    where
        T::Err: Display,
    {
        Vec::<String>::deserialize(d)?.iter().map(|t| t.parse().map_err(D::Error::custom)).collect()
    }
}

/// serde of a choice (`clap::ValueEnum`) by the name the command line shows
/// (`newton`, `x0a` as `a`): one, an optional one, or a list.
#[cfg(feature = "clap")]
pub mod choice {
    use clap::ValueEnum;
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    /// The name clap shows for `v`.
    pub(crate) fn name<T: ValueEnum>(v: &T) -> String {
        v.to_possible_value().map(|p| p.get_name().to_string()).unwrap_or_default()
    }

    /// The choice named `text`, or a message listing the names.
    pub(crate) fn parse<T: ValueEnum>(text: &str) -> Result<T, String> {
        T::from_str(text, false).map_err(|_| {
            let names: Vec<String> = T::value_variants()
                .iter()
                .filter_map(|v| v.to_possible_value())
                .filter(|p| !p.is_hide_set())
                .map(|p| p.get_name().to_string())
                .collect();
            format!("invalid value '{text}' [possible values: {}]", names.join(", "))
        })
    }

    /// Serializes the choice's name.
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer, T: ValueEnum>(v: &T, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&name(v))
    }

    /// Deserializes a choice from its name.
    ///
    /// # Errors
    /// A message listing the names, for any other text.
    pub fn deserialize<'de, D: Deserializer<'de>, T: ValueEnum>(d: D) -> Result<T, D::Error> {
        parse(&String::deserialize(d)?).map_err(D::Error::custom)
    }

    /// An optional choice (`None`: not given).
    pub mod option {
        use clap::ValueEnum;
        use serde::{Deserialize, Deserializer, Serializer, de::Error};

        use crate::settings::values::choice::{name, parse};

        /// Serializes the choice's name, or none.
        ///
        /// # Errors
        /// The serializer's.
        pub fn serialize<S: Serializer, T: ValueEnum>(v: &Option<T>, s: S) -> Result<S::Ok, S::Error> {
            match v {
                Some(v) => s.serialize_some(&name(v)),
                None => s.serialize_none(),
            }
        }

        /// Deserializes a name, or none.
        ///
        /// # Errors
        /// A message listing the names, for any other text.
        pub fn deserialize<'de, D: Deserializer<'de>, T: ValueEnum>(d: D) -> Result<Option<T>, D::Error> {
            Option::<String>::deserialize(d)?.map(|t| parse(&t).map_err(D::Error::custom)).transpose()
        }
    }

    /// A list of choices (a sweep's dimension).
    pub mod list {
        use clap::ValueEnum;
        use serde::{Deserialize, Deserializer, Serializer, de::Error};

        use crate::settings::values::choice::{name, parse};

        /// Serializes the choices' names.
        ///
        /// # Errors
        /// The serializer's.
        pub fn serialize<S: Serializer, T: ValueEnum>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
            s.collect_seq(v.iter().map(name))
        }

        /// Deserializes a list of names.
        ///
        /// # Errors
        /// A message listing the names, for any other text.
        pub fn deserialize<'de, D: Deserializer<'de>, T: ValueEnum>(d: D) -> Result<Vec<T>, D::Error> {
            Vec::<String>::deserialize(d)?.iter().map(|t| parse(t).map_err(D::Error::custom)).collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::NumberList;

    #[test]
    fn a_number_list_reads_the_command_line_text_and_writes_it_back() {
        let l: NumberList = " -90, 90".parse().unwrap();
        assert_eq!(l.0, vec![-90.0, 90.0]);
        assert_eq!(l.to_string(), "-90,90");
        let l: NumberList = "32,0,18.27,0".parse().unwrap();
        assert_eq!(l.to_string(), "32,0,18.27,0");
        assert!("1,,2".parse::<NumberList>().unwrap_err().contains("`1,,2`"));
        assert!("a".parse::<NumberList>().is_err());
    }

    #[test]
    fn a_number_list_deserializes_from_one_number_a_list_or_its_text_exactly() {
        let x: f64 = 0.1 + 0.2; // 0.30000000000000004: exactly, not 0.3
        let one: NumberList = serde_json::from_value(serde_json::json!(x)).unwrap();
        assert_eq!(one.0[0].to_bits(), x.to_bits());
        let many: NumberList = serde_json::from_value(serde_json::json!([-1, 0.5])).unwrap();
        assert_eq!(many.0, vec![-1.0, 0.5]);
        let text: NumberList = serde_json::from_value(serde_json::json!("-1,0.5")).unwrap();
        assert_eq!(text, many);
        assert!(serde_json::from_value::<NumberList>(serde_json::json!(["a"])).is_err());
        assert!(serde_json::from_value::<NumberList>(serde_json::json!("1,b")).is_err());
    }
}
