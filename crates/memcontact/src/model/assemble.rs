//! Assembly of the model (docs/theory.md#discrete-model; docs/theory.md#extensions for
//! boundary heights, free edges, mixed and second bodies) with the data checks that only
//! assembly can make.

use super::body::{Body, FoundationMatrix, VertexValues};
use super::boundary::boundary_heights;
use super::checks::{check_centroids, check_vertices};
use super::data::{BodyData, BodyStiffness, Extensions, Foundation, ProblemData, Sampling};
use super::sampling::{mollify, paper_epsilon, vertex_average};
use super::system::Model;
use crate::error::{Error, Result};
use crate::fem::assemble_lift;
use crate::fem::{
    assemble_mass, assemble_stiffness_and_mass, unknowns_pattern, Loads, VertexTriangles,
};
use crate::field::Coefficient;
use crate::mesh::boundary::FixedBoundary;
use crate::mesh::{DofMap, Mesh};
use crate::sparse::Csr;
use rayon::prelude::*;
use std::sync::Arc;

impl Model {
    /// Assembles S, L, D, φₙ and M on `mesh` (docs/theory.md#discrete-model), validating
    /// the data: t > 0, h ≥ 0, every value finite.
    pub fn assemble(mesh: &Mesh, data: &ProblemData) -> Result<Model> {
        Model::assemble_with(mesh, data, &Extensions::default())
    }

    /// [`Model::assemble`] with the data beyond the paper's frame
    /// (docs/theory.md#extensions): boundary heights and free edges (the unknowns are then
    /// the vertices not on Γ_D and `d` carries the lifting `−S_fix G`), rigid regions of
    /// the obstacle, a body below. Refused here, before any solve: a boundary region that
    /// does not exist, a height that is not finite, a membrane that nothing holds (no fixed
    /// boundary and no body that can stop it), both bodies rigid with φ_low > φ at some
    /// unknown.
    pub fn assemble_with(mesh: &Mesh, data: &ProblemData, ext: &Extensions) -> Result<Model> {
        let (adj, boundary) = mesh.patches();
        Model::assemble_on(mesh, &adj, &boundary, data, ext)
    }

    /// [`Model::assemble_with`] given the mesh's vertex → triangles adjacency and its
    /// boundary vertices (computed once per run and shared with the checks).
    pub fn assemble_on(
        mesh: &Mesh,
        adj: &VertexTriangles,
        boundary: &[bool],
        data: &ProblemData,
        ext: &Extensions,
    ) -> Result<Model> {
        let t = data.tension;
        if !t.is_finite() || t <= 0.0 {
            return Err(Error::Data(format!(
                "membrane.tension must be a finite number > 0, got {t}"
            )));
        }
        let fixed = match &ext.boundary {
            Some(b) => Some(FixedBoundary::new(mesh, adj, b.free)?),
            None => None,
        };
        let dofs = match &fixed {
            Some(f) => DofMap::from_fixed(&f.fixed),
            None => DofMap::from_fixed(boundary),
        };
        if dofs.is_empty() {
            return Err(Error::Mesh(
                "the mesh has no interior vertex: there is no unknown to solve for".into(),
            ));
        }
        // The triangle areas, shared by every load-type integral below.
        let areas = mesh.areas();
        let loads = Loads::new(mesh, &dofs, adj, &areas);
        // Data checks: every value finite, h ≥ 0. f and h at the triangle centroids (their
        // quadrature), φ and h at the vertices (their samples).
        check_centroids(mesh, &loads, "membrane.load f", data.load, false)?;
        let upper = BodyData {
            shape: data.shape,
            stiffness: data.stiffness,
            rigid_regions: ext.rigid_regions,
            foundation: data.foundation,
            sampling: data.sampling,
        };
        let pattern = Arc::new(unknowns_pattern(mesh, &dofs, adj, boundary)?);
        // S and the upper body's consistent L share one pass over the rows.
        let masked = Masked::new(upper);
        let consistent_h = match (masked.elastic(), data.foundation) {
            (Some(h), Foundation::Consistent) => Some(h),
            _ => None,
        };
        let (s, l_consistent) =
            assemble_stiffness_and_mass(mesh, &dofs, adj, &pattern, t, consistent_h);
        let body = assemble_body(mesh, adj, &loads, &dofs, &upper, l_consistent, NAMES_UPPER)?;
        let load = data.load;
        let (mut d, total_load) = loads.vector_and_integral(load);
        if let Some(i) = crate::sparse::first_non_finite(&d) {
            let p = mesh.points[dofs.vertex[i] as usize];
            return Err(Error::Data(format!(
                "membrane.load f is not finite near ({}, {})",
                p[0], p[1]
            )));
        }
        // Boundary heights and the lifting S_fix G.
        let (boundary_values, lift) = match (&ext.boundary, &fixed) {
            (Some(b), Some(f)) => {
                let g = boundary_heights(mesh, f, b.height)?;
                if g.iter().any(|&x| x != 0.0) {
                    let lift = assemble_lift(mesh, &dofs, adj, t, &g);
                    (g, lift)
                } else {
                    (Vec::new(), Vec::new())
                }
            }
            _ => (Vec::new(), Vec::new()),
        };
        for (di, li) in d.iter_mut().zip(&lift) {
            *di -= li;
        }
        let lower = match &ext.lower {
            Some(low) => {
                let masked = Masked::new(*low);
                let l_consistent = match (masked.elastic(), low.foundation) {
                    (Some(h), Foundation::Consistent) => {
                        Some(assemble_mass(mesh, &dofs, adj, &pattern, h))
                    }
                    _ => None,
                };
                Some(assemble_body(
                    mesh,
                    adj,
                    &loads,
                    &dofs,
                    low,
                    l_consistent,
                    NAMES_LOWER,
                )?)
            }
            None => None,
        };
        let Body {
            l,
            phi,
            can_touch,
            rigid,
            foundation,
            phi_fixed,
            h_vertices,
            epsilon,
        } = body;
        let model = Model {
            dofs,
            tension: t,
            s,
            l,
            d,
            phi,
            can_touch,
            foundation,
            phi_fixed,
            h_vertices,
            total_load,
            epsilon,
            rigid,
            lower,
            boundary_values,
            lift,
        };
        if fixed.is_some() {
            model.check_held(mesh)?;
        }
        model.check_squeeze(mesh)?;
        Ok(model)
    }
}

/// The names of one body's data in messages.
#[derive(Clone, Copy)]
pub(super) struct BodyNames {
    stiffness: &'static str,
    shape: &'static str,
    epsilon: &'static str,
}

pub(super) const NAMES_UPPER: BodyNames = BodyNames {
    stiffness: "obstacle.stiffness h",
    shape: "obstacle.shape φ",
    epsilon: "obstacle.epsilon",
};

pub(super) const NAMES_LOWER: BodyNames = BodyNames {
    stiffness: "lower.stiffness h_low",
    shape: "lower.shape φ_low",
    epsilon: "lower.epsilon",
};

/// A body's elastic stiffness with its rigid regions masked to 0 (the elastic term is
/// integrated over the elastic triangles only, docs/theory.md#mixed-bodies).
pub(super) struct Masked<'a> {
    inner: Option<&'a dyn Coefficient>,
    rigid: &'a [u32],
}

impl<'a> Masked<'a> {
    pub(super) fn new(body: BodyData<'a>) -> Masked<'a> {
        Masked {
            inner: match body.stiffness {
                BodyStiffness::Elastic(h) => Some(h),
                BodyStiffness::Rigid => None,
            },
            rigid: body.rigid_regions,
        }
    }

    /// The coefficient to integrate (`None`: rigid everywhere). Without rigid regions it is
    /// the body's own coefficient, so that the paper's model is assembled as before.
    pub(super) fn elastic(&self) -> Option<&dyn Coefficient> {
        let inner = self.inner?;
        if self.rigid.is_empty() {
            Some(inner)
        } else {
            Some(self)
        }
    }
}

impl Coefficient for Masked<'_> {
    fn at(&self, p: crate::mesh::Point, region: u32) -> f64 {
        if self.rigid.contains(&region) {
            0.0
        } else {
            self.inner.map_or(0.0, |h| h.at(p, region))
        }
    }
    fn on_region(&self, region: u32) -> Option<f64> {
        if self.rigid.contains(&region) {
            Some(0.0)
        } else {
            self.inner.and_then(|h| h.on_region(region))
        }
    }
}

/// Assembles one body (docs/theory.md#matrices for the obstacle, docs/theory.md#second-body
/// for the body below, docs/theory.md#mixed-bodies for rigid regions): its foundation
/// matrix (`l_consistent` when the caller assembled it), its sampled surface, the unknowns
/// it can touch and those it holds rigidly, with the data checks (h ≥ 0 and finite, φ
/// finite).
pub(super) fn assemble_body(
    mesh: &Mesh,
    adj: &VertexTriangles,
    loads: &Loads,
    dofs: &DofMap,
    data: &BodyData,
    l_consistent: Option<Csr>,
    names: BodyNames,
) -> Result<Body> {
    let masked = Masked::new(*data);
    // Vertices whose patch meets a rigid region (every vertex for a wholly rigid body).
    let rigid_vertex: Option<Vec<bool>> = match (data.stiffness, data.rigid_regions) {
        (BodyStiffness::Rigid, _) => None,
        (_, []) => None,
        (_, tags) => Some(
            (0..mesh.n_vertices())
                .map(|v| {
                    adj.of(v)
                        .iter()
                        .any(|&k| tags.contains(&mesh.regions[k as usize]))
                })
                .collect(),
        ),
    };
    let wholly_rigid = matches!(data.stiffness, BodyStiffness::Rigid)
        || (!data.rigid_regions.is_empty()
            && mesh.regions.iter().all(|r| data.rigid_regions.contains(r)));
    let h_vertices = match masked.elastic() {
        Some(h) if !wholly_rigid => {
            check_centroids(mesh, loads, names.stiffness, h, true)?;
            // One value everywhere: it was checked, and it is every vertex's average.
            let uniform = loads.uniform(h);
            match (uniform, &rigid_vertex) {
                (Some(value), None) => VertexValues::Uniform {
                    value,
                    n: mesh.n_vertices(),
                },
                _ => {
                    let mut hv = match uniform {
                        Some(v) => vec_of(mesh.n_vertices(), v),
                        None => {
                            let hv = vertex_average(mesh, adj, h);
                            check_vertices(mesh, names.stiffness, &hv, true)?;
                            hv
                        }
                    };
                    if let Some(r) = &rigid_vertex {
                        for (h, &rv) in hv.iter_mut().zip(r) {
                            if rv {
                                *h = f64::INFINITY;
                            }
                        }
                    }
                    VertexValues::from_values(hv)
                }
            }
        }
        _ => VertexValues::Uniform {
            value: f64::INFINITY,
            n: mesh.n_vertices(),
        },
    };
    let l = match (masked.elastic(), l_consistent) {
        _ if wholly_rigid => FoundationMatrix::Rigid,
        (_, Some(l)) => FoundationMatrix::Consistent(l),
        (Some(h), None) => FoundationMatrix::Lumped(loads.vector(h)),
        (None, None) => FoundationMatrix::Rigid,
    };
    let rigid: Option<Vec<bool>> = match (&rigid_vertex, wholly_rigid) {
        (Some(r), false) => {
            let on_unknowns: Vec<bool> = dofs.vertex.iter().map(|&v| r[v as usize]).collect();
            on_unknowns.iter().any(|&x| x).then_some(on_unknowns)
        }
        _ => None,
    };
    let can_touch: Vec<bool> = (0..dofs.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| l.is_rigid() || l.diag(i) > 0.0 || rigid.as_ref().is_some_and(|r| r[i]))
        .collect();
    let (phi_vertices, epsilon) = match data.sampling {
        Sampling::Nodal => (vertex_average(mesh, adj, data.shape), None),
        Sampling::Mollified { epsilon } => {
            let eps = match epsilon {
                Some(e) if e.is_finite() && e > 0.0 => e,
                Some(e) => {
                    return Err(Error::Data(format!(
                        "{} must be a finite number > 0, got {e}",
                        names.epsilon
                    )))
                }
                None => paper_epsilon(mesh),
            };
            (mollify(mesh, adj, data.shape, eps), Some(eps))
        }
    };
    check_vertices(mesh, names.shape, &phi_vertices, false)?;
    let phi = dofs.to_unknowns(&phi_vertices);
    let phi_fixed = super::body::fixed_values(dofs, &phi_vertices);
    drop(phi_vertices);
    Ok(Body {
        l,
        phi,
        can_touch,
        rigid,
        foundation: data.foundation,
        phi_fixed,
        h_vertices,
        epsilon,
    })
}

/// `n` copies of `v`, written on all threads.
pub(super) fn vec_of(n: usize, v: f64) -> Vec<f64> {
    (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| v)
        .collect()
}
