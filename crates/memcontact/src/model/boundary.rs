//! The heights g on the fixed part of the boundary (docs/theory.md#boundary-data).

use super::data::bad_value;
use super::data::Extensions;
use crate::error::Result;
use crate::fem::VertexTriangles;
use crate::field::Coefficient;
use crate::mesh::boundary::FixedBoundary;
use crate::mesh::Mesh;

/// Which vertices are fixed and their heights g (0 elsewhere), as the assembly with `ext`
/// takes them (docs/theory.md#boundary-data).
pub fn fixed_heights(
    mesh: &Mesh,
    adj: &VertexTriangles,
    ext: &Extensions,
) -> Result<(Vec<bool>, Vec<f64>)> {
    fixed_heights_on(mesh, adj, &mesh.boundary_vertices_with(adj), ext)
}

/// [`fixed_heights`] given the boundary vertices of the mesh.
pub fn fixed_heights_on(
    mesh: &Mesh,
    adj: &VertexTriangles,
    boundary: &[bool],
    ext: &Extensions,
) -> Result<(Vec<bool>, Vec<f64>)> {
    match &ext.boundary {
        Some(b) => {
            let fixed = FixedBoundary::new(mesh, adj, b.free)?;
            let g = boundary_heights(mesh, &fixed, b.height)?;
            Ok((fixed.fixed, g))
        }
        None => Ok((boundary.to_vec(), vec![0.0; mesh.n_vertices()])),
    }
}

/// The heights g at the fixed vertices (docs/theory.md#boundary-data), 0 elsewhere: at a
/// vertex, g with the tag of each fixed boundary edge through it, averaged over those edges
/// (they differ only where a table gives two sides different heights). A height that is not
/// finite is an error naming the point.
pub(super) fn boundary_heights(
    mesh: &Mesh,
    fixed: &FixedBoundary,
    height: &dyn Coefficient,
) -> Result<Vec<f64>> {
    let nv = mesh.n_vertices();
    let mut sum = vec![0.0; nv];
    let mut count = vec![0u32; nv];
    for &([a, b], tag) in &fixed.edges {
        for v in [a as usize, b as usize] {
            let g = height
                .on_region(tag)
                .unwrap_or_else(|| height.at(mesh.points[v], tag));
            sum[v] += g;
            count[v] += 1;
        }
    }
    let g: Vec<f64> = sum
        .iter()
        .zip(&count)
        .map(|(&s, &c)| if c == 0 { 0.0 } else { s / c as f64 })
        .collect();
    if let Some(v) = g.iter().position(|x| !x.is_finite()) {
        return Err(bad_value("boundary.height g", g[v], mesh.points[v]));
    }
    Ok(g)
}
