//! Influence maps: the derivative of an output in the stiffness at every vertex, "where
//! the soil stiffness matters" (docs/theory.md#adjoint). The stiffness is perturbed
//! by a hat function ψ_v of the vertex (over the body's elastic triangles): the consistent
//! L changes by `∫ ψ_v gᵢ gⱼ`, the lumped l by `∫ ψ_v gᵢ`. Then
//!
//! * the energy (envelope theorem): `dJ/dh_v = ½ ∫ ψ_v p_h²` (lumped `½ Σᵢ Mᵥᵢ pᵢ²`);
//! * an output with adjoint λ: `dQ/dh_v = −∫ ψ_v λ_h p_h` (lumped `−Σᵢ Mᵥᵢ λᵢ pᵢ`), λ_h and
//!   p_h the P1 functions of λ and p on the penetrating vertices;
//!
//! and for the body below the same with q = (φ_low − U)⁺ and the opposite sign for the
//! outputs (its force pushes up). Summed over the vertices, the map of a uniform
//! stiffness is the derivative in it: `Σ_v dQ/dh_v = dQ/dh`.

use crate::mesh::Mesh;
use crate::model::{Foundation, Model};

/// `scale · ∫ ψ_v x_h y_h` (consistent) or `scale · Σᵢ Mᵥᵢ xᵢ yᵢ` (lumped) at every vertex
/// v, over the triangles whose region is not in `rigid`; `x`, `y` over the unknowns (the
/// fixed vertices count as 0).
pub fn vertex_map(
    mesh: &Mesh,
    model: &Model,
    foundation: Foundation,
    rigid: &[u32],
    x: &[f64],
    y: &[f64],
    scale: f64,
) -> Vec<f64> {
    let nv = mesh.n_vertices();
    let mut out = vec![0.0; nv];
    let at = |v: u32, z: &[f64]| model.dofs.of(v as usize).map_or(0.0, |i| z[i as usize]);
    for (k, t) in mesh.triangles.iter().enumerate() {
        if rigid.contains(&mesh.regions[k]) {
            continue;
        }
        let xs = t.map(|v| at(v, x));
        let ys = t.map(|v| at(v, y));
        if xs.iter().all(|&v| v == 0.0) || ys.iter().all(|&v| v == 0.0) {
            continue;
        }
        let area = mesh.area(k);
        for a in 0..3 {
            let mut s = 0.0;
            match foundation {
                Foundation::Consistent => {
                    for (b, &xb) in xs.iter().enumerate() {
                        for (c, &yc) in ys.iter().enumerate() {
                            s += xb * yc * triple(a, b, c);
                        }
                    }
                }
                Foundation::Lumped => {
                    for b in 0..3 {
                        let m = if a == b { 1.0 / 6.0 } else { 1.0 / 12.0 };
                        s += m * xs[b] * ys[b];
                    }
                }
            }
            out[t[a] as usize] += scale * area * s;
        }
    }
    out
}

/// `∫_T λ_a λ_b λ_c / |T|`: 1/10 for three equal indices, 1/30 for two, 1/60 for none.
fn triple(a: usize, b: usize, c: usize) -> f64 {
    match (a == b, b == c, a == c) {
        (true, true, _) => 1.0 / 10.0,
        (false, false, false) => 1.0 / 60.0,
        _ => 1.0 / 30.0,
    }
}
