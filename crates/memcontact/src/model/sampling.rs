//! The sampled obstacle φₙ: nodal values, or the paper's mollified sampling
//! φₙ = rₙ(J_ε * φ) with its radius εₙ.

use crate::fem::VertexTriangles;
use crate::field::Coefficient;
use crate::mesh::Mesh;
use crate::quadrature::gauss_legendre;
use rayon::prelude::*;

/// A coefficient at every vertex: the average over the triangles around it of its value
/// there with that triangle's region (so region tables are averaged on interfaces).
pub(super) fn vertex_average(mesh: &Mesh, adj: &VertexTriangles, c: &dyn Coefficient) -> Vec<f64> {
    (0..mesh.n_vertices())
        .into_par_iter()
        .with_min_len(1024)
        .map(|v| {
            let tris = adj.of(v);
            let first = mesh.regions[tris[0] as usize];
            if tris.iter().all(|&k| mesh.regions[k as usize] == first) {
                return c.at(mesh.points[v], first);
            }
            tris.iter()
                .map(|&k| c.at(mesh.points[v], mesh.regions[k as usize]))
                .sum::<f64>()
                / tris.len() as f64
        })
        .collect()
}

/// The paper's mollifier radius `ε_n = max{l_n^¼, meas(Ω∖Ω_n)^¼, meas(Ω'_n)^¼}`, with
/// Ω'_n the triangles having a vertex on ∂Ω_n and Ω∖Ω_n the gap to a curved boundary.
pub fn paper_epsilon(mesh: &Mesh) -> f64 {
    let q = mesh.quality();
    let boundary = mesh.boundary_vertices();
    let boundary_layer: f64 = (0..mesh.n_triangles())
        .filter(|&k| mesh.triangles[k].iter().any(|&v| boundary[v as usize]))
        .map(|k| mesh.area(k))
        .sum();
    let gap = mesh
        .curve
        .map(|c| (std::f64::consts::PI * c.radius * c.radius - q.area).max(0.0))
        .unwrap_or(0.0);
    q.l_n
        .powf(0.25)
        .max(gap.powf(0.25))
        .max(boundary_layer.powf(0.25))
}

/// `(J_ε * φ)(a_v)` at every vertex, with the standard mollifier
/// `J(x) ∝ exp(−1 / (1 − |x|²/ε²))` on the disc of radius ε. φ is evaluated as a function
/// on the plane (with the vertex's region for region tables); a polar Gauss rule
/// (16 radii × 32 angles), normalised with the same rule, keeps constants exact.
pub(super) fn mollify(
    mesh: &Mesh,
    adj: &VertexTriangles,
    phi: &dyn Coefficient,
    eps: f64,
) -> Vec<f64> {
    const NR: usize = 16;
    const NT: usize = 32;
    let (gx, gw) = gauss_legendre(NR);
    // Radial nodes on (0, 1) with the Jacobian r and the mollifier profile.
    let radial: Vec<(f64, f64)> = gx
        .iter()
        .zip(&gw)
        .map(|(&x, &w)| {
            let s = 0.5 * (x + 1.0);
            let prof = (-1.0 / (1.0 - s * s)).exp();
            (s, 0.5 * w * s * prof)
        })
        .collect();
    let norm: f64 = radial.iter().map(|r| r.1).sum::<f64>() * NT as f64;
    (0..mesh.n_vertices())
        .into_par_iter()
        .with_min_len(256)
        .map(|v| {
            let a = mesh.points[v];
            let region = mesh.regions[adj.of(v)[0] as usize];
            let mut acc = 0.0;
            for &(s, w) in &radial {
                for k in 0..NT {
                    let th = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / NT as f64;
                    let p = [a[0] + eps * s * th.cos(), a[1] + eps * s * th.sin()];
                    acc += w * phi.at(p, region);
                }
            }
            acc / norm
        })
        .collect()
}
