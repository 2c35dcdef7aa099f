//! What assembly takes: the problem's data bound to a mesh, as views
//! (docs/theory.md#discrete-model and the extensions of docs/theory.md#extensions), and the
//! choices of foundation matrix and sampling.

use crate::error::{Error, Result};
use crate::field::Coefficient;

/// Which foundation matrix represents the elastic obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Foundation {
    /// The paper's consistent matrix `L_ij = ∫ h g_i g_j` (J₂ is not differentiable).
    Consistent,
    /// The diagonal `l_i = ∫ h g_i` (docs/theory.md#lumped): J is C¹ with a semismooth
    /// gradient.
    Lumped,
}

impl std::str::FromStr for Foundation {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "consistent" => Ok(Foundation::Consistent),
            "lumped" => Ok(Foundation::Lumped),
            _ => Err(Error::Data(format!(
                "foundation must be \"consistent\" or \"lumped\", not \"{s}\""
            ))),
        }
    }
}

impl Foundation {
    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Foundation::Consistent => "consistent",
            Foundation::Lumped => "lumped",
        }
    }
}

/// How the obstacle φ is sampled at the vertices (docs/theory.md#obstacle-sampling).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampling {
    /// `φ_i = φ(a_i)`: the usual practice for continuous φ.
    Nodal,
    /// The paper's `φ_n = r_n (J_ε * φ)`; `epsilon: None` takes the paper's
    /// `ε_n = max{l_n^¼, meas(Ω∖Ω_n)^¼, meas(Ω'_n)^¼}`.
    Mollified {
        /// The mollifier radius, or `None` for the paper's ε_n.
        epsilon: Option<f64>,
    },
}

/// The obstacle's stiffness.
#[derive(Clone, Copy)]
pub enum BodyStiffness<'a> {
    /// A Winkler foundation of stiffness h ≥ 0.
    Elastic(&'a dyn Coefficient),
    /// The rigid obstacle (h = ∞): the classical constraint u ≤ φ.
    Rigid,
}

/// The problem data of Problem 1: tension, load, obstacle.
#[derive(Clone, Copy)]
pub struct ProblemData<'a> {
    /// Tension t > 0.
    pub tension: f64,
    /// Load f.
    pub load: &'a dyn Coefficient,
    /// Obstacle surface φ.
    pub shape: &'a dyn Coefficient,
    /// Obstacle stiffness h.
    pub stiffness: BodyStiffness<'a>,
    /// Consistent or lumped L.
    pub foundation: Foundation,
    /// How φ is sampled.
    pub sampling: Sampling,
}

/// The data beyond the paper's frame (docs/theory.md#extensions): boundary heights and free
/// edges, rigid regions of the obstacle (mixed bodies) and a second body below. The default
/// is the paper's frame: the whole boundary fixed at 0, one body, rigid everywhere or
/// nowhere.
#[derive(Clone, Copy, Default)]
pub struct Extensions<'a> {
    /// Which boundary regions are free and the height g on the others (`None`: the whole
    /// boundary fixed at 0).
    pub boundary: Option<BoundaryData<'a>>,
    /// Region tags where the obstacle is rigid while elastic elsewhere (mixed bodies).
    pub rigid_regions: &'a [u32],
    /// The body below the membrane.
    pub lower: Option<BodyData<'a>>,
}

/// The boundary data (docs/theory.md#boundary-data): `u = g` on the fixed part Γ_D, free
/// elsewhere.
#[derive(Clone, Copy)]
pub struct BoundaryData<'a> {
    /// The boundary regions left free (names, or tags as text).
    pub free: &'a [String],
    /// The height g, evaluated at a boundary vertex with the tag of a fixed boundary edge
    /// through it (the average over those edges where they differ).
    pub height: &'a dyn Coefficient,
}

/// One body's data: surface, stiffness (with rigid regions), foundation matrix, sampling.
#[derive(Clone, Copy)]
pub struct BodyData<'a> {
    /// The body's surface.
    pub shape: &'a dyn Coefficient,
    /// Its stiffness.
    pub stiffness: BodyStiffness<'a>,
    /// Region tags where it is rigid while elastic elsewhere.
    pub rigid_regions: &'a [u32],
    /// Consistent or lumped.
    pub foundation: Foundation,
    /// How its surface is sampled.
    pub sampling: Sampling,
}

/// The error for a bad value `v` of `name` at `p`.
pub(super) fn bad_value(name: &str, v: f64, p: [f64; 2]) -> Error {
    let what = if v.is_nan() {
        "is NaN".to_string()
    } else if !v.is_finite() {
        format!("is infinite ({v})")
    } else {
        format!("is negative ({v})")
    };
    Error::Data(format!("{name} {what} at ({}, {})", p[0], p[1]))
}
