//! A posteriori error indicators of a discrete solution (docs/theory.md#estimators), one
//! per triangle, in the units of the energy norm `‖v‖²_a = t ∫ |∇v|²` squared:
//!
//! `η_T² = (1/t) [ h_T² ‖f − ρ_h‖²_T + ½ Σ_{E ⊂ ∂T inside} h_E ‖[t ∂u_h/∂n]‖²_E
//!          + Σ_{E ⊂ ∂T free} h_E ‖t ∂u_h/∂n‖²_E ] + ∫_T ρ_rigid⁺ |φ − u_h|`.
//!
//! `ρ_h` is the density of the bodies' reaction on the membrane: the P1 function whose
//! value at an unknown is its nodal reaction `D_i − (SU)_i` (the contact forces of 2e, net
//! of both bodies) divided by `∫ g_i`. With it the element residual is that of the linear
//! problem `−t Δu = f − ρ` the discrete solution solves, whatever the bodies are: elastic
//! (consistent or lumped: the foundation force exactly as the solve has it), rigid, rigid in
//! some regions, or two of them. For an elastic body this is the residual estimator of the
//! monotone semilinear problem (Verfürth's framework) with the foundation term in the form
//! the solve uses; where a body is rigid it is the estimator of Braess (2005) and Veeser
//! (2001): the linear residual with the discrete contact force, plus the complementarity
//! term `∫ ρ⁺ |φ − u_h|` of the rigid contact (zero at the vertices, where `U = φ`, and the
//! interpolation error of φ between them). Free edges (the natural condition
//! `t ∂u/∂n = 0`) carry their flux; held edges carry none.

use crate::error::{Error, Result};
use crate::fem::Element;
use crate::field::Coefficient;
use crate::mesh::{Mesh, VertexTriangles};
use crate::model::Model;
use crate::quadrature::{map, DEGREE5};
use rayon::prelude::*;

/// The indicators of a solution.
#[derive(Debug, Clone)]
pub struct Indicators {
    /// `η_T²` for every triangle of the mesh, in its order.
    pub eta2: Vec<f64>,
    /// `η = (Σ η_T²)^½`.
    #[cfg_attr(not(test), allow(dead_code))]
    pub total: f64,
}

/// The indicators of the solution `u` (over the unknowns) of `model` on `mesh`, with the
/// load `f` and the obstacle's surface `shape` (for the rigid complementarity term) as the
/// case gives them, and `free_edges` the boundary edges with the natural condition.
/// Errors: a non-finite indicator (data that overflow), naming the triangle.
pub fn estimate(
    mesh: &Mesh,
    model: &Model,
    load: &dyn Coefficient,
    shape: &dyn Coefficient,
    free_edges: &[[u32; 2]],
    u: &[f64],
) -> Result<Indicators> {
    let t = model.tension;
    let nv = mesh.n_vertices();
    let uv = model.to_vertices(u);
    // The reaction density at every vertex (0 at held vertices), and whether a rigid body
    // holds the vertex.
    let residual = model.residual(u);
    let mut mass = vec![0.0; nv];
    for (k, tri) in mesh.triangles.iter().enumerate() {
        let a = mesh.area(k) / 3.0;
        for &v in tri {
            mass[v as usize] += a;
        }
    }
    let mut rho = vec![0.0; nv];
    let mut rigid = vec![false; nv];
    for (i, &v) in model.dofs.vertex.iter().enumerate() {
        let v = v as usize;
        rho[v] = -residual[i] / mass[v];
        rigid[v] = model.rigid_at(i) || model.lower.as_ref().is_some_and(|b| b.rigid_at(i));
    }
    let grads: Vec<[f64; 2]> = (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(4096)
        .map(|k| {
            let e = Element::of(mesh, k);
            let t = mesh.triangles[k];
            let mut g = [0.0; 2];
            for (a, &v) in t.iter().enumerate() {
                g[0] += uv[v as usize] * e.grad[a][0];
                g[1] += uv[v as usize] * e.grad[a][1];
            }
            g
        })
        .collect();
    // Element residuals and the rigid complementarity term.
    let mut eta2: Vec<f64> = (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| {
            let tri = mesh.triangles[k];
            let c = mesh.corners(k);
            let region = mesh.regions[k];
            let area = mesh.area(k);
            let h = crate::mesh::dist(c[0], c[1])
                .max(crate::mesh::dist(c[1], c[2]))
                .max(crate::mesh::dist(c[2], c[0]));
            let (mut r2, mut comp) = (0.0, 0.0);
            let any_rigid = tri
                .iter()
                .any(|&v| rigid[v as usize] && rho[v as usize] > 0.0);
            let points = DEGREE5.map(|(b, _)| map(&c, &b));
            let mut f = [0.0; DEGREE5.len()];
            load.at_points(&points, region, &mut f);
            for ((b, w), (p, f)) in DEGREE5.into_iter().zip(points.into_iter().zip(f)) {
                let rho_p: f64 = (0..3).map(|a| b[a] * rho[tri[a] as usize]).sum();
                let r = f - rho_p;
                r2 += w * r * r;
                if any_rigid {
                    let up: f64 = (0..3)
                        .map(|a| {
                            let v = tri[a] as usize;
                            b[a] * if rigid[v] { rho[v].max(0.0) } else { 0.0 }
                        })
                        .sum();
                    let u_p: f64 = (0..3).map(|a| b[a] * uv[tri[a] as usize]).sum();
                    comp += w * up * (shape.at(p, region) - u_p).abs();
                }
            }
            h * h * r2 * area / t + comp * area
        })
        .collect();
    // Edge terms: the jump of the flux across every inside edge, half to each side; the
    // flux itself across free edges.
    let adj = VertexTriangles::new(mesh);
    let free: std::collections::HashSet<(u32, u32)> = free_edges
        .iter()
        .map(|&[a, b]| (a.min(b), a.max(b)))
        .collect();
    let edge_terms: Vec<f64> = (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| {
            let tri = mesh.triangles[k];
            let mut sum = 0.0;
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let (pa, pb) = (mesh.points[a as usize], mesh.points[b as usize]);
                let len = crate::mesh::dist(pa, pb);
                // The outward normal of a counter-clockwise triangle's edge a → b.
                let n = [(pb[1] - pa[1]) / len, -(pb[0] - pa[0]) / len];
                let flux = |g: [f64; 2]| t * (g[0] * n[0] + g[1] * n[1]);
                let other = adj
                    .of(a as usize)
                    .iter()
                    .copied()
                    .find(|&o| o as usize != k && mesh.triangles[o as usize].contains(&b));
                match other {
                    Some(o) => {
                        let jump = flux(grads[k]) - flux(grads[o as usize]);
                        sum += 0.5 * len * len * jump * jump;
                    }
                    None if free.contains(&(a.min(b), a.max(b))) => {
                        let f = flux(grads[k]);
                        sum += len * len * f * f;
                    }
                    None => {}
                }
            }
            sum / t
        })
        .collect();
    for (e, s) in eta2.iter_mut().zip(&edge_terms) {
        *e += s;
    }
    if let Some(k) = eta2.iter().position(|e| !e.is_finite()) {
        let c = mesh.corners(k);
        return Err(Error::Data(format!(
            "the error indicator of triangle {k} (at ({}, {})) is {}: the data overflow \
             double precision there",
            c[0][0], c[0][1], eta2[k]
        )));
    }
    let total = eta2.iter().sum::<f64>().sqrt();
    Ok(Indicators { eta2, total })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FnCoefficient;
    use crate::mesh::generate::{rectangle, Diagonal, RectangleSpec};
    use crate::model::{BodyStiffness, Extensions, Foundation, ProblemData, Sampling};

    fn grid(n: usize) -> Mesh {
        rectangle(&RectangleSpec {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            nx: n,
            ny: n,
            diagonal: Diagonal::Alternate,
        })
        .unwrap()
        .finest()
        .clone()
    }

    /// Tension `t`, no load, no body (h = 0 under a far obstacle).
    fn unloaded(t: f64) -> ProblemData<'static> {
        ProblemData {
            tension: t,
            load: &0.0,
            shape: &10.0,
            stiffness: BodyStiffness::Elastic(&0.0),
            foundation: Foundation::Consistent,
            sampling: Sampling::Nodal,
        }
    }

    /// A P1 problem solved exactly: u = 1 + 2x − y (its heights on the boundary), no load,
    /// no body. The indicators vanish to rounding.
    #[test]
    fn indicators_vanish_for_a_solution_in_the_p1_space() {
        let mesh = grid(12);
        let g = FnCoefficient(|p: [f64; 2]| 1.0 + 2.0 * p[0] - p[1]);
        let data = unloaded(2.0);
        let free: Vec<String> = Vec::new();
        let ext = Extensions {
            boundary: Some(crate::model::BoundaryData {
                free: &free,
                height: &g,
            }),
            ..Extensions::default()
        };
        let model = Model::assemble_with(&mesh, &data, &ext).unwrap();
        let u = crate::solve::linear::solve(&model, &crate::solve::Settings::default())
            .unwrap()
            .u;
        let ind = estimate(&mesh, &model, &0.0, &10.0, &[], &u).unwrap();
        assert!(ind.total < 1e-12, "{}", ind.total);
        // A load breaks it: the indicator sees the residual.
        let loaded = ProblemData { load: &1.0, ..data };
        let model = Model::assemble_with(&mesh, &loaded, &ext).unwrap();
        let u = crate::solve::linear::solve(&model, &crate::solve::Settings::default())
            .unwrap()
            .u;
        let ind = estimate(&mesh, &model, &1.0, &10.0, &[], &u).unwrap();
        assert!(ind.total > 1e-3, "{}", ind.total);
    }

    /// The free-edge term is exactly `Σ h_E ‖t ∂u/∂n‖²_E / t` over the free edges: for the
    /// P1 function u = 1 + 2x − y with the top side free (∂u/∂n = −1 there), listing the
    /// top edges as free adds `t Σ h_E² = t/n` to η², whatever else the indicators hold.
    #[test]
    fn the_free_edge_term_is_the_flux_through_the_free_edges() {
        let n = 10;
        let mesh = grid(n);
        let g = FnCoefficient(|p: [f64; 2]| 1.0 + 2.0 * p[0] - p[1]);
        let t = 3.0;
        let data = unloaded(t);
        let free = vec!["top".to_string()];
        let ext = Extensions {
            boundary: Some(crate::model::BoundaryData {
                free: &free,
                height: &g,
            }),
            ..Extensions::default()
        };
        let model = Model::assemble_with(&mesh, &data, &ext).unwrap();
        let u: Vec<f64> = model
            .dofs
            .vertex
            .iter()
            .map(|&v| g.at(mesh.points[v as usize], 0))
            .collect();
        let top: Vec<[u32; 2]> = (0..mesh.n_triangles())
            .flat_map(|k| {
                let tri = mesh.triangles[k];
                (0..3).map(move |e| [tri[e], tri[(e + 1) % 3]])
            })
            .filter(|&[a, b]| {
                mesh.points[a as usize][1] == 1.0 && mesh.points[b as usize][1] == 1.0
            })
            .collect();
        assert_eq!(top.len(), n);
        let without = estimate(&mesh, &model, &0.0, &10.0, &[], &u).unwrap();
        let with = estimate(&mesh, &model, &0.0, &10.0, &top, &u).unwrap();
        let added = with.total.powi(2) - without.total.powi(2);
        let expected = t / n as f64;
        assert!((added - expected).abs() < 1e-12, "{added} vs {expected}");
    }

    /// Indicators that overflow are an error naming the triangle, not a silent infinity
    /// (the adaptive loop then stops, keeping the step before).
    #[test]
    fn an_overflowing_indicator_is_an_error() {
        let mesh = grid(4);
        let data = unloaded(1.0);
        let model = Model::assemble_with(&mesh, &data, &Extensions::default()).unwrap();
        let mut u = vec![0.0; model.n()];
        u[0] = 1e200;
        let e = estimate(&mesh, &model, &0.0, &10.0, &[], &u).unwrap_err();
        assert!(e.to_string().contains("triangle"), "{e}");
    }
}
