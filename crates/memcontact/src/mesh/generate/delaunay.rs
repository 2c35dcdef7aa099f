//! Constrained Delaunay refinement (spade) shared by the disc and the polygon.

use crate::error::{Error, Result};
use crate::mesh::{Mesh, Point};
use rayon::prelude::*;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};
use std::collections::BTreeMap;

/// Tags every boundary edge of `mesh` with `tag_of(midpoint)` and names the tags.
pub(super) fn tag_boundary(
    mesh: Mesh,
    tag_of: impl Fn(Point) -> u32,
    names: BTreeMap<u32, String>,
) -> Result<Mesh> {
    let edges = mesh.boundary_edges();
    let tags = edges
        .iter()
        .map(|&[a, b]| {
            let (p, q) = (mesh.points[a as usize], mesh.points[b as usize]);
            tag_of([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])])
        })
        .collect();
    mesh.with_boundary_regions(edges, tags, names)
}

/// Puts every triangle in counter-clockwise order (spade's faces are, but be sure).
pub(super) fn orient_ccw(points: &[Point], triangles: &mut [[u32; 3]]) {
    triangles.par_iter_mut().for_each(|t| {
        if crate::mesh::signed_area(points, t) < 0.0 {
            t.swap(1, 2);
        }
    });
}

pub(super) type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Inserts `vertices` and the constraint `segments` into a constrained Delaunay
/// triangulation and refines it with the angle limit `min_angle` (degrees) and the area
/// bound `size²·√3/4`. `exclude_outer` skips faces outside the constraints (by parity).
/// `estimate` (triangles expected) sizes the vertex budget.
pub(super) fn refined_cdt(
    vertices: &[Point],
    segments: &[[usize; 2]],
    size: f64,
    min_angle: f64,
    exclude_outer: bool,
    estimate: f64,
    what: &str,
) -> Result<Cdt> {
    let mut cdt = Cdt::new();
    let mut handles = Vec::with_capacity(vertices.len());
    for (i, p) in vertices.iter().enumerate() {
        let h = cdt.insert(Point2::new(p[0], p[1])).map_err(|e| {
            Error::Mesh(format!(
                "{what}: vertex {i} at ({}, {}) cannot be inserted: {e:?}",
                p[0], p[1]
            ))
        })?;
        handles.push(h);
    }
    for s in segments {
        let (a, b) = (handles[s[0]], handles[s[1]]);
        if a != b {
            cdt.add_constraint_and_split(a, b, |p| p);
        }
    }
    let budget = (4.0 * estimate) as usize + 10 * vertices.len() + 1000;
    let params = RefinementParameters::<f64>::new()
        .with_angle_limit(AngleLimit::from_deg(min_angle))
        .with_max_allowed_area(size * size * 3f64.sqrt() / 4.0)
        .with_max_additional_vertices(budget)
        .exclude_outer_faces(exclude_outer);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| cdt.refine(params)))
        .map_err(|_| {
            Error::Mesh(format!(
                "{what}: Delaunay refinement failed (loss of precision); \
                 check the geometry for nearly coincident vertices or edges"
            ))
        })?;
    if !result.refinement_complete {
        return Err(Error::Mesh(format!(
            "{what}: Delaunay refinement did not finish within {budget} added vertices \
             (min_angle {min_angle}°, size {size}); lower min_angle or check for very small \
             input angles"
        )));
    }
    Ok(cdt)
}
