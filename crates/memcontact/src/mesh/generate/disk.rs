//! The disc: boundary vertices on the circle, interior by Delaunay refinement.

use super::delaunay::{orient_ccw, refined_cdt, tag_boundary};
use super::size::{estimated_triangles, uniform_levels, MAX_TRIANGLES};
use crate::error::{Error, Result};
use crate::mesh::refine::Hierarchy;
use crate::mesh::{Circle, Mesh, Point};
use spade::Triangulation;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// An unstructured, shape-regular mesh of the disc of `center` and `radius` with element
/// size about `size`: `⌈2πR / size⌉` boundary vertices exactly on the circle, interior from
/// constrained Delaunay refinement (30° angle limit, area bound `size²·√3/4`). Boundary
/// vertices the refinement adds on chords are projected onto the circle, so every boundary
/// vertex lies on it; `mesh.curve` records the circle for later refinement.
pub fn disk(center: Point, radius: f64, size: f64) -> Result<Mesh> {
    let estimate = disk_estimate(center, radius, size)?;
    let n = ((2.0 * PI * radius / size).ceil() as usize).max(6);
    let on_circle: Vec<Point> = (0..n)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / n as f64;
            [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
        })
        .collect();
    let segments: Vec<[usize; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
    let cdt = refined_cdt(&on_circle, &segments, size, 30.0, true, estimate, "disk")?;
    let mut points: Vec<Point> = cdt
        .vertices()
        .map(|v| [v.position().x, v.position().y])
        .collect();
    // Steiner points that refinement put on boundary chords: move them onto the circle.
    let circle = Circle { center, radius };
    for e in cdt.convex_hull() {
        let v = e.from().fix().index();
        if v >= n {
            points[v] = circle.project(points[v]);
        }
    }
    let mut triangles: Vec<[u32; 3]> = cdt
        .inner_faces()
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    orient_ccw(&points, &mut triangles);
    if let Some(k) = triangles
        .iter()
        .position(|t| crate::mesh::signed_area(&points, t) <= 0.0)
    {
        return Err(Error::Mesh(format!(
            "disk: triangle {k} turned over when its boundary vertices were moved onto the \
             circle; choose a smaller size (got {size} for radius {radius})"
        )));
    }
    let mut mesh = Mesh::new(points, triangles, vec![], BTreeMap::new())?;
    mesh.curve = Some(circle);
    tag_boundary(mesh, |_| 1, BTreeMap::from([(1, "outer".to_string())]))
}

/// Checks the disc's data and returns the triangle count its mesh will have, refused
/// above [`MAX_TRIANGLES`].
pub(super) fn disk_estimate(center: Point, radius: f64, size: f64) -> Result<f64> {
    if !center[0].is_finite() || !center[1].is_finite() {
        return Err(Error::Mesh(format!(
            "disk: centre ({}, {}) is not finite",
            center[0], center[1]
        )));
    }
    if !radius.is_finite() || radius <= 0.0 {
        return Err(Error::Mesh(format!(
            "disk: radius must be positive and finite, got {radius}"
        )));
    }
    if !size.is_finite() || size <= 0.0 {
        return Err(Error::Mesh(format!(
            "disk: element size must be positive and finite, got {size}"
        )));
    }
    let estimate = estimated_triangles(PI * radius * radius, size);
    if estimate > MAX_TRIANGLES {
        return Err(Error::Mesh(format!(
            "disk: size {size} is too small for radius {radius}: about {estimate:.2e} \
             triangles, more than the limit {MAX_TRIANGLES:.0e}"
        )));
    }
    Ok(estimate)
}

/// The disc of [`disk`] as a hierarchy: with more than [`super::DELAUNAY_TRIANGLES`] triangles
/// expected, the disc meshed at `size · 2ᵏ` and refined uniformly `k` times (new boundary
/// vertices on the circle), so that the finest level has element size about `size` and the
/// coarse mesh's angles; otherwise the single mesh of [`disk`].
pub fn disk_levels(center: Point, radius: f64, size: f64) -> Result<Hierarchy> {
    let k = uniform_levels(disk_estimate(center, radius, size)?);
    let coarse = disk(center, radius, size * f64::from(1u32 << k))?;
    Ok(Hierarchy::refined(coarse, k as usize))
}
