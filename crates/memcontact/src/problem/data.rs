//! The data of Problem 1 and beyond: membrane, obstacle, body below, boundary heights and
//! free edges, and the checks of their constants.

use super::mesh::MeshSpec;
use crate::error::Invalid;
use crate::field::{Field, Stiffness};
use crate::model::{Foundation, Sampling};
use serde::{Deserialize, Serialize};

/// The problem: a mesh and the data t, f, φ, h of the paper's Problem 1, with the
/// discretisation choices of its §2 (consistent or lumped L, nodal or mollified φ).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Problem {
    /// `[mesh]`: where the triangulation comes from.
    pub mesh: MeshSpec,
    /// `[membrane]`: tension and load.
    pub membrane: Membrane,
    /// `[obstacle]`: the elastic (or rigid) body.
    pub obstacle: Obstacle,
    /// `[boundary]`: the heights on the fixed boundary and the free boundary regions
    /// (default: the whole boundary fixed at 0, as in the paper).
    #[serde(default, skip_serializing_if = "Boundary::is_default")]
    pub boundary: Boundary,
    /// `[lower]`: a second body below the membrane (its surface, stiffness, foundation and
    /// sampling, with the keys of `[obstacle]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower: Option<Obstacle>,
}

/// `[boundary]`: `u = g` on the fixed part of the boundary, the natural condition
/// (no force across the edge) on the free part.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Boundary {
    /// The height g (length): a number, an expression of x and y, a table per boundary
    /// region (Gmsh physical curves; the generators' sides `left`, `right`, `bottom`,
    /// `top`, `outer`, `hole1`, ...), or one value per vertex.
    #[serde(default = "zero_height", skip_serializing_if = "is_zero")]
    pub height: Field,
    /// The boundary regions that are not fixed (names, or tags as text).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub free: Vec<String>,
}

fn zero_height() -> Field {
    Field::Constant(0.0)
}

fn is_zero(f: &Field) -> bool {
    matches!(f, Field::Constant(v) if *v == 0.0)
}

impl Default for Boundary {
    fn default() -> Boundary {
        Boundary {
            height: zero_height(),
            free: Vec::new(),
        }
    }
}

impl Boundary {
    /// The paper's frame: everything fixed at height 0.
    pub fn is_default(&self) -> bool {
        is_zero(&self.height) && self.free.is_empty()
    }
}

/// `[membrane]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Membrane {
    /// The tension t > 0 (force/length).
    pub tension: f64,
    /// The load f (force/area, positive in +x₃): a number, an expression or a region table.
    pub load: Field,
}

/// `[obstacle]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// The body's surface φ (length).
    pub shape: Field,
    /// The stiffness h ≥ 0 (force/length³), or rigid.
    pub stiffness: Stiffness,
    /// The consistent matrix of the paper or its lumped diagonal.
    #[serde(default = "consistent")]
    pub foundation: Foundation,
    /// Nodal values of φ, or the paper's mollified sampling.
    #[serde(default)]
    pub sampling: SamplingKind,
    /// The mollifier radius ε for mollified sampling (default: the paper's ε_n).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
}

fn consistent() -> Foundation {
    Foundation::Consistent
}

/// How φ is sampled at the vertices (the name of a [`Sampling`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SamplingKind {
    /// `φ_i = φ(a_i)`.
    #[default]
    Nodal,
    /// The paper's `φ_n = r_n(J_ε * φ)`.
    Mollified,
}

impl SamplingKind {
    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            SamplingKind::Nodal => "nodal",
            SamplingKind::Mollified => "mollified",
        }
    }
}

impl Obstacle {
    /// The sampling with its mollifier radius.
    pub fn sampling(&self) -> Sampling {
        match self.sampling {
            SamplingKind::Nodal => Sampling::Nodal,
            SamplingKind::Mollified => Sampling::Mollified {
                epsilon: self.epsilon,
            },
        }
    }
}

/// Checks a field's constants (a number, or the numbers of a region table): finite, and
/// non-negative when asked. Expressions are checked where they are evaluated.
fn check_field(key: &str, f: &Field, non_negative: bool) -> std::result::Result<(), Invalid> {
    let check = |k: String, v: f64| {
        if !v.is_finite() {
            Err(Invalid::new(k, format!("must be finite, got {v}")))
        } else if non_negative && v < 0.0 {
            Err(Invalid::new(k, format!("must be ≥ 0, got {v}")))
        } else {
            Ok(())
        }
    };
    match f {
        Field::Constant(v) => check(key.to_string(), *v),
        Field::Expr(_) => Ok(()),
        Field::Nodal(values) => {
            for (i, v) in values.iter().enumerate() {
                check(format!("{key}[{i}]"), *v)?;
            }
            Ok(())
        }
        Field::Regions(t) => {
            for (name, v) in t {
                if let Field::Constant(c) = v {
                    check(format!("{key}.{name}"), *c)?;
                }
            }
            Ok(())
        }
    }
}

impl Problem {
    /// Checks every value that can be checked without the mesh: t > 0, constants finite,
    /// h ≥ 0, ε > 0 and only with mollified sampling, the mesh generator's parameters, the
    /// boundary heights and, for the generators, the names of the boundary regions.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        self.mesh.validate()?;
        let t = self.membrane.tension;
        if !(t.is_finite() && t > 0.0) {
            return Err(Invalid::new(
                "membrane.tension",
                format!("must be a finite number > 0, got {t}"),
            ));
        }
        check_field("membrane.load", &self.membrane.load, false)?;
        self.obstacle.validate("obstacle")?;
        if let Some(low) = &self.lower {
            low.validate("lower")?;
        }
        self.boundary.validate(&self.mesh)
    }
}

impl Obstacle {
    /// Checks a body's constants (the section is `obstacle` or `lower`).
    fn validate(&self, section: &str) -> std::result::Result<(), Invalid> {
        check_field(&format!("{section}.shape"), &self.shape, false)?;
        for (key, h) in self.stiffness.elastic_fields() {
            check_field(&format!("{section}.stiffness{key}"), h, true)?;
        }
        if let (SamplingKind::Mollified, Field::Nodal(_)) = (self.sampling, &self.shape) {
            return Err(Invalid::new(
                format!("{section}.sampling"),
                "mollified sampling needs φ as a function of x and y; nodal values of φ \
                 are its samples (use sampling = \"nodal\")",
            ));
        }
        match (self.sampling, self.epsilon) {
            (SamplingKind::Nodal, Some(_)) => Err(Invalid::new(
                format!("{section}.epsilon"),
                "is only used with sampling = \"mollified\"",
            )),
            (SamplingKind::Mollified, Some(e)) if !(e.is_finite() && e > 0.0) => Err(Invalid::new(
                format!("{section}.epsilon"),
                format!("must be a finite number > 0, got {e}"),
            )),
            _ => Ok(()),
        }
    }
}

impl Boundary {
    /// Checks the heights' constants and, when the mesh generator names its boundary
    /// regions, that `free` and the keys of a height table name existing regions.
    fn validate(&self, mesh: &MeshSpec) -> std::result::Result<(), Invalid> {
        check_field("boundary.height", &self.height, false)?;
        for (i, name) in self.free.iter().enumerate() {
            if name.trim().is_empty() {
                return Err(Invalid::new("boundary.free", format!("entry {i} is empty")));
            }
            if self.free[..i].contains(name) {
                return Err(Invalid::new(
                    "boundary.free",
                    format!("\"{name}\" is listed twice"),
                ));
            }
        }
        let Some(sides) = mesh.boundary_region_names() else {
            return Ok(());
        };
        let known = |k: &str| {
            sides.iter().any(|s| s == k)
                || k.trim()
                    .parse::<usize>()
                    .is_ok_and(|t| t >= 1 && t <= sides.len())
        };
        let listing = sides.join(", ");
        for name in &self.free {
            if !known(name) {
                return Err(Invalid::new(
                    "boundary.free",
                    format!(
                        "no boundary region named '{name}' (the {} generator's boundary \
                         regions: {listing})",
                        mesh.kind()
                    ),
                ));
            }
        }
        if let Field::Regions(table) = &self.height {
            for key in table.keys() {
                if key != crate::field::DEFAULT_KEY && !known(key) {
                    return Err(Invalid::new(
                        format!("boundary.height.{key}"),
                        format!(
                            "no boundary region named '{key}' (the {} generator's boundary \
                             regions: {listing})",
                            mesh.kind()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}
