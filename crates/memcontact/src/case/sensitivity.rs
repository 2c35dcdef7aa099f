//! `[[sensor]]`, `[sensitivity]` and `[fit]`: the points where the deflection is read (and
//! measured), the derivatives a run reports, and the back-analysis of stiffnesses from
//! measured deflections (docs/theory.md#sensitivities).
//!
//! Here: the keys as serde values, their checks without the mesh, and the parameters a
//! case can be differentiated in ([`ParameterKey`]): which datum a key names (t, f, φ, h,
//! the body below's φ_low and h_low, the boundary heights g, or one entry of a region
//! table of these), and how it enters (a number; a factor on an expression; an offset
//! added to a surface). The derivatives themselves are computed by
//! [`crate::sensitivity`].

use crate::error::Invalid;
use crate::field::{Field, Stiffness};
use crate::problem::Problem;
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `[[sensor]]`: a point where the deflection u is read (by P1 interpolation), and,
/// for a fit, measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sensor {
    /// The sensor's name (letters, digits, `_`, `-`, `.`): the output `sensor:NAME` and
    /// the influence field `dsensor_NAME_dh`.
    pub name: String,
    /// Where it is, `[x, y]` (inside the mesh).
    pub at: [f64; 2],
    /// The measured deflection there (length), for `[fit]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured: Option<f64>,
    /// The measurement's standard deviation σ > 0 (length; default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
}

/// `[sensitivity]`: the outputs to differentiate and the case keys to differentiate them
/// in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensitivitySpec {
    /// Any of `energy`, `max_deflection`, `total_contact_force`, `total_contact_force_low`,
    /// `contact_area`, `sensors` (every sensor), `sensor:NAME`, `contact_force:REGION`.
    #[serde(default = "default_outputs")]
    pub outputs: Vec<String>,
    /// Case keys whose value is a number (`membrane.tension`, `obstacle.stiffness.soft`,
    /// ...), or that hold an expression (differentiated as a factor on the load or the
    /// stiffness, an offset of a surface or of the boundary heights).
    pub parameters: Vec<String>,
    /// Write the influence maps `dJ_dh` and `dsensor_NAME_dh` into `solution.vtu`
    /// (default `true`; each sensor's map costs one adjoint solve).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub influence: Option<bool>,
}

fn default_outputs() -> Vec<String> {
    vec!["energy".into()]
}

/// `[fit]`: back-analysis of case parameters from measured deflections.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    /// The parameters fitted, key → `[min, max]` (the start is the case's value).
    pub parameters: FitParameters,
    /// A CSV file of measurements (`name,x,y,u` and optionally `sigma`), relative to the
    /// case file; without it, the sensors' `measured` values.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurements: Option<PathBuf>,
    /// The most Gauss-Newton (Levenberg-Marquardt) iterations.
    #[serde(default = "default_fit_iterations")]
    pub max_iterations: usize,
    /// Stop when a step changes no parameter by more than this (relative; in ln p for
    /// positive parameters), or the gradient of the misfit is this small.
    #[serde(default = "default_fit_tolerance")]
    pub tolerance: f64,
    /// The weight α of a Tikhonov pull toward the start, `½ α ‖ln p − ln p₀‖²`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<f64>,
}

fn default_fit_iterations() -> usize {
    30
}

fn default_fit_tolerance() -> f64 {
    1e-8
}

/// The bounds of the fitted parameters: case key → `[min, max]`. In TOML either quoted
/// keys (`"obstacle.stiffness.soft" = [10, 1000]`) or dotted ones
/// (`obstacle.stiffness.soft = [10, 1000]`, which `--set fit.parameters.KEY=[a, b]`
/// writes) under `[fit.parameters]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FitParameters(pub BTreeMap<String, [f64; 2]>);

impl Serialize for FitParameters {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> Deserialize<'de> for FitParameters {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        /// A bound pair, or a table of further key parts.
        enum Entry {
            Bounds([f64; 2]),
            Table(BTreeMap<String, Entry>),
        }
        impl<'de> Deserialize<'de> for Entry {
            fn deserialize<D: serde::Deserializer<'de>>(
                d: D,
            ) -> std::result::Result<Entry, D::Error> {
                struct V;
                impl<'de> Visitor<'de> for V {
                    type Value = Entry;
                    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                        f.write_str("bounds [min, max], or a table of keys")
                    }
                    fn visit_seq<A: de::SeqAccess<'de>>(
                        self,
                        mut seq: A,
                    ) -> std::result::Result<Entry, A::Error> {
                        let mut v = Vec::new();
                        while let Some(x) = seq.next_element::<f64>()? {
                            if v.len() == 2 {
                                return Err(de::Error::custom("bounds are two numbers [min, max]"));
                            }
                            v.push(x);
                        }
                        match v[..] {
                            [a, b] => Ok(Entry::Bounds([a, b])),
                            _ => Err(de::Error::custom("bounds are two numbers [min, max]")),
                        }
                    }
                    fn visit_map<A: MapAccess<'de>>(
                        self,
                        mut map: A,
                    ) -> std::result::Result<Entry, A::Error> {
                        let mut t = BTreeMap::new();
                        while let Some((k, v)) = map.next_entry::<String, Entry>()? {
                            t.insert(k, v);
                        }
                        Ok(Entry::Table(t))
                    }
                }
                d.deserialize_any(V)
            }
        }
        fn flatten(
            prefix: &str,
            t: BTreeMap<String, Entry>,
            out: &mut BTreeMap<String, [f64; 2]>,
        ) -> std::result::Result<(), String> {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k
                } else {
                    format!("{prefix}.{k}")
                };
                match v {
                    Entry::Bounds(b) => {
                        if out.insert(key.clone(), b).is_some() {
                            return Err(format!("\"{key}\" is given twice"));
                        }
                    }
                    Entry::Table(t) => flatten(&key, t, out)?,
                }
            }
            Ok(())
        }
        let Entry::Table(t) = Entry::deserialize(d)? else {
            return Err(de::Error::custom(
                "a table of case keys and their bounds, e.g. \
                 { \"obstacle.stiffness.soft\" = [10, 1000] }",
            ));
        };
        let mut out = BTreeMap::new();
        flatten("", t, &mut out).map_err(de::Error::custom)?;
        Ok(FitParameters(out))
    }
}

impl FitSpec {
    /// Makes a relative `measurements` path relative to `base` (the case file's directory).
    pub fn resolve(&mut self, base: &Path) {
        if let Some(m) = &mut self.measurements {
            if m.is_relative() {
                *m = base.join(&*m);
            }
        }
    }
}

/// The datum a parameter key names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParameterTarget {
    /// `membrane.tension`: t.
    Tension,
    /// `membrane.load`: f.
    Load,
    /// `obstacle.shape`: φ.
    Shape,
    /// `obstacle.stiffness`: h.
    Stiffness,
    /// `lower.shape`: φ_low.
    LowerShape,
    /// `lower.stiffness`: h_low.
    LowerStiffness,
    /// `boundary.height`: g.
    Height,
}

impl ParameterTarget {
    /// All targets with their case keys.
    const ALL: [(ParameterTarget, &'static str); 7] = [
        (ParameterTarget::Tension, "membrane.tension"),
        (ParameterTarget::Load, "membrane.load"),
        (ParameterTarget::Shape, "obstacle.shape"),
        (ParameterTarget::Stiffness, "obstacle.stiffness"),
        (ParameterTarget::LowerShape, "lower.shape"),
        (ParameterTarget::LowerStiffness, "lower.stiffness"),
        (ParameterTarget::Height, "boundary.height"),
    ];

    /// The case key of the whole datum.
    pub fn key(self) -> &'static str {
        ParameterTarget::ALL
            .iter()
            .find(|(t, _)| *t == self)
            .map(|(_, k)| *k)
            .expect("every target has a key")
    }

    /// A surface or a height: an expression is shifted (an offset), not scaled.
    fn is_surface(self) -> bool {
        matches!(
            self,
            ParameterTarget::Shape | ParameterTarget::LowerShape | ParameterTarget::Height
        )
    }
}

/// How a parameter enters its datum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParameterKind {
    /// The key holds a number p; derivatives are d/dp, elasticities (p/Q) dQ/dp.
    Value,
    /// The key holds an expression (or a table, or per-vertex values) of a load or a
    /// stiffness: the derivative is with respect to a factor k multiplying it, at k = 1.
    Factor,
    /// The key holds an expression of a surface or a height: the derivative is with
    /// respect to a constant c added to it, at c = 0 (no elasticity).
    Offset,
}

impl ParameterKind {
    /// The name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            ParameterKind::Value => "value",
            ParameterKind::Factor => "factor",
            ParameterKind::Offset => "offset",
        }
    }
}

/// A case key a derivative can be taken in: the datum, the region-table entry (if one),
/// how it enters, and its value in the case (the number; 1 for a factor, 0 for an offset).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterKey {
    /// The key as given (`obstacle.stiffness.soft`).
    pub key: String,
    /// The datum.
    pub target: ParameterTarget,
    /// The region-table entry, when the key names one (`soft`, or `default`).
    pub region: Option<String>,
    /// How it enters.
    pub kind: ParameterKind,
    /// Its value in the case.
    pub value: f64,
}

/// A datum of the problem as the parameter keys see it.
enum Datum<'a> {
    Number(f64),
    Field(&'a Field),
    Stiffness(&'a Stiffness),
}

fn datum(problem: &Problem, target: ParameterTarget) -> Option<Datum<'_>> {
    Some(match target {
        ParameterTarget::Tension => Datum::Number(problem.membrane.tension),
        ParameterTarget::Load => Datum::Field(&problem.membrane.load),
        ParameterTarget::Shape => Datum::Field(&problem.obstacle.shape),
        ParameterTarget::Stiffness => Datum::Stiffness(&problem.obstacle.stiffness),
        ParameterTarget::LowerShape => Datum::Field(&problem.lower.as_ref()?.shape),
        ParameterTarget::LowerStiffness => Datum::Stiffness(&problem.lower.as_ref()?.stiffness),
        ParameterTarget::Height => Datum::Field(&problem.boundary.height),
    })
}

/// The kind and value of a field (or of one of its region entries) as a parameter of
/// `target`; `None` where it cannot be one (a table as a whole is a factor or an offset).
fn field_kind(target: ParameterTarget, f: &Field) -> (ParameterKind, f64) {
    match (f, target.is_surface()) {
        (Field::Constant(v), _) => (ParameterKind::Value, *v),
        (_, true) => (ParameterKind::Offset, 0.0),
        (_, false) => (ParameterKind::Factor, 1.0),
    }
}

impl ParameterKey {
    /// Parses `key` against the case's problem. Errors name the key and list the valid
    /// ones.
    pub fn parse(problem: &Problem, key: &str) -> std::result::Result<ParameterKey, String> {
        let unknown = || {
            format!(
                "no parameter \"{key}\" in this case (valid keys: {})",
                valid_keys(problem).join(", ")
            )
        };
        let (target, rest) = ParameterTarget::ALL
            .iter()
            .find_map(|&(t, k)| {
                if key == k {
                    Some((t, None))
                } else {
                    key.strip_prefix(k)
                        .and_then(|r| r.strip_prefix('.'))
                        .map(|r| (t, Some(r.to_string())))
                }
            })
            .ok_or_else(unknown)?;
        let d = datum(problem, target).ok_or_else(unknown)?;
        let (kind, value) = match (&d, &rest) {
            (Datum::Number(v), None) => (ParameterKind::Value, *v),
            (Datum::Field(f), None) => field_kind(target, f),
            (Datum::Field(Field::Regions(t)), Some(r)) => {
                let f = t.get(r.as_str()).ok_or_else(unknown)?;
                field_kind(target, f)
            }
            (Datum::Stiffness(Stiffness::Elastic(f)), None) => field_kind(target, f),
            (Datum::Stiffness(Stiffness::Mixed(_)), None) => (ParameterKind::Factor, 1.0),
            (Datum::Stiffness(Stiffness::Elastic(Field::Regions(t))), Some(r)) => {
                field_kind(target, t.get(r.as_str()).ok_or_else(unknown)?)
            }
            (Datum::Stiffness(Stiffness::Mixed(t)), Some(r)) => match t.get(r.as_str()) {
                Some(Stiffness::Elastic(f)) => field_kind(target, f),
                Some(_) => {
                    return Err(format!(
                        "\"{key}\" is rigid: a rigid region has no stiffness to \
                         differentiate (valid keys: {})",
                        valid_keys(problem).join(", ")
                    ))
                }
                None => return Err(unknown()),
            },
            (Datum::Stiffness(Stiffness::Rigid), _) => {
                return Err(format!(
                    "\"{key}\": the body is rigid, it has no stiffness to differentiate \
                     (valid keys: {})",
                    valid_keys(problem).join(", ")
                ))
            }
            _ => return Err(unknown()),
        };
        Ok(ParameterKey {
            key: key.to_string(),
            target,
            region: rest,
            kind,
            value,
        })
    }

    /// `problem` with this parameter set to `value` (a number for [`ParameterKind::Value`],
    /// the factor for [`ParameterKind::Factor`], the offset for [`ParameterKind::Offset`]).
    pub fn apply(&self, problem: &mut Problem, value: f64) -> std::result::Result<(), String> {
        let kind = self.kind;
        let region_entry = |f: &mut Field| -> std::result::Result<(), String> {
            match (&self.region, f) {
                (None, f) => set_field(f, kind, value),
                (Some(r), Field::Regions(t)) => match t.get_mut(r.as_str()) {
                    Some(e) => set_field(e, kind, value),
                    None => Err(format!("no region entry \"{r}\"")),
                },
                (Some(r), _) => Err(format!("no region entry \"{r}\"")),
            }
        };
        let stiffness = |s: &mut Stiffness| -> std::result::Result<(), String> {
            match (&self.region, s) {
                (_, Stiffness::Elastic(f)) => region_entry(f),
                (None, Stiffness::Mixed(t)) => {
                    for v in t.values_mut() {
                        if let Stiffness::Elastic(f) = v {
                            set_field(f, kind, value)?;
                        }
                    }
                    Ok(())
                }
                (Some(r), Stiffness::Mixed(t)) => match t.get_mut(r.as_str()) {
                    Some(Stiffness::Elastic(f)) => set_field(f, kind, value),
                    _ => Err(format!("no elastic region entry \"{r}\"")),
                },
                (_, Stiffness::Rigid) => Err("the body is rigid".into()),
            }
        };
        fn lower(p: &mut Problem) -> std::result::Result<&mut crate::problem::Obstacle, String> {
            p.lower
                .as_mut()
                .ok_or_else(|| "the case has no [lower]".to_string())
        }
        match self.target {
            ParameterTarget::Tension => {
                problem.membrane.tension = match kind {
                    ParameterKind::Factor => problem.membrane.tension * value,
                    _ => value,
                };
                Ok(())
            }
            ParameterTarget::Load => region_entry(&mut problem.membrane.load),
            ParameterTarget::Shape => region_entry(&mut problem.obstacle.shape),
            ParameterTarget::Stiffness => stiffness(&mut problem.obstacle.stiffness),
            ParameterTarget::LowerShape => region_entry(&mut lower(problem)?.shape),
            ParameterTarget::LowerStiffness => stiffness(&mut lower(problem)?.stiffness),
            ParameterTarget::Height => region_entry(&mut problem.boundary.height),
        }
    }
}

/// A field set to the number `value` ([`ParameterKind::Value`]), multiplied by it
/// ([`ParameterKind::Factor`]) or shifted by it ([`ParameterKind::Offset`]); a region table
/// entry by entry.
fn set_field(f: &mut Field, kind: ParameterKind, value: f64) -> std::result::Result<(), String> {
    let op = |x: f64| match kind {
        ParameterKind::Value => value,
        ParameterKind::Factor => x * value,
        ParameterKind::Offset => x + value,
    };
    match f {
        Field::Constant(c) => *c = op(*c),
        _ if kind == ParameterKind::Value => *f = Field::Constant(value),
        Field::Nodal(v) => *v = v.iter().map(|&x| op(x)).collect(),
        Field::Expr(e) => {
            let text = match kind {
                ParameterKind::Factor => format!("{value:e}*({})", e.source()),
                _ => format!("({}) + {value:e}", e.source()),
            };
            *f = Field::parse(&text).map_err(|e| e.to_string())?;
        }
        Field::Regions(t) => {
            for v in t.values_mut() {
                set_field(v, kind, value)?;
            }
        }
    }
    Ok(())
}

/// Every parameter key of the case's problem: the data as a whole and every entry of
/// their region tables (not the rigid ones).
pub fn valid_keys(problem: &Problem) -> Vec<String> {
    let mut keys = Vec::new();
    for (target, key) in ParameterTarget::ALL {
        let Some(d) = datum(problem, target) else {
            continue;
        };
        match d {
            Datum::Number(_) => keys.push(key.to_string()),
            Datum::Field(f) => {
                keys.push(key.to_string());
                if let Field::Regions(t) = f {
                    keys.extend(t.keys().map(|r| format!("{key}.{r}")));
                }
            }
            Datum::Stiffness(Stiffness::Rigid) => {}
            Datum::Stiffness(Stiffness::Elastic(f)) => {
                keys.push(key.to_string());
                if let Field::Regions(t) = f {
                    keys.extend(t.keys().map(|r| format!("{key}.{r}")));
                }
            }
            Datum::Stiffness(Stiffness::Mixed(t)) => {
                keys.push(key.to_string());
                keys.extend(
                    t.iter()
                        .filter(|(_, v)| !v.is_rigid())
                        .map(|(r, _)| format!("{key}.{r}")),
                );
            }
        }
    }
    keys
}

/// The names `[sensitivity] outputs` accepts (besides `sensor:NAME` and
/// `contact_force:REGION`).
pub const OUTPUT_NAMES: [&str; 6] = [
    "energy",
    "max_deflection",
    "total_contact_force",
    "total_contact_force_low",
    "contact_area",
    "sensors",
];

/// Whether `name` may name a sensor: letters, digits, `_`, `-`, `.`.
fn sensor_name_ok(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

/// Checks a sensor's name and point (`key` is `sensor.N`, or a measurements file row).
pub(crate) fn check_sensor(key: &str, s: &Sensor) -> std::result::Result<(), Invalid> {
    if !sensor_name_ok(&s.name) {
        return Err(Invalid::new(
            format!("{key}.name"),
            format!(
                "\"{}\" is not a sensor name (1 to 64 letters, digits, '_', '-' or '.')",
                s.name
            ),
        ));
    }
    if !(s.at[0].is_finite() && s.at[1].is_finite()) {
        return Err(Invalid::new(
            format!("{key}.at"),
            format!("must be a finite point, got {:?}", s.at),
        ));
    }
    if let Some(m) = s.measured {
        if !m.is_finite() {
            return Err(Invalid::new(
                format!("{key}.measured"),
                format!("must be a finite number, got {m}"),
            ));
        }
    }
    if let Some(sigma) = s.sigma {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(Invalid::new(
                format!("{key}.sigma"),
                format!("must be a finite number > 0, got {sigma}"),
            ));
        }
    }
    Ok(())
}

/// Checks the sensors, `[sensitivity]` and `[fit]` of a case against its problem (without
/// the mesh: points inside it and region names are checked on the mesh).
pub fn validate(
    problem: &Problem,
    sensors: &[Sensor],
    sensitivity: Option<&SensitivitySpec>,
    fit: Option<&FitSpec>,
) -> std::result::Result<(), Invalid> {
    for (i, s) in sensors.iter().enumerate() {
        let key = format!("sensor.{i}");
        check_sensor(&key, s)?;
        if sensors[..i].iter().any(|o| o.name == s.name) {
            return Err(Invalid::new(
                format!("{key}.name"),
                format!("\"{}\" names two sensors", s.name),
            ));
        }
    }
    if let Some(spec) = sensitivity {
        if spec.outputs.is_empty() {
            return Err(Invalid::new("sensitivity.outputs", "is empty"));
        }
        for (i, o) in spec.outputs.iter().enumerate() {
            check_output(problem, sensors, o)
                .map_err(|m| Invalid::new("sensitivity.outputs", m))?;
            if spec.outputs[..i].contains(o) {
                return Err(Invalid::new(
                    "sensitivity.outputs",
                    format!("\"{o}\" is listed twice"),
                ));
            }
        }
        if spec.parameters.is_empty() {
            return Err(Invalid::new("sensitivity.parameters", "is empty"));
        }
        for (i, p) in spec.parameters.iter().enumerate() {
            ParameterKey::parse(problem, p)
                .map_err(|m| Invalid::new("sensitivity.parameters", m))?;
            if spec.parameters[..i].contains(p) {
                return Err(Invalid::new(
                    "sensitivity.parameters",
                    format!("\"{p}\" is listed twice"),
                ));
            }
        }
    }
    if let Some(fit) = fit {
        validate_fit(problem, sensors, fit)?;
    }
    Ok(())
}

/// Checks one output name.
fn check_output(problem: &Problem, sensors: &[Sensor], o: &str) -> std::result::Result<(), String> {
    if let Some(name) = o.strip_prefix("sensor:") {
        return if sensors.iter().any(|s| s.name == name) {
            Ok(())
        } else {
            Err(format!("\"{o}\": no [[sensor]] is named \"{name}\""))
        };
    }
    if let Some(region) = o.strip_prefix("contact_force:") {
        return if region.trim().is_empty() {
            Err(format!("\"{o}\": name a region of the mesh"))
        } else {
            Ok(())
        };
    }
    match o {
        "sensors" if sensors.is_empty() => Err("\"sensors\": the case has no [[sensor]]".into()),
        "total_contact_force_low" if problem.lower.is_none() => {
            Err("\"total_contact_force_low\": the case has no [lower] body".into())
        }
        _ if OUTPUT_NAMES.contains(&o) => Ok(()),
        _ => Err(format!(
            "unknown output \"{o}\" (valid: {}, sensor:NAME, contact_force:REGION)",
            OUTPUT_NAMES.join(", ")
        )),
    }
}

/// Checks `[fit]`: the parameters are numbers of the case within their bounds, the options
/// in range, and (without a measurements file) enough sensors measured.
fn validate_fit(
    problem: &Problem,
    sensors: &[Sensor],
    fit: &FitSpec,
) -> std::result::Result<(), Invalid> {
    if fit.parameters.0.is_empty() {
        return Err(Invalid::new("fit.parameters", "is empty"));
    }
    for (key, &[lo, hi]) in &fit.parameters.0 {
        let k = format!("fit.parameters.{key}");
        let p = ParameterKey::parse(problem, key).map_err(|m| Invalid::new(&k, m))?;
        if p.kind != ParameterKind::Value {
            return Err(Invalid::new(
                &k,
                format!(
                    "the case gives {} by {}: a fitted parameter must be a number in the \
                     case (its start value)",
                    key,
                    match p.kind {
                        ParameterKind::Factor => "an expression or a table (a factor)",
                        _ => "an expression (an offset)",
                    }
                ),
            ));
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(Invalid::new(
                &k,
                format!("bounds must be two finite numbers min < max, got [{lo}, {hi}]"),
            ));
        }
        if !(lo <= p.value && p.value <= hi) {
            return Err(Invalid::new(
                &k,
                format!(
                    "the bounds [{lo}, {hi}] exclude the start value {} (the case's own)",
                    p.value
                ),
            ));
        }
        let positive_only = matches!(
            p.target,
            ParameterTarget::Tension | ParameterTarget::Stiffness | ParameterTarget::LowerStiffness
        );
        if positive_only && lo <= 0.0 {
            return Err(Invalid::new(
                &k,
                format!(
                    "a tension or a stiffness is fitted in its logarithm: the lower bound \
                     must be > 0, got {lo}"
                ),
            ));
        }
    }
    if fit.max_iterations == 0 || fit.max_iterations > 1000 {
        return Err(Invalid::new(
            "fit.max_iterations",
            format!("must be between 1 and 1000, got {}", fit.max_iterations),
        ));
    }
    let tol = fit.tolerance;
    if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
        return Err(Invalid::new(
            "fit.tolerance",
            format!("must be a number in (0, 1), got {tol}"),
        ));
    }
    if let Some(a) = fit.prior {
        if !(a.is_finite() && a >= 0.0) {
            return Err(Invalid::new(
                "fit.prior",
                format!("must be a finite number ≥ 0, got {a}"),
            ));
        }
    }
    if fit.measurements.is_none() {
        let measured = sensors.iter().filter(|s| s.measured.is_some()).count();
        check_enough(measured, fit).map_err(|m| Invalid::new("fit", m))?;
        if measured == 0 {
            return Err(Invalid::new(
                "fit",
                "no measurements: give sensors a `measured` value, or \
                 measurements = \"points.csv\"",
            ));
        }
    }
    Ok(())
}

/// At least as many measurements as parameters, unless a prior regularises the fit.
pub(crate) fn check_enough(measured: usize, fit: &FitSpec) -> std::result::Result<(), String> {
    let n = fit.parameters.0.len();
    if measured < n && fit.prior.is_none_or(|a| a == 0.0) {
        return Err(format!(
            "{measured} measurement{} for {n} parameters: the fit needs at least as many \
             measurements as parameters (or a prior, fit.prior > 0)",
            if measured == 1 { "" } else { "s" }
        ));
    }
    Ok(())
}

/// Checks the sensors, `[sensitivity]` and `[fit]` of a whole case ([`validate`]), and
/// refuses `[fit]` and `[sensitivity]` beside steps or `[adapt]`, with the reason.
pub(crate) fn validate_case(case: &super::Case) -> std::result::Result<(), Invalid> {
    validate(
        &case.problem,
        &case.sensors,
        case.sensitivity.as_ref(),
        case.fit.as_ref(),
    )?;
    let with = if case.sweep.is_some() {
        "[sweep]"
    } else if !case.load_cases.is_empty() {
        "[[load_case]]"
    } else if case.adapt.is_some() {
        "[adapt]"
    } else {
        return Ok(());
    };
    let why = "the derivatives belong to one discrete problem, and a sweep, load cases or \
               an adaptive loop solve several (run the sensitivity or the fit on one case; \
               a later version may join them)";
    if case.fit.is_some() {
        return Err(Invalid::new(
            "fit",
            format!("a case with {with} cannot fit: {why}"),
        ));
    }
    if case.sensitivity.is_some() {
        return Err(Invalid::new(
            "sensitivity",
            format!("a case with {with} cannot have [sensitivity]: {why}"),
        ));
    }
    Ok(())
}
