//! Data bound to a mesh: region tables resolved against its regions once, nodal values
//! against its vertices, so that assembly evaluates them at quadrature points.

use super::coefficient::Coefficient;
use super::expr::Expr;
use super::nodal::NodalP1;
use super::value::{Field, Stiffness, DEFAULT_KEY};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::collections::BTreeMap;
use std::sync::Arc;

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

impl Field {
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

impl Stiffness {
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

impl Coefficient for BoundField {
    fn at(&self, p: [f64; 2], region: u32) -> f64 {
        self.eval(p, region)
    }
    fn at_points(&self, points: &[[f64; 2]], region: u32, out: &mut [f64]) {
        match self.value(region) {
            Some(Value::Expr(e)) => e.eval_many(points, out),
            value => {
                for (o, &p) in out.iter_mut().zip(points) {
                    *o = value.map_or(f64::NAN, |v| v.eval(p));
                }
            }
        }
    }
    fn on_region(&self, region: u32) -> Option<f64> {
        self.region_constant(region)
    }
}
