//! The values of data: a number, an expression, a table per region, or one value per
//! vertex; the stiffness with its rigid limit; the rules sampled values must obey.

use super::expr::Expr;
use crate::error::{Error, Result};
use std::collections::BTreeMap;
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

    /// Parses a number or an expression of `x, y` (an [`Expr`], in the grammar of the case
    /// file: docs/case-file/index.md#expressions); an expression that does not depend on
    /// the position becomes a [`Field::Constant`] (`"2*pi"`, `"-3"`).
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

/// The foundation stiffness h: an elastic (Winkler) obstacle with `h ≥ 0`, the rigid
/// obstacle `h = ∞` of the classical obstacle problem `u ≤ φ` (docs/theory.md#limits), or a
/// body rigid in some regions and elastic in others.
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
    pub(super) fn elastic_table(table: &BTreeMap<String, Stiffness>) -> Field {
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
pub(super) fn number(v: f64) -> String {
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
