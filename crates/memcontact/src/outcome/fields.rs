//! Physical results derived from a solution (docs/theory.md#physical-outputs): deflection,
//! sampled obstacle, penetration, contact pressure, nodal contact forces X₁, vertex states,
//! and the totals an engineer checks (load, reaction, contact area, largest deflection).

use crate::mesh::{signed_area, Mesh};
use crate::model::Model;
use crate::solve::Solution;
use crate::sparse::{map_blocks, sum_blocks, zeroed};
use rayon::prelude::*;

/// Fields over all mesh vertices (u = g on the fixed boundary, 0 by default).
#[derive(Debug, Clone)]
pub struct NodalFields {
    /// Deflection u.
    pub u: Vec<f64>,
    /// Sampled obstacle φ_n.
    pub phi: Vec<f64>,
    /// Penetration (u − φ)⁺ (zero where the obstacle cannot touch).
    pub penetration: Vec<f64>,
    /// Contact pressure h (u − φ)⁺; where the obstacle is rigid, the nodal contact force
    /// per unit of nodal area X₁ᵢ / (|Qᵢ|/3).
    pub pressure: Vec<f64>,
    /// Nodal contact force of the obstacle X₁ (= D − SU on M without a body below; the
    /// obstacle's share of it with one), zero elsewhere and on the fixed boundary.
    pub contact_force: Vec<f64>,
    /// −1 clear, 0 touching (U = φ), 1 penetrating.
    pub state: Vec<i8>,
    /// Where the body lies against the membrane: h > 0 around the vertex, or rigid.
    pub covered: Vec<bool>,
    /// The body below's fields, when there is one.
    pub lower: Option<LowerFields>,
}

/// The body below's fields over all vertices (docs/theory.md#second-body).
#[derive(Debug, Clone)]
pub struct LowerFields {
    /// Its sampled surface φ_low.
    pub phi: Vec<f64>,
    /// Penetration (φ_low − u)⁺ (zero where it cannot touch).
    pub penetration: Vec<f64>,
    /// Contact pressure h_low (φ_low − u)⁺, or, where rigid, the nodal force per nodal
    /// area (positive pushing up).
    pub pressure: Vec<f64>,
    /// Its nodal contact force (pushing up).
    pub contact_force: Vec<f64>,
    /// −1 clear, 0 touching (U = φ_low), 1 penetrating (U < φ_low).
    pub state: Vec<i8>,
    /// Where it lies under the membrane (h_low > 0 around the vertex, or rigid).
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
    /// The body below's totals, when there is one.
    pub lower: Option<LowerTotals>,
}

/// The body below's totals (docs/theory.md#second-body).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct LowerTotals {
    /// Unknowns it can touch.
    pub can_touch_low_vertices: usize,
    /// Vertices in contact with it (touching or penetrating).
    pub contact_low_vertices: usize,
    /// Vertices exactly on it (U = φ_low).
    pub touching_low_vertices: usize,
    /// Vertices sunk into it (U < φ_low).
    pub penetrating_low_vertices: usize,
    /// Vertices in contact with both bodies at once (squeezed between them).
    pub squeezed_vertices: usize,
    /// Σ |Qᵢ|/3 over the vertices in contact with it.
    pub contact_area_low: f64,
    /// Its total force on the membrane (positive pushing up).
    pub total_contact_force_low: f64,
    /// Its largest contact pressure.
    pub max_pressure_low: f64,
    /// Area where it lies under the membrane but the membrane is clear of it.
    pub liftoff_area_low: f64,
}

/// Computes the vertex fields and totals of `solution`.
pub fn derive(mesh: &Mesh, model: &Model, solution: &Solution) -> (NodalFields, Totals) {
    derive_from(mesh, model, &solution.u)
}

/// Nodal areas |Q_i| / 3 of every vertex (summed over the triangles in mesh order; the
/// array is first written on all threads, the areas are not stored).
fn nodal_areas(mesh: &Mesh) -> Vec<f64> {
    let mut nodal_area = zeroed(mesh.n_vertices());
    for t in &mesh.triangles {
        let a = signed_area(&mesh.points, t) / 3.0;
        for &v in t {
            nodal_area[v as usize] += a;
        }
    }
    nodal_area
}

/// A body's pressure at every vertex: `h × penetration`, or where it is rigid (h = ∞),
/// its nodal force per nodal area.
fn pressure(
    h: &crate::model::VertexValues,
    penetration: &[f64],
    force: &[f64],
    nodal_area: &[f64],
) -> Vec<f64> {
    (0..h.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|v| {
            let hv = h.get(v);
            if hv.is_infinite() {
                if nodal_area[v] > 0.0 {
                    force[v] / nodal_area[v]
                } else {
                    0.0
                }
            } else {
                hv * penetration[v]
            }
        })
        .collect()
}

/// `value(i)` at the vertex of every unknown i, `boundary` elsewhere (in parallel).
fn gather<T: Copy + Send + Sync>(
    dofs: &crate::mesh::DofMap,
    value: impl Fn(usize) -> T + Sync,
    boundary: T,
) -> Vec<T> {
    dofs.gather(value, boundary)
}

/// The vertices where the stiffness `h` is positive (a body lies there).
fn covered_by(h: &crate::model::VertexValues) -> Vec<bool> {
    (0..h.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|v| h.get(v) > 0.0)
        .collect()
}

/// Computes the vertex fields and totals of the iterate `u` (over the unknowns).
pub fn derive_from(mesh: &Mesh, model: &Model, u_dofs: &[f64]) -> (NodalFields, Totals) {
    let nv = mesh.n_vertices();
    let dofs = &model.dofs;
    let u = model.to_vertices(u_dofs);
    let forces = crate::certificate::contact_forces(model, u_dofs);
    let contact_force = dofs.to_vertices(&forces.up, 0.0);
    let states = model.states(u_dofs);
    // Over the vertices, from the unknowns (boundary vertices: clear, no penetration).
    let state: Vec<i8> = gather(dofs, |i| states[i], -1);
    let penetration = gather(
        dofs,
        |i| {
            if model.can_touch[i] {
                (u_dofs[i] - model.phi[i]).max(0.0)
            } else {
                0.0
            }
        },
        0.0,
    );
    let nodal_area = nodal_areas(mesh);
    let pressure_up = pressure(&model.h_vertices, &penetration, &contact_force, &nodal_area);
    let count = |s: i8| states.par_iter().filter(|&&x| x == s).count();
    // Sums and extremes in fixed blocks, folded in block order (the same for any number of
    // threads). (An empty f64 sum is −0.)
    let area_where = |pick: &(dyn Fn(usize) -> bool + Sync)| {
        0.0 + sum_blocks(nv, |r| r.filter(|&v| pick(v)).map(|v| nodal_area[v]).sum())
    };
    let fold = |x: &[f64], init: f64, f: fn(f64, f64) -> f64| {
        let parts = map_blocks(x.len(), |r| x[r].iter().fold(init, |m, &v| f(m, v)));
        parts.into_iter().fold(init, f)
    };
    let sum = |x: &[f64]| sum_blocks(x.len(), |r| x[r].iter().sum());
    let contact_area = area_where(&|v| state[v] >= 0);
    let covered: Vec<bool> = covered_by(&model.h_vertices);
    let liftoff_area = area_where(&|v| covered[v] && state[v] < 0 && !mesh_boundary(dofs, v));
    let max_pressure = fold(&pressure_up, 0.0, f64::max);
    let max_u = fold(&u, f64::NEG_INFINITY, f64::max);
    let min_u = fold(&u, f64::INFINITY, f64::min);
    let (lower, lower_totals) = match &model.lower {
        Some(low) => {
            let states_low = model.lower_states(u_dofs);
            let state_low: Vec<i8> = gather(dofs, |i| states_low[i], -1);
            let penetration_low = gather(
                dofs,
                |i| {
                    if low.can_touch[i] {
                        (low.phi[i] - u_dofs[i]).max(0.0)
                    } else {
                        0.0
                    }
                },
                0.0,
            );
            let force_low = dofs.to_vertices(&forces.low, 0.0);
            let pressure_low = pressure(&low.h_vertices, &penetration_low, &force_low, &nodal_area);
            let covered_low: Vec<bool> = covered_by(&low.h_vertices);
            let count_low = |s: i8| states_low.iter().filter(|&&x| x == s).count();
            let totals = LowerTotals {
                can_touch_low_vertices: low.can_touch.iter().filter(|&&c| c).count(),
                contact_low_vertices: count_low(0) + count_low(1),
                touching_low_vertices: count_low(0),
                penetrating_low_vertices: count_low(1),
                squeezed_vertices: states
                    .iter()
                    .zip(&states_low)
                    .filter(|(&a, &b)| a >= 0 && b >= 0)
                    .count(),
                contact_area_low: area_where(&|v| state_low[v] >= 0),
                total_contact_force_low: sum(&forces.low),
                max_pressure_low: fold(&pressure_low, 0.0, f64::max),
                liftoff_area_low: area_where(&|v| {
                    covered_low[v] && state_low[v] < 0 && !mesh_boundary(dofs, v)
                }),
            };
            let fields = LowerFields {
                phi: low.phi_vertices(dofs),
                penetration: penetration_low,
                pressure: pressure_low,
                contact_force: force_low,
                state: state_low,
                covered: covered_low,
            };
            (Some(fields), Some(totals))
        }
        None => (None, None),
    };
    let totals = Totals {
        liftoff_area,
        max_pressure,
        contact_vertices: count(0) + count(1),
        touching_vertices: count(0),
        penetrating_vertices: count(1),
        clear_vertices: count(-1),
        contact_area,
        total_load: model.total_load,
        total_contact_force: sum(&forces.up),
        max_deflection: max_u.abs().max(min_u.abs()),
        min_u,
        max_u,
        lower: lower_totals,
    };
    (
        NodalFields {
            u,
            phi: model.phi_vertices(),
            penetration,
            pressure: pressure_up,
            contact_force,
            state,
            covered,
            lower,
        },
        totals,
    )
}

/// `true` for a vertex that carries no unknown (on the fixed boundary).
fn mesh_boundary(dofs: &crate::mesh::DofMap, v: usize) -> bool {
    dofs.is_fixed(v)
}
