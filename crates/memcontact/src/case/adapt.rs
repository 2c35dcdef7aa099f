//! `[adapt]`: adaptive refinement (docs/case-file/adapt.md; the theory:
//! docs/theory.md#adaptivity): the loop solve → estimate → mark → refine → solve, its
//! stopping rules and its marking.

use crate::error::Invalid;
use serde::{Deserialize, Serialize};

/// The settings of the adaptive loop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptSpec {
    /// Stop before a step whose mesh would have more vertices than this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_vertices: Option<usize>,
    /// The most steps solved (the start mesh's solve is step 0).
    #[serde(default = "default_steps")]
    pub steps: usize,
    /// Dörfler's fraction θ ∈ (0, 1]: the fewest triangles whose squared indicators add
    /// up to θ of the total are refined.
    #[serde(default = "default_theta")]
    pub theta: f64,
    /// The triangles holding both contact and non-contact vertices, and this many rings of
    /// neighbours, are refined besides (0: none); at most as many as the Dörfler set holds,
    /// the largest first.
    #[serde(default = "default_rings")]
    pub free_boundary_rings: usize,
    /// Stop once the estimator η is at most this (energy-norm units).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
}

fn default_steps() -> usize {
    20
}

fn default_theta() -> f64 {
    0.5
}

fn default_rings() -> usize {
    1
}

impl Default for AdaptSpec {
    fn default() -> AdaptSpec {
        AdaptSpec {
            max_vertices: None,
            steps: default_steps(),
            theta: default_theta(),
            free_boundary_rings: default_rings(),
            tolerance: None,
        }
    }
}

impl AdaptSpec {
    /// Checks the values (the start mesh's size against `max_vertices` is checked when the
    /// mesh is built).
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        if !(self.theta > 0.0 && self.theta <= 1.0) {
            return Err(Invalid::new(
                "adapt.theta",
                format!("must be in (0, 1], got {}", self.theta),
            ));
        }
        if self.steps < 1 {
            return Err(Invalid::new("adapt.steps", "must be at least 1"));
        }
        if self.max_vertices == Some(0) {
            return Err(Invalid::new("adapt.max_vertices", "must be at least 1"));
        }
        if let Some(t) = self.tolerance {
            if !(t.is_finite() && t > 0.0) {
                return Err(Invalid::new(
                    "adapt.tolerance",
                    format!("must be a finite number > 0, got {t}"),
                ));
            }
        }
        Ok(())
    }
}
