//! Fields and stiffnesses from and to serde data (TOML, JSON, Python dicts).

use super::value::{Field, Stiffness};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeMap, Serializer};
use std::collections::BTreeMap;
use std::fmt;

const EXPECTING: &str = "a number, a string with a number or an expression of x and y, \
     a table of region values, or an array of one value per mesh vertex";

struct FieldVisitor;

impl<'de> Visitor<'de> for FieldVisitor {
    type Value = Field;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(EXPECTING)
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Field, E> {
        Ok(Field::Constant(v as f64))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Field, E> {
        Ok(Field::Constant(v as f64))
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Field, E> {
        Ok(Field::Constant(v))
    }

    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Field, E> {
        Field::parse(v).map_err(E::custom)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Field, A::Error> {
        let mut values = Vec::with_capacity(seq.size_hint().unwrap_or(0));
        while let Some(v) = seq.next_element::<f64>()? {
            values.push(v);
        }
        if values.is_empty() {
            return Err(de::Error::custom(
                "an empty array: give one value per mesh vertex",
            ));
        }
        Ok(Field::Nodal(values.into()))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Field, A::Error> {
        let mut table = BTreeMap::new();
        while let Some((key, RegionValue(value))) = map.next_entry::<String, RegionValue>()? {
            if table.contains_key(&key) {
                return Err(de::Error::custom(format!("region '{key}' is given twice")));
            }
            table.insert(key, value);
        }
        if table.is_empty() {
            return Err(de::Error::custom(
                "an empty table: give at least one region or a \"default\"",
            ));
        }
        Ok(Field::Regions(table))
    }
}

impl<'de> serde::Deserialize<'de> for Field {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Field, D::Error> {
        d.deserialize_any(FieldVisitor)
    }
}

/// The value of one region in a table: a number or a string, not another table.
struct RegionValue(Field);

impl<'de> serde::Deserialize<'de> for RegionValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RegionValue, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RegionValue;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a region's value: a number or a string with a number or an expression")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<RegionValue, E> {
                Ok(RegionValue(Field::Constant(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<RegionValue, E> {
                Ok(RegionValue(Field::Constant(v as f64)))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<RegionValue, E> {
                Ok(RegionValue(Field::Constant(v)))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<RegionValue, E> {
                if v.trim().eq_ignore_ascii_case("rigid") {
                    return Err(E::custom(
                        "\"rigid\" is a stiffness: only the regions of a stiffness table \
                         can be rigid",
                    ));
                }
                Field::parse(v).map(RegionValue).map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}

struct StiffnessVisitor;

impl<'de> Visitor<'de> for StiffnessVisitor {
    type Value = Stiffness;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "\"rigid\", {EXPECTING}")
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Stiffness, E> {
        FieldVisitor.visit_i64(v).map(Stiffness::Elastic)
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Stiffness, E> {
        FieldVisitor.visit_u64(v).map(Stiffness::Elastic)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Stiffness, E> {
        FieldVisitor.visit_f64(v).map(Stiffness::Elastic)
    }

    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Stiffness, E> {
        Stiffness::parse(v).map_err(E::custom)
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Stiffness, A::Error> {
        let mut table = BTreeMap::new();
        while let Some((key, RegionStiffness(value))) =
            map.next_entry::<String, RegionStiffness>()?
        {
            if table.contains_key(&key) {
                return Err(de::Error::custom(format!("region '{key}' is given twice")));
            }
            table.insert(key, value);
        }
        if table.is_empty() {
            return Err(de::Error::custom(
                "an empty table: give at least one region or a \"default\"",
            ));
        }
        if table.values().any(Stiffness::is_rigid) {
            return Ok(Stiffness::Mixed(table));
        }
        Ok(Stiffness::Elastic(Field::Regions(
            table
                .into_iter()
                .map(|(k, v)| match v {
                    Stiffness::Elastic(f) => (k, f),
                    _ => unreachable!("no rigid entry"),
                })
                .collect(),
        )))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<Stiffness, A::Error> {
        FieldVisitor.visit_seq(seq).map(Stiffness::Elastic)
    }
}

/// The value of one region in a stiffness table: `"rigid"`, a number or a string.
struct RegionStiffness(Stiffness);

impl<'de> serde::Deserialize<'de> for RegionStiffness {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RegionStiffness, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RegionStiffness;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a region's stiffness: \"rigid\", a number or a string with a number or \
                     an expression",
                )
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<RegionStiffness, E> {
                Ok(RegionStiffness(Stiffness::Elastic(Field::Constant(
                    v as f64,
                ))))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<RegionStiffness, E> {
                Ok(RegionStiffness(Stiffness::Elastic(Field::Constant(
                    v as f64,
                ))))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<RegionStiffness, E> {
                Ok(RegionStiffness(Stiffness::Elastic(Field::Constant(v))))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<RegionStiffness, E> {
                Stiffness::parse(v).map(RegionStiffness).map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> serde::Deserialize<'de> for Stiffness {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Stiffness, D::Error> {
        d.deserialize_any(StiffnessVisitor)
    }
}

/// Serialises to what [`Field`]'s `Deserialize` reads back: a number, the expression
/// text, or a table.
impl serde::Serialize for Field {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Field::Constant(v) => s.serialize_f64(*v),
            Field::Expr(e) => s.serialize_str(e.source()),
            Field::Regions(table) => {
                let mut map = s.serialize_map(Some(table.len()))?;
                for (k, v) in table {
                    map.serialize_entry(k, v)?;
                }
                map.end()
            }
            Field::Nodal(values) => values.serialize(s),
        }
    }
}

/// Serialises to what [`Stiffness`]'s `Deserialize` reads back (`"rigid"` or a field).
impl serde::Serialize for Stiffness {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Stiffness::Elastic(f) => f.serialize(s),
            Stiffness::Rigid => s.serialize_str("rigid"),
            Stiffness::Mixed(table) => {
                let mut map = s.serialize_map(Some(table.len()))?;
                for (k, v) in table {
                    map.serialize_entry(k, v)?;
                }
                map.end()
            }
        }
    }
}
