//! Physical results derived from a solution (SPEC §3, "Physical outputs"): deflection,
//! sampled obstacle, penetration, contact pressure, nodal contact forces X₁, vertex states,
//! and the totals an engineer checks (load, reaction, contact area, largest deflection).

use crate::mesh::Mesh;
use crate::model::Model;
use crate::solve::Solution;

/// Fields over all mesh vertices (boundary vertices included, u = 0 there).
#[derive(Debug, Clone)]
pub struct NodalFields {
    /// Deflection u.
    pub u: Vec<f64>,
    /// Sampled obstacle φ_n.
    pub phi: Vec<f64>,
    /// Penetration (u − φ)⁺ (zero where the obstacle cannot touch).
    pub penetration: Vec<f64>,
    /// Contact pressure h (u − φ)⁺; for the rigid obstacle, the nodal contact force per
    /// unit of nodal area X₁ᵢ / (|Qᵢ|/3).
    pub pressure: Vec<f64>,
    /// Nodal contact force X₁ = D − SU on M (zero elsewhere and on the boundary).
    pub contact_force: Vec<f64>,
    /// −1 clear, 0 touching (U = φ), 1 penetrating.
    pub state: Vec<i8>,
    /// Where the body lies against the membrane: h > 0 around the vertex, or rigid.
    pub covered: Vec<bool>,
}

/// Scalar results.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Totals {
    /// Vertices in contact (touching or penetrating).
    pub contact_vertices: usize,
    /// Vertices exactly touching (U = φ).
    pub touching_vertices: usize,
    /// Vertices penetrating (U > φ).
    pub penetrating_vertices: usize,
    /// Unknowns clear of the obstacle.
    pub clear_vertices: usize,
    /// Area of the contact zone: the nodal areas |Qᵢ|/3 of the vertices in contact.
    pub contact_area: f64,
    /// ∫_{Ω_n} f.
    pub total_load: f64,
    /// Σ X₁: the total force the obstacle exerts (positive pushing down, i.e. in −x₃).
    pub total_contact_force: f64,
    /// The largest |u|.
    pub max_deflection: f64,
    /// Area where the body lies under the membrane but the membrane is clear of it
    /// (nodal areas of the covered unknowns with U < φ).
    pub liftoff_area: f64,
    /// The largest contact pressure.
    pub max_pressure: f64,
    /// The smallest u.
    pub min_u: f64,
    /// The largest u.
    pub max_u: f64,
}

/// Computes the vertex fields and totals of `solution`.
pub fn derive(mesh: &Mesh, model: &Model, solution: &Solution) -> (NodalFields, Totals) {
    derive_from(mesh, model, &solution.u)
}

/// Computes the vertex fields and totals of the iterate `u` (over the unknowns).
pub fn derive_from(mesh: &Mesh, model: &Model, u_dofs: &[f64]) -> (NodalFields, Totals) {
    let nv = mesh.n_vertices();
    let dofs = &model.dofs;
    let u = model.to_vertices(u_dofs);
    let r = model.residual(u_dofs);
    let x1: Vec<f64> = r
        .iter()
        .zip(&model.can_touch)
        .map(|(ri, &c)| if c { -ri } else { 0.0 })
        .collect();
    let contact_force = dofs.to_vertices(&x1, 0.0);
    let states = model.states(u_dofs);
    let mut state = vec![-1i8; nv];
    let mut penetration = vec![0.0; nv];
    for (i, &v) in dofs.vertex.iter().enumerate() {
        state[v as usize] = states[i];
        if model.can_touch[i] {
            penetration[v as usize] = (u_dofs[i] - model.phi[i]).max(0.0);
        }
    }
    // Nodal areas |Q_i| / 3.
    let mut nodal_area = vec![0.0; nv];
    for k in 0..mesh.n_triangles() {
        let a = mesh.area(k) / 3.0;
        for &v in &mesh.triangles[k] {
            nodal_area[v as usize] += a;
        }
    }
    let pressure: Vec<f64> = (0..nv)
        .map(|v| {
            if model.is_rigid() {
                if nodal_area[v] > 0.0 {
                    contact_force[v] / nodal_area[v]
                } else {
                    0.0
                }
            } else {
                model.h_vertices[v] * penetration[v]
            }
        })
        .collect();
    let count = |s: i8| states.iter().filter(|&&x| x == s).count();
    // (An empty f64 sum is −0.)
    let contact_area = 0.0
        + (0..nv)
            .filter(|&v| state[v] >= 0)
            .map(|v| nodal_area[v])
            .sum::<f64>();
    let covered: Vec<bool> = model.h_vertices.iter().map(|&h| h > 0.0).collect();
    let liftoff_area = 0.0
        + (0..nv)
            .filter(|&v| covered[v] && state[v] < 0 && !mesh_boundary(dofs, v))
            .map(|v| nodal_area[v])
            .sum::<f64>();
    let max_pressure = pressure.iter().cloned().fold(0.0f64, f64::max);
    let max_u = u.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min_u = u.iter().cloned().fold(f64::INFINITY, f64::min);
    let totals = Totals {
        liftoff_area,
        max_pressure,
        contact_vertices: count(0) + count(1),
        touching_vertices: count(0),
        penetrating_vertices: count(1),
        clear_vertices: count(-1),
        contact_area,
        total_load: model.total_load,
        total_contact_force: x1.iter().sum(),
        max_deflection: max_u.abs().max(min_u.abs()),
        min_u,
        max_u,
    };
    (
        NodalFields {
            u,
            phi: model.phi_vertices.clone(),
            penetration,
            pressure,
            contact_force,
            state,
            covered,
        },
        totals,
    )
}

/// `true` for a vertex that carries no unknown (on the fixed boundary).
fn mesh_boundary(dofs: &crate::mesh::DofMap, v: usize) -> bool {
    dofs.dof[v].is_none()
}
