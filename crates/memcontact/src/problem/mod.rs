//! The problem: a mesh and the data t, f, φ, h of the paper's Problem 1, with the
//! discretisation choices of its §2 and the data beyond it (docs/theory.md#extensions:
//! boundary heights, free edges, a body below). Pure data with serde defaults and one
//! `validate` step; it builds nothing (the discretisation does).

mod data;
mod mesh;

pub use data::{Boundary, Membrane, Obstacle, Problem, SamplingKind};
pub use mesh::{GivenMesh, MeshSource, MeshSpec, RegionPolygon, MAX_REFINE};
