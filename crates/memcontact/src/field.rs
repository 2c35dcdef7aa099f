//! Scalar problem data of SPEC §1: the load `f`, the obstacle surface `φ` and the
//! foundation stiffness `h` (with the rigid limit `h → ∞`).
//!
//! A [`Field`] is what a case file says: a number, an [`Expr`] of `x, y`, or a table of
//! values per named mesh region. [`Field::bind`] resolves it against a mesh's regions once
//! and gives a [`BoundField`] that assembly evaluates at quadrature points (and asks
//! whether it is constant on a region, to skip quadrature). [`check_values`] validates
//! sampled values (`h ≥ 0`, no NaN, ...) and says where a bad value sits.

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::mesh::Mesh;
use crate::nodal::NodalP1;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeMap, Serializer};
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

/// The key of a region table that applies to the regions not listed.
pub const DEFAULT_KEY: &str = crate::mesh::regions::DEFAULT;

/// A scalar field on the domain: the data f, φ or h.
///
/// Deserialises (serde) from a number, a string holding a number or an expression, or a
/// table mapping region names (or numeric region tags as text, or `"default"`) to numbers
/// or strings. In TOML:
///
/// ```toml
/// f = -1.5
/// phi = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
/// h = { soil = 100, foam = "50*(1 + x)", default = 0 }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Field {
    /// The same value everywhere.
    Constant(f64),
    /// A function of the position (never constant: [`Field::parse`] folds those).
    Expr(Expr),
    /// A value per region: keys are region names, region tags as text, or
    /// [`DEFAULT_KEY`]; values are [`Field::Constant`] or [`Field::Expr`].
    Regions(BTreeMap<String, Field>),
    /// One value per mesh vertex, in the mesh's vertex order: the P1 interpolant of those
    /// values (φ sampled at a vertex is the value given there). Binds only with the mesh
    /// ([`Field::bind_to_mesh`]).
    Nodal(Arc<[f64]>),
}

impl Field {
    /// A constant field.
    pub fn from_number(value: f64) -> Field {
        Field::Constant(value)
    }

    /// Parses a number or an expression of `x, y` (see [`crate::expr`]); an expression that
    /// does not depend on the position becomes a [`Field::Constant`] (`"2*pi"`, `"-3"`).
    pub fn parse(text: &str) -> Result<Field> {
        let e = Expr::parse(text)?;
        Ok(match e.constant_value() {
            Some(v) => Field::Constant(v),
            None => Field::Expr(e),
        })
    }

    /// The value when the field is the same constant everywhere (for a region table: when
    /// every entry is that constant).
    pub fn constant(&self) -> Option<f64> {
        match self {
            Field::Constant(v) => Some(*v),
            Field::Expr(e) => e.constant_value(),
            Field::Regions(table) => {
                let mut values = table.values().map(Field::constant);
                let first = values.next()??;
                values
                    .all(|v| v.is_some_and(|v| v.to_bits() == first.to_bits()))
                    .then_some(first)
            }
            Field::Nodal(_) => None,
        }
    }

    /// Resolves the field against `mesh`: its regions ([`Field::bind`]), or, for nodal
    /// values, its vertices (one value per vertex, all finite).
    pub fn bind_to_mesh(&self, name: &str, mesh: &Mesh) -> Result<BoundField> {
        match self {
            Field::Nodal(values) => Ok(BoundField {
                name: name.to_string(),
                regions: Vec::new(),
                fallback: Some(Value::Nodal(Arc::new(NodalP1::new(
                    name,
                    mesh,
                    values.clone(),
                )?))),
            }),
            _ => self.bind(name, &mesh.region_names, &mesh.region_tags()),
        }
    }

    /// Resolves the field against a mesh.
    ///
    /// `name` names the field in messages (`"stiffness h"`); `region_names` maps region tags
    /// to names; `tags` are the region tags present in the mesh (repetitions are fine). A
    /// region table key is a region name, else a tag written as a number, else
    /// [`DEFAULT_KEY`]; every present region needs a value (its own or the default).
    ///
    /// Errors ([`Error::Data`]): a key naming no region of the mesh, a region given twice
    /// (by name and by tag), a region without a value and no default, a table inside a
    /// table, nodal values (they need the mesh: [`Field::bind_to_mesh`]).
    pub fn bind(
        &self,
        name: &str,
        region_names: &BTreeMap<u32, String>,
        tags: &[u32],
    ) -> Result<BoundField> {
        let mut present: Vec<u32> = tags.to_vec();
        present.sort_unstable();
        present.dedup();
        let label = |tag: u32| {
            region_names
                .get(&tag)
                .cloned()
                .unwrap_or_else(|| tag.to_string())
        };
        let listing = || {
            let names: Vec<String> = present.iter().map(|&t| label(t)).collect();
            if names.is_empty() {
                "the mesh has no regions".to_string()
            } else {
                format!("regions: {}", names.join(", "))
            }
        };
        let table = match self {
            Field::Regions(table) => table,
            Field::Nodal(_) => {
                return Err(Error::Data(format!(
                    "{name}: nodal values belong to one mesh and cannot be carried to \
                     another; give a number, an expression or a region table"
                )))
            }
            uniform => {
                return Ok(BoundField {
                    name: name.to_string(),
                    regions: Vec::new(),
                    fallback: Some(Value::of(name, DEFAULT_KEY, uniform)?),
                })
            }
        };
        let mut fallback = None;
        let mut given: BTreeMap<u32, (&str, Value)> = BTreeMap::new();
        for (key, field) in table {
            let value = Value::of(name, key, field)?;
            if key == DEFAULT_KEY {
                fallback = Some(value);
                continue;
            }
            // A name may label several tags: the value applies to each of them.
            let by_name: Vec<u32> = region_names
                .iter()
                .filter(|(_, n)| n.as_str() == key)
                .map(|(&t, _)| t)
                .collect();
            let is_present = |t: &u32| present.binary_search(t).is_ok();
            if let Ok(tag) = key.trim().parse::<u32>() {
                if !by_name.is_empty() && !by_name.contains(&tag) && present.contains(&tag) {
                    return Err(Error::Data(format!(
                        "{name}: the key '{key}' is ambiguous: it is the name of region tag \
                         {} and also the tag of region {}; rename the physical surface \
                         named '{key}' in the mesh (region table keys are names, or tags \
                         written as numbers)",
                        by_name[0],
                        label(tag)
                    )));
                }
            }
            let targets: Vec<u32> = if !by_name.is_empty() {
                let found: Vec<u32> = by_name.iter().copied().filter(is_present).collect();
                if found.is_empty() {
                    let tags: Vec<String> = by_name.iter().map(u32::to_string).collect();
                    return Err(Error::Data(format!(
                        "{name}: region '{key}' (tag {}) has no triangles in the mesh ({})",
                        tags.join(", "),
                        listing()
                    )));
                }
                found
            } else {
                match key.trim().parse::<u32>() {
                    Ok(tag) if is_present(&tag) => vec![tag],
                    _ => {
                        return Err(Error::Data(format!(
                            "{name}: no region named '{key}' in the mesh ({})",
                            listing()
                        )))
                    }
                }
            };
            for tag in targets {
                if let Some((other, _)) = given.insert(tag, (key.as_str(), value.clone())) {
                    return Err(Error::Data(format!(
                        "{name}: region {} is given twice (as '{other}' and as '{key}')",
                        label(tag)
                    )));
                }
            }
        }
        let mut regions = Vec::with_capacity(present.len());
        for &tag in &present {
            let value = match (given.remove(&tag), &fallback) {
                (Some((_, v)), _) => v,
                (None, Some(v)) => v.clone(),
                (None, None) => {
                    return Err(Error::Data(format!(
                        "{name}: no value for region {} and no \"{DEFAULT_KEY}\" entry ({})",
                        label(tag),
                        listing()
                    )))
                }
            };
            regions.push((tag, value));
        }
        Ok(BoundField {
            name: name.to_string(),
            regions,
            fallback,
        })
    }
}

impl From<f64> for Field {
    fn from(value: f64) -> Field {
        Field::Constant(value)
    }
}

impl From<Expr> for Field {
    fn from(e: Expr) -> Field {
        match e.constant_value() {
            Some(v) => Field::Constant(v),
            None => Field::Expr(e),
        }
    }
}

impl std::str::FromStr for Field {
    type Err = Error;
    fn from_str(s: &str) -> Result<Field> {
        Field::parse(s)
    }
}

/// A region's value after binding.
#[derive(Clone, Debug)]
enum Value {
    Constant(f64),
    Expr(Expr),
    Nodal(Arc<NodalP1>),
}

impl Value {
    fn of(name: &str, key: &str, field: &Field) -> Result<Value> {
        Ok(match field {
            Field::Constant(v) => Value::Constant(*v),
            Field::Expr(e) => match e.constant_value() {
                Some(v) => Value::Constant(v),
                None => Value::Expr(e.clone()),
            },
            Field::Regions(_) => {
                return Err(Error::Data(format!(
                    "{name}: the value of region '{key}' is a table; \
                     it must be a number or an expression"
                )))
            }
            Field::Nodal(_) => {
                return Err(Error::Data(format!(
                    "{name}: the value of region '{key}' is an array; \
                     it must be a number or an expression"
                )))
            }
        })
    }

    #[inline]
    fn eval(&self, p: [f64; 2]) -> f64 {
        match self {
            Value::Constant(v) => *v,
            Value::Expr(e) => e.eval(p[0], p[1]),
            Value::Nodal(n) => n.eval(p),
        }
    }

    fn constant(&self) -> Option<f64> {
        match self {
            Value::Constant(v) => Some(*v),
            Value::Expr(_) | Value::Nodal(_) => None,
        }
    }
}

/// A [`Field`] resolved against a mesh's regions: evaluate it at a point of a triangle of
/// a given region tag.
#[derive(Clone, Debug)]
pub struct BoundField {
    name: String,
    /// The values of the regions present in the mesh, sorted by tag (empty for a field
    /// that is the same function everywhere: then `fallback` holds it).
    regions: Vec<(u32, Value)>,
    /// The value for tags not in `regions`: the whole field, or a table's default.
    fallback: Option<Value>,
}

impl BoundField {
    /// The name given to [`Field::bind`].
    pub fn name(&self) -> &str {
        &self.name
    }

    #[inline]
    fn value(&self, region: u32) -> Option<&Value> {
        if self.regions.is_empty() {
            return self.fallback.as_ref();
        }
        match self.regions.binary_search_by_key(&region, |(t, _)| *t) {
            Ok(i) => Some(&self.regions[i].1),
            Err(_) => self.fallback.as_ref(),
        }
    }

    /// The value at the point `p` of a triangle of region `region`. A region that was not
    /// among the bound tags gets the table's default, or NaN when there is none (which the
    /// data checks report).
    #[inline]
    pub fn eval(&self, p: [f64; 2], region: u32) -> f64 {
        self.value(region).map_or(f64::NAN, |v| v.eval(p))
    }

    /// The value when the field is the same constant on every bound region.
    pub fn constant(&self) -> Option<f64> {
        if self.regions.is_empty() {
            return self.fallback.as_ref()?.constant();
        }
        let first = self.regions[0].1.constant()?;
        self.regions
            .iter()
            .all(|(_, v)| v.constant().is_some_and(|c| c.to_bits() == first.to_bits()))
            .then_some(first)
    }

    /// The value when the field is constant on region `region` (assembly can then skip
    /// quadrature there).
    pub fn region_constant(&self, region: u32) -> Option<f64> {
        self.value(region)?.constant()
    }
}

/// The foundation stiffness h: an elastic (Winkler) obstacle with `h ≥ 0`, the rigid
/// obstacle `h = ∞` of the classical obstacle problem `u ≤ φ` (SPEC §1, limits), or a body
/// rigid in some regions and elastic in others.
///
/// Deserialises like a [`Field`], from the string `"rigid"` (any case), and from a region
/// table whose values may be `"rigid"`: `{ plinth = "rigid", default = 200 }`.
#[derive(Clone, Debug, PartialEq)]
pub enum Stiffness {
    /// A finite stiffness field `h ≥ 0`.
    Elastic(Field),
    /// The rigid obstacle.
    Rigid,
    /// A region table in which some regions (or the default) are rigid: every value is
    /// [`Stiffness::Rigid`] or [`Stiffness::Elastic`] of a number or an expression.
    Mixed(BTreeMap<String, Stiffness>),
}

/// A [`Stiffness`] resolved against a mesh: the elastic part (zero on the rigid regions)
/// and the tags of the rigid regions.
#[derive(Clone, Debug)]
pub struct BoundStiffness {
    /// h on the elastic regions, 0 on the rigid ones (`None`: every region is rigid).
    pub elastic: Option<BoundField>,
    /// The region tags that are rigid (all of them when `elastic` is `None`).
    pub rigid_tags: Vec<u32>,
}

impl BoundStiffness {
    /// `true` when every region is rigid.
    pub fn is_rigid(&self) -> bool {
        self.elastic.is_none()
    }
}

impl Stiffness {
    /// Parses `"rigid"` (any case, surrounding spaces ignored) or a [`Field`] text.
    pub fn parse(text: &str) -> Result<Stiffness> {
        if text.trim().eq_ignore_ascii_case("rigid") {
            Ok(Stiffness::Rigid)
        } else {
            Field::parse(text).map(Stiffness::Elastic)
        }
    }

    /// Whether this is the rigid obstacle.
    pub fn is_rigid(&self) -> bool {
        matches!(self, Stiffness::Rigid)
    }

    /// The stiffness field of an elastic obstacle (`None` for a rigid or mixed body).
    pub fn field(&self) -> Option<&Field> {
        match self {
            Stiffness::Elastic(f) => Some(f),
            Stiffness::Rigid | Stiffness::Mixed(_) => None,
        }
    }

    /// The elastic part of a mixed table: the rigid entries replaced by 0 (the elastic
    /// term is integrated over the elastic triangles only).
    fn elastic_table(table: &BTreeMap<String, Stiffness>) -> Field {
        Field::Regions(
            table
                .iter()
                .map(|(k, v)| {
                    let f = match v {
                        Stiffness::Elastic(f) => f.clone(),
                        _ => Field::Constant(0.0),
                    };
                    (k.clone(), f)
                })
                .collect(),
        )
    }

    /// The elastic fields of the stiffness (a mixed table's elastic entries), for checks.
    pub fn elastic_fields(&self) -> Vec<(String, &Field)> {
        match self {
            Stiffness::Elastic(f) => vec![(String::new(), f)],
            Stiffness::Rigid => Vec::new(),
            Stiffness::Mixed(t) => t
                .iter()
                .filter_map(|(k, v)| match v {
                    Stiffness::Elastic(f) => Some((format!(".{k}"), f)),
                    _ => None,
                })
                .collect(),
        }
    }

    /// Resolves the stiffness against `mesh` ([`Field::bind_to_mesh`] for the elastic
    /// part; the rigid entries of a mixed table name regions like any other key).
    pub fn bind_to_mesh(&self, name: &str, mesh: &Mesh) -> Result<BoundStiffness> {
        match self {
            Stiffness::Rigid => Ok(BoundStiffness {
                elastic: None,
                rigid_tags: mesh.region_tags(),
            }),
            Stiffness::Elastic(h) => Ok(BoundStiffness {
                elastic: Some(h.bind_to_mesh(name, mesh)?),
                rigid_tags: Vec::new(),
            }),
            Stiffness::Mixed(table) => {
                let tags = mesh.region_tags();
                // Which regions are rigid: a marker table bound like the stiffness itself,
                // so that names, tags and the default resolve with the same rules.
                let marker = Field::Regions(
                    table
                        .iter()
                        .map(|(k, v)| (k.clone(), Field::Constant(f64::from(v.is_rigid()))))
                        .collect(),
                );
                let marker = marker.bind(name, &mesh.region_names, &tags)?;
                let rigid_tags: Vec<u32> = tags
                    .iter()
                    .copied()
                    .filter(|&t| marker.region_constant(t) == Some(1.0))
                    .collect();
                let elastic = if rigid_tags.len() == tags.len() {
                    None
                } else {
                    Some(Stiffness::elastic_table(table).bind(name, &mesh.region_names, &tags)?)
                };
                Ok(BoundStiffness {
                    elastic,
                    rigid_tags,
                })
            }
        }
    }
}

impl From<Field> for Stiffness {
    fn from(f: Field) -> Stiffness {
        Stiffness::Elastic(f)
    }
}

impl std::str::FromStr for Stiffness {
    type Err = Error;
    fn from_str(s: &str) -> Result<Stiffness> {
        Stiffness::parse(s)
    }
}

// ---------------------------------------------------------------------------------------
// Validation.

/// What values a quantity may take. NaN and ±∞ are never allowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// Any finite number (a load f, an obstacle height φ).
    Finite,
    /// A finite number ≥ 0 (a stiffness h).
    FiniteNonNegative,
    /// A finite number > 0 (a tension t).
    FinitePositive,
}

impl Rule {
    /// What is wrong with `value` under this rule (`"is negative"`), or `None` if it is
    /// allowed.
    pub fn violation(self, value: f64) -> Option<&'static str> {
        if value.is_nan() {
            Some("is not a number")
        } else if value.is_infinite() {
            Some("is infinite")
        } else if self == Rule::FiniteNonNegative && value < 0.0 {
            Some("is negative")
        } else if self == Rule::FinitePositive && value <= 0.0 {
            Some("is not positive")
        } else {
            None
        }
    }
}

/// Checks values sampled at points (quadrature points, vertices) against `rule`.
///
/// The error ([`Error::Data`]) names the quantity, the first bad value and its point, and
/// how many more bad values there are:
/// `invalid data: stiffness h is negative (-3) at (0.25, 0.5) (and at 4 more points)`.
pub fn check_values(
    name: &str,
    values: impl IntoIterator<Item = ([f64; 2], f64)>,
    rule: Rule,
) -> Result<()> {
    let mut values = values.into_iter();
    let Some((p, v, what)) = values
        .by_ref()
        .find_map(|(p, v)| rule.violation(v).map(|w| (p, v, w)))
    else {
        return Ok(());
    };
    let more = values.filter(|(_, v)| rule.violation(*v).is_some()).count();
    let more = match more {
        0 => String::new(),
        1 => " (and at 1 more point)".to_string(),
        n => format!(" (and at {n} more points)"),
    };
    Err(Error::Data(format!(
        "{name} {what} ({}) at ({}, {}){more}",
        number(v),
        number(p[0]),
        number(p[1])
    )))
}

/// Checks a single value (a tension t): `invalid data: tension t is not positive (0)`.
pub fn check_value(name: &str, value: f64, rule: Rule) -> Result<()> {
    match rule.violation(value) {
        None => Ok(()),
        Some(what) => Err(Error::Data(format!("{name} {what} ({})", number(value)))),
    }
}

/// A number for messages: at most 6 significant digits.
fn number(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return format!("{v}");
    }
    let exponent = v.abs().log10().floor() as i32;
    if (-4..6).contains(&exponent) {
        let decimals = (5 - exponent).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.')
        } else {
            &s
        };
        s.to_string()
    } else {
        let s = format!("{v:.5e}");
        match s.split_once('e') {
            Some((mantissa, exp)) if mantissa.contains('.') => format!(
                "{}e{exp}",
                mantissa.trim_end_matches('0').trim_end_matches('.')
            ),
            _ => s,
        }
    }
}

// ---------------------------------------------------------------------------------------
// serde.

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

impl crate::fem::Coefficient for BoundField {
    fn at(&self, p: [f64; 2], region: u32) -> f64 {
        self.eval(p, region)
    }
    fn on_region(&self, region: u32) -> Option<f64> {
        self.region_constant(region)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn names() -> BTreeMap<u32, String> {
        BTreeMap::from([(1, "soil".to_string()), (2, "foam".to_string())])
    }

    fn data_error(r: Result<impl fmt::Debug>) -> String {
        match r {
            Err(Error::Data(m)) => m,
            other => panic!("expected a data error, got {other:?}"),
        }
    }

    fn json(text: &str) -> Field {
        serde_json::from_str(text).unwrap_or_else(|e| panic!("{text}: {e}"))
    }

    #[test]
    fn parse_numbers_and_expressions() {
        assert_eq!(Field::parse("3").unwrap(), Field::Constant(3.0));
        assert_eq!(Field::parse(" -2.5e-1 ").unwrap(), Field::Constant(-0.25));
        assert_eq!(Field::parse("2*pi").unwrap(), Field::Constant(2.0 * PI));
        assert_eq!(Field::from_number(4.5), Field::Constant(4.5));
        assert_eq!(Field::from(4.5), Field::Constant(4.5));
        match Field::parse("1 + x*y").unwrap() {
            Field::Expr(e) => assert_eq!(e.eval(2.0, 3.0), 7.0),
            other => panic!("{other:?}"),
        }
        assert!(matches!(Field::parse("1 + z"), Err(Error::Expr { .. })));
        assert!(matches!(Field::parse(""), Err(Error::Expr { .. })));
        assert!(matches!(Field::parse("inf"), Err(Error::Expr { .. })));
        assert_eq!(Field::parse("x").unwrap().constant(), None);
        assert_eq!(json(r#"{"a": 1, "b": "2/2"}"#).constant(), Some(1.0));
        assert_eq!(json(r#"{"a": 1, "b": 2}"#).constant(), None);
    }

    #[test]
    fn uniform_fields_bind_to_any_mesh() {
        let c = Field::Constant(2.5)
            .bind("load f", &names(), &[1, 2])
            .unwrap();
        assert_eq!(c.name(), "load f");
        assert_eq!(c.eval([0.3, 0.4], 1), 2.5);
        assert_eq!(c.eval([0.3, 0.4], 99), 2.5);
        assert_eq!(c.constant(), Some(2.5));
        assert_eq!(c.region_constant(2), Some(2.5));

        let e = Field::parse("x^2 - y")
            .unwrap()
            .bind("obstacle φ", &BTreeMap::new(), &[0])
            .unwrap();
        assert_eq!(e.eval([3.0, 1.0], 0), 8.0);
        assert_eq!(e.eval([3.0, 1.0], 7), 8.0);
        assert_eq!(e.constant(), None);
        assert_eq!(e.region_constant(0), None);
    }

    #[test]
    fn region_tables_by_name_tag_and_default() {
        let table = json(r#"{"soil": 100, "2": "50*x", "default": 7}"#);
        let h = table
            .bind("stiffness h", &names(), &[1, 2, 3, 2, 1])
            .unwrap();
        assert_eq!(h.eval([0.5, 0.0], 1), 100.0);
        assert_eq!(h.eval([0.5, 0.0], 2), 25.0);
        assert_eq!(h.eval([0.5, 0.0], 3), 7.0); // unnamed region 3: the default
        assert_eq!(h.eval([0.5, 0.0], 42), 7.0); // a region not bound: the default
        assert_eq!(h.constant(), None);
        assert_eq!(h.region_constant(1), Some(100.0));
        assert_eq!(h.region_constant(2), None);
        assert_eq!(h.region_constant(3), Some(7.0));

        // Without a default an unbound region is NaN, which the checks report.
        let h = json(r#"{"soil": 1, "foam": 2}"#)
            .bind("h", &names(), &[1, 2])
            .unwrap();
        assert!(h.eval([0.0, 0.0], 3).is_nan());
        assert_eq!(h.region_constant(3), None);
        assert_eq!(h.constant(), None);

        // The same constant on every region is a constant field.
        let h = json(r#"{"soil": 4, "default": "2*2"}"#)
            .bind("h", &names(), &[1, 2])
            .unwrap();
        assert_eq!(h.constant(), Some(4.0));
        // A constant expression counts as a constant.
        let h = Field::Regions(BTreeMap::from([(
            "soil".into(),
            Field::Expr(Expr::parse("3").unwrap()),
        )]))
        .bind("h", &names(), &[1])
        .unwrap();
        assert_eq!(h.region_constant(1), Some(3.0));
    }

    #[test]
    fn binding_errors_name_the_field_and_the_regions() {
        let m = data_error(json(r#"{"clay": 1}"#).bind("stiffness", &names(), &[1, 2]));
        assert_eq!(
            m,
            "stiffness: no region named 'clay' in the mesh (regions: soil, foam)"
        );
        let m = data_error(json(r#"{"7": 1, "default": 0}"#).bind("h", &names(), &[1, 2, 3]));
        assert_eq!(
            m,
            "h: no region named '7' in the mesh (regions: soil, foam, 3)"
        );
        let m = data_error(json(r#"{"foam": 1}"#).bind("h", &names(), &[1]));
        assert!(m.contains("region 'foam' (tag 2) has no triangles"), "{m}");
        let m = data_error(json(r#"{"soil": 1}"#).bind("load f", &names(), &[1, 2]));
        assert_eq!(
            m,
            "load f: no value for region foam and no \"default\" entry (regions: soil, foam)"
        );
        // A name shared by two tags applies to both.
        let shared = BTreeMap::from([(1, "soil".to_string()), (5, "soil".to_string())]);
        let h = json(r#"{"soil": 3}"#).bind("h", &shared, &[1, 5]).unwrap();
        assert_eq!((h.eval([0.0, 0.0], 1), h.eval([0.0, 0.0], 5)), (3.0, 3.0));
        let m = data_error(json(r#"{"soil": 1, "1": 2}"#).bind("h", &names(), &[1, 2]));
        assert!(m.contains("region soil is given twice"), "{m}");
        let nested = Field::Regions(BTreeMap::from([(
            "soil".to_string(),
            Field::Regions(BTreeMap::from([("x".to_string(), Field::Constant(1.0))])),
        )]));
        let m = data_error(nested.bind("h", &names(), &[1]));
        assert!(m.contains("region 'soil' is a table"), "{m}");
        // The error displays as invalid data.
        let shown = json(r#"{"clay": 1}"#)
            .bind("h", &names(), &[1])
            .unwrap_err()
            .to_string();
        assert!(
            shown.starts_with("invalid data: h: no region named 'clay'"),
            "{shown}"
        );
    }

    #[test]
    fn stiffness_rigid_or_elastic() {
        assert_eq!(Stiffness::parse("rigid").unwrap(), Stiffness::Rigid);
        assert_eq!(Stiffness::parse(" RiGiD ").unwrap(), Stiffness::Rigid);
        assert!(Stiffness::parse("rigid").unwrap().is_rigid());
        assert_eq!(
            Stiffness::parse("100").unwrap(),
            Stiffness::Elastic(Field::Constant(100.0))
        );
        assert_eq!(
            Stiffness::parse("1e3").unwrap().field(),
            Some(&Field::Constant(1000.0))
        );
        assert!(Stiffness::parse("rigidity").is_err());
        let s: Stiffness = serde_json::from_str("\"Rigid\"").unwrap();
        assert_eq!(s, Stiffness::Rigid);
        let s: Stiffness = serde_json::from_str("250").unwrap();
        assert_eq!(s, Stiffness::Elastic(Field::Constant(250.0)));
        let s: Stiffness = serde_json::from_str("\"100*(1+x)\"").unwrap();
        assert!(matches!(s, Stiffness::Elastic(Field::Expr(_))));
        let s: Stiffness = serde_json::from_str(r#"{"soil": 100, "foam": "50*x"}"#).unwrap();
        assert!(matches!(s, Stiffness::Elastic(Field::Regions(ref t)) if t.len() == 2));
        // A table may make some regions rigid (mixed bodies); other fields may not.
        let s: Stiffness = serde_json::from_str(r#"{"soil": "rigid", "foam": 50}"#).unwrap();
        let Stiffness::Mixed(t) = &s else {
            panic!("{s:?}")
        };
        assert_eq!(t["soil"], Stiffness::Rigid);
        assert_eq!(t["foam"], Stiffness::Elastic(Field::Constant(50.0)));
        let back = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<Stiffness>(&back).unwrap(), s);
        let e = serde_json::from_str::<Field>(r#"{"soil": "rigid"}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("only the regions of a stiffness table"), "{e}");
    }

    #[test]
    fn deserialise_from_json_values() {
        assert_eq!(json("3"), Field::Constant(3.0));
        assert_eq!(json("-3"), Field::Constant(-3.0));
        assert_eq!(json("2.5"), Field::Constant(2.5));
        assert_eq!(json("\"2.5\""), Field::Constant(2.5));
        assert_eq!(json("\"-pi\""), Field::Constant(-PI));
        match json("\"0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)\"") {
            Field::Expr(e) => assert!((e.eval(0.25, 0.0) - 0.6).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        match json(r#"{"soil": 100, "foam": "50*x", "default": "1/2"}"#) {
            Field::Regions(t) => {
                assert_eq!(t["soil"], Field::Constant(100.0));
                assert_eq!(t["default"], Field::Constant(0.5));
                assert!(matches!(t["foam"], Field::Expr(_)));
            }
            other => panic!("{other:?}"),
        }
        for (bad, fragment) in [
            ("true", "a number, a string"),
            ("[]", "empty array"),
            ("[1, \"x\"]", "f64"),
            ("null", "a number, a string"),
            ("\"1 + z\"", "unknown variable 'z'"),
            (r#"{"soil": {"a": 1}}"#, "a region's value"),
            (r#"{"soil": true}"#, "a region's value"),
            (r#"{"soil": "sin("}"#, "unexpected end of expression"),
            (r#"{"soil": 1, "soil": 2}"#, "given twice"),
            ("{}", "empty table"),
        ] {
            let e = serde_json::from_str::<Field>(bad).unwrap_err().to_string();
            assert!(e.contains(fragment), "{bad}: {e}");
        }
    }

    #[test]
    fn serialise_round_trip() {
        for text in [r#"3.5"#, r#""x*y""#, r#"{"default":"1+x","soil":2.0}"#] {
            let f = json(text);
            let back = serde_json::to_string(&f).unwrap();
            assert_eq!(json(&back), f, "{text} -> {back}");
        }
        assert_eq!(
            serde_json::to_string(&Stiffness::Rigid).unwrap(),
            "\"rigid\""
        );
    }

    #[test]
    fn checks_report_value_and_place() {
        let pts = [
            ([0.0, 0.0], 1.0),
            ([0.25, 0.5], -3.0),
            ([1.0, 1.0], -1.0),
            ([2.0, 0.0], 0.0),
        ];
        let m = data_error(check_values("stiffness h", pts, Rule::FiniteNonNegative));
        assert_eq!(
            m,
            "stiffness h is negative (-3) at (0.25, 0.5) (and at 1 more point)"
        );
        assert!(check_values("load f", pts, Rule::Finite).is_ok());
        let m = data_error(check_values("t", pts, Rule::FinitePositive));
        assert_eq!(
            m,
            "t is not positive (-3) at (0.25, 0.5) (and at 2 more points)"
        );
        assert!(check_values("h", [([0.0, 0.0], 0.0)], Rule::FiniteNonNegative).is_ok());
        assert!(check_values("h", std::iter::empty(), Rule::FinitePositive).is_ok());
        for rule in [Rule::Finite, Rule::FiniteNonNegative, Rule::FinitePositive] {
            let m = data_error(check_values("f", [([1.0, 2.0], f64::NAN)], rule));
            assert_eq!(m, "f is not a number (NaN) at (1, 2)");
            let m = data_error(check_values("f", [([1.0, 2.0], f64::INFINITY)], rule));
            assert_eq!(m, "f is infinite (inf) at (1, 2)");
            let m = data_error(check_values("f", [([1.0, 2.0], f64::NEG_INFINITY)], rule));
            assert_eq!(m, "f is infinite (-inf) at (1, 2)");
        }
        let m = data_error(check_value("tension t", 0.0, Rule::FinitePositive));
        assert_eq!(m, "tension t is not positive (0)");
        assert!(check_value("tension t", 1e-12, Rule::FinitePositive).is_ok());
        let shown = check_value("t", -1.0, Rule::FinitePositive)
            .unwrap_err()
            .to_string();
        assert_eq!(shown, "invalid data: t is not positive (-1)");
        // Long numbers are shortened to 6 significant digits.
        let m = data_error(check_values(
            "h",
            [([0.1 + 0.2, 1.0 / 3.0], -1e-9)],
            Rule::FiniteNonNegative,
        ));
        assert_eq!(m, "h is negative (-1e-9) at (0.3, 0.333333)");
        assert_eq!(number(1234567.0), "1.23457e6");
        assert_eq!(number(-2.5e20), "-2.5e20");
        assert_eq!(number(100.0), "100");
        assert_eq!(number(0.000123456789), "0.000123457");
    }

    #[test]
    fn thread_safe() {
        fn check<T: Send + Sync>() {}
        check::<Field>();
        check::<BoundField>();
        check::<Stiffness>();
    }

    #[test]
    fn ambiguous_region_names_are_refused() {
        // Tag 5 is named "2", and tag 2 exists: the key "2" could mean either.
        let names = BTreeMap::from([
            (2, "clay".to_string()),
            (5, "2".to_string()),
            (6, "default".to_string()),
            (7, String::new()),
            (8, "8".to_string()),
        ]);
        let tags = [2, 5, 6, 7, 8, 2];
        let m = data_error(json(r#"{"2": 1, "default": 0}"#).bind("stiffness h", &names, &tags));
        assert!(m.contains("'2' is ambiguous") && m.contains("clay"), "{m}");
        // Tags reach the regions whose names are reserved or empty; a name equal to its
        // own tag is no ambiguity.
        let h = json(r#"{"6": 1, "7": 2, "8": 3, "clay": 4, "default": 0}"#)
            .bind("stiffness h", &names, &tags)
            .unwrap();
        assert_eq!(h.eval([0.0, 0.0], 6), 1.0);
        assert_eq!(h.eval([0.0, 0.0], 7), 2.0);
        assert_eq!(h.eval([0.0, 0.0], 8), 3.0);
        assert_eq!(h.eval([0.0, 0.0], 5), 0.0);
    }
}
