//! The checks of derived numbers, on every path from data to a written result: the data
//! where assembly does not sample it (on the boundary), the assembled model for overflow
//! (S, L, D, φₙ, ∫f and the size of J), and the results of a solve (J, the certificate,
//! the fields and totals). A non-finite number is a clear error naming the data that made
//! it, never a certificate of 0 or a `null` in `summary.json`.
//!
//! [`assemble_checked`] is the one way to a checked model: the front door ([`crate::run`]), the
//! convergence studies and the load sweeps use it; a sweep step that scales a model is
//! checked again with [`check_model`].

use super::body::FoundationMatrix;
use super::data::bad_value;
use super::data::{BodyStiffness, Extensions, ProblemData};
use super::system::Model;
use crate::error::{Error, Result};
use crate::fem::{Loads, VertexTriangles};
use crate::field::Coefficient;
use crate::mesh::Mesh;
use crate::sparse::first_non_finite;
use rayon::prelude::*;

/// Assembles the model of `data` with the extensions `ext` on `mesh`
/// ([`Model::assemble_with`]) between the checks of the boundary data
/// ([`check_boundary_data`]) and of overflow ([`check_model`]).
pub fn assemble_checked(mesh: &Mesh, data: &ProblemData, ext: &Extensions) -> Result<Model> {
    let (adj, boundary) = mesh.patches();
    assemble_checked_on(mesh, &adj, &boundary, data, ext)
}

/// [`assemble_checked`] given the mesh's vertex → triangles adjacency and its boundary vertices.
pub fn assemble_checked_on(
    mesh: &Mesh,
    adj: &VertexTriangles,
    boundary: &[bool],
    data: &ProblemData,
    ext: &Extensions,
) -> Result<Model> {
    check_boundary_data_on(mesh, adj, boundary, data, ext)?;
    let model = Model::assemble_on(mesh, adj, boundary, data, ext)?;
    check_model(mesh, &model)?;
    Ok(model)
}

/// Checks the data where assembly does not sample it: f on the boundary vertices (a load
/// singular on the boundary, like `1/x` on x = 0, is refused), and, where a body is rigid
/// next to the fixed boundary, that it leaves room for the prescribed height g there
/// (`φ ≥ g` above, `φ_low ≤ g` below: otherwise no continuous solution exists).
pub fn check_boundary_data(mesh: &Mesh, data: &ProblemData, ext: &Extensions) -> Result<()> {
    let (adj, boundary) = mesh.patches();
    check_boundary_data_on(mesh, &adj, &boundary, data, ext)
}

/// [`check_boundary_data`] given the mesh's adjacency and boundary vertices.
fn check_boundary_data_on(
    mesh: &Mesh,
    adj: &VertexTriangles,
    boundary: &[bool],
    data: &ProblemData,
    ext: &Extensions,
) -> Result<()> {
    // Without boundary conditions of its own, the whole boundary is fixed at height 0.
    let given = match ext.boundary {
        Some(_) => Some(super::boundary::fixed_heights_on(mesh, adj, boundary, ext)?),
        None => None,
    };
    let rigid_upper = |region: u32| {
        matches!(data.stiffness, BodyStiffness::Rigid) || ext.rigid_regions.contains(&region)
    };
    for (v, &on) in boundary.iter().enumerate() {
        if !on {
            continue;
        }
        let p = mesh.points[v];
        let (fixed, g) = given.as_ref().map_or((true, 0.0), |(f, g)| (f[v], g[v]));
        for &k in adj.of(v) {
            let region = mesh.regions[k as usize];
            let f = value(data.load, p, region);
            if !f.is_finite() {
                return Err(Error::Data(format!(
                    "membrane.load f is not finite on the boundary at ({}, {}) (f = {f}): the \
                     load must be bounded on the closed domain",
                    p[0], p[1]
                )));
            }
            if !fixed {
                continue;
            }
            if rigid_upper(region) {
                let phi = value(data.shape, p, region);
                if phi < g {
                    return Err(Error::Data(format!(
                        "obstacle.shape φ = {phi} at the boundary point ({}, {}) lies below \
                         the fixed boundary (u = {g} there): with a rigid obstacle (u ≤ φ) the \
                         problem has no continuous solution; raise φ to at least {g} on the \
                         boundary or give the obstacle a finite stiffness",
                        p[0], p[1]
                    )));
                }
            }
            if let Some(low) = &ext.lower {
                if matches!(low.stiffness, BodyStiffness::Rigid)
                    || low.rigid_regions.contains(&region)
                {
                    let phi = value(low.shape, p, region);
                    if phi > g {
                        return Err(Error::Data(format!(
                            "lower.shape φ_low = {phi} at the boundary point ({}, {}) lies \
                             above the fixed boundary (u = {g} there): with a rigid body \
                             below (u ≥ φ_low) the problem has no continuous solution; lower \
                             φ_low to at most {g} on the boundary or give the body a finite \
                             stiffness",
                            p[0], p[1]
                        )));
                    }
                }
            }
        }
    }
    Ok(())
}

/// A coefficient's value at `p` in `region`.
fn value(c: &dyn Coefficient, p: [f64; 2], region: u32) -> f64 {
    c.on_region(region).unwrap_or_else(|| c.at(p, region))
}

/// Refuses a model whose matrices or data overflowed double precision, naming the data.
pub fn check_model(mesh: &Mesh, model: &Model) -> Result<()> {
    if !model.s.is_finite() {
        let smallest_area = (0..mesh.n_triangles())
            .map(|k| mesh.area(k).abs())
            .fold(f64::INFINITY, f64::min);
        return Err(Error::Data(format!(
            "the stiffness matrix S overflows double precision: tension t = {:e} on triangles \
             as small as {smallest_area:e} (S grows like t × edge² / area); rescale the \
             problem (units) so that t and the mesh are moderate",
            model.tension
        )));
    }
    if !matrix_finite(&model.l) {
        return Err(Error::Data(
            "the foundation matrix L = ∫h gᵢgⱼ overflows double precision: \
             obstacle.stiffness h is too large (use stiffness = \"rigid\" for a rigid body)"
                .into(),
        ));
    }
    if let Some(i) = first_non_finite(&model.phi) {
        let p = mesh.points[model.dofs.vertex[i] as usize];
        return Err(Error::Data(format!(
            "obstacle.shape φ is not finite at ({}, {})",
            p[0], p[1]
        )));
    }
    if let Some(low) = &model.lower {
        if !matrix_finite(&low.l) {
            return Err(Error::Data(
                "the foundation matrix of the body below overflows double precision: \
                 lower.stiffness is too large (use stiffness = \"rigid\" for a rigid body)"
                    .into(),
            ));
        }
        if let Some(i) = first_non_finite(&low.phi) {
            let p = mesh.points[model.dofs.vertex[i] as usize];
            return Err(Error::Data(format!(
                "lower.shape φ_low is not finite at ({}, {})",
                p[0], p[1]
            )));
        }
    }
    if let Some(i) = first_non_finite(&model.d) {
        let p = mesh.points[model.dofs.vertex[i] as usize];
        return Err(Error::Data(format!(
            "the nodal load D = ∫f gᵢ overflows double precision near ({}, {}): \
             membrane.load f is too large",
            p[0], p[1]
        )));
    }
    if !model.total_load.is_finite() {
        return Err(Error::Data(
            "the total load ∫f overflows double precision: membrane.load f is too large".into(),
        ));
    }
    // J = ½UᵀSU − UᵀD with U of the size D/S: the products must stay finite.
    let d_max = crate::sparse::norm_inf(&model.d);
    let s_min = model.s.diag().into_iter().fold(f64::INFINITY, f64::min);
    let u_size = d_max / s_min * (model.n() as f64).sqrt();
    if !(d_max * u_size * model.n() as f64).is_finite() {
        return Err(Error::Data(format!(
            "the energy J would overflow double precision: the nodal loads |D| reach \
             {d_max:.3e} against a stiffness of {s_min:.3e} (membrane.load is too large for the \
             tension); rescale the problem (units)"
        )));
    }
    Ok(())
}

/// Whether a foundation matrix holds finite numbers only.
fn matrix_finite(l: &FoundationMatrix) -> bool {
    match l {
        FoundationMatrix::Consistent(l) => l.is_finite(),
        FoundationMatrix::Lumped(d) => first_non_finite(d).is_none(),
        FoundationMatrix::Rigid => true,
    }
}

/// What overflowed, in terms of the data, for the messages of
/// [`crate::solve::check_solution`] and of the checks of a run's fields and totals.
pub const OVERFLOW_HINT: &str = "the data's scales (tension t, load f, stiffness h, shape φ, \
                             mesh size) overflow double precision; rescale the problem \
                             (units)";

impl Model {
    /// Refuses a membrane that nothing holds (docs/theory.md#boundary-data): every
    /// connected group of unknowns that no fixed vertex touches must be held by the bodies:
    /// by one from each side, or by one body toward which the net load on the group pushes.
    /// Otherwise J has no minimiser (or no unique one) and S is singular on the group.
    pub(super) fn check_held(&self, mesh: &Mesh) -> Result<()> {
        let n = self.n();
        // Union-find over the couplings of S.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut i: u32) -> u32 {
            while p[i as usize] != i {
                p[i as usize] = p[p[i as usize] as usize];
                i = p[i as usize];
            }
            i
        }
        let pat = &self.s.pattern;
        for i in 0..n {
            for &j in &pat.col[pat.ptr(i)..pat.ptr(i + 1)] {
                let (a, b) = (find(&mut parent, i as u32), find(&mut parent, j));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        // Unknowns next to a fixed vertex: a triangle of theirs has a fixed corner.
        let adj = VertexTriangles::new(mesh);
        #[derive(Clone, Copy, Default)]
        struct Group {
            anchored: bool,
            upper: bool,
            lower: bool,
            load: f64,
            first: u32,
            size: usize,
        }
        let mut groups = vec![Group::default(); n];
        for (i, &v) in self.dofs.vertex.iter().enumerate() {
            let anchored = adj.of(v as usize).iter().any(|&k| {
                mesh.triangles[k as usize]
                    .iter()
                    .any(|&w| self.dofs.is_fixed(w as usize))
            });
            let r = find(&mut parent, i as u32) as usize;
            let g = &mut groups[r];
            if g.size == 0 {
                g.first = i as u32;
            }
            g.size += 1;
            g.anchored |= anchored;
            g.upper |= self.can_touch[i];
            g.lower |= self.lower.as_ref().is_some_and(|b| b.can_touch[i]);
            g.load += self.d[i];
        }
        for g in groups.iter().filter(|g| g.size > 0 && !g.anchored) {
            let held = (g.upper && (g.lower || g.load > 0.0)) || (g.lower && g.load < 0.0);
            if held {
                continue;
            }
            let p = mesh.points[self.dofs.vertex[g.first as usize] as usize];
            let why = if !g.upper && !g.lower {
                "no body can touch it".to_string()
            } else if g.upper {
                format!(
                    "only the obstacle above can touch it, and the net load on it ({:e}) does \
                     not push it up against the obstacle",
                    g.load
                )
            } else {
                format!(
                    "only the body below can touch it, and the net load on it ({:e}) does \
                     not push it down onto the body",
                    g.load
                )
            };
            return Err(Error::Data(format!(
                "the membrane is not held: {} vertices (one at ({}, {})) touch no fixed \
                 boundary and {why}, so it can move without bound; fix part of the boundary \
                 (boundary.free lists the free regions) or give it a body on each side",
                g.size, p[0], p[1]
            )));
        }
        Ok(())
    }

    /// Refuses two rigid bodies that overlap at an unknown (φ_low > φ there: no admissible
    /// deflection, docs/theory.md#second-body), naming the vertices.
    pub(super) fn check_squeeze(&self, mesh: &Mesh) -> Result<()> {
        let Some(low) = &self.lower else {
            return Ok(());
        };
        let bad: Vec<usize> = (0..self.n())
            .filter(|&i| self.rigid_at(i) && low.rigid_at(i) && low.phi[i] > self.phi[i])
            .collect();
        if bad.is_empty() {
            return Ok(());
        }
        let shown: Vec<String> = bad
            .iter()
            .take(5)
            .map(|&i| {
                let v = self.dofs.vertex[i] as usize;
                let p = mesh.points[v];
                format!(
                    "vertex {v} at ({}, {}): φ_low = {} > φ = {}",
                    p[0], p[1], low.phi[i], self.phi[i]
                )
            })
            .collect();
        let more = if bad.len() > 5 {
            format!(" and {} more", bad.len() - 5)
        } else {
            String::new()
        };
        Err(Error::Data(format!(
            "both bodies are rigid and overlap, so no deflection fits between them \
             (φ_low ≤ u ≤ φ is empty) at {} vertices: {}{more}",
            bad.len(),
            shown.join("; ")
        )))
    }
}

/// Checks a coefficient at every triangle centroid: finite, and non-negative when asked
/// (once per region where it is constant, once in all where it has one value everywhere).
pub(super) fn check_centroids(
    mesh: &Mesh,
    loads: &Loads,
    name: &str,
    c: &dyn Coefficient,
    non_negative: bool,
) -> Result<()> {
    let bad = |v: f64| !v.is_finite() || (non_negative && v < 0.0);
    // One value everywhere: checked once (a bad one is named at the first centroid).
    if let Some(v) = loads.uniform(c) {
        if !bad(v) {
            return Ok(());
        }
    }
    let found = (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(4096)
        .find_map_first(|k| {
            let r = mesh.regions[k];
            // The centroid only where c is not constant on the region (or to name a bad value).
            let centroid = || {
                let cs = mesh.corners(k);
                [
                    (cs[0][0] + cs[1][0] + cs[2][0]) / 3.0,
                    (cs[0][1] + cs[1][1] + cs[2][1]) / 3.0,
                ]
            };
            let v = c.on_region(r).unwrap_or_else(|| c.at(centroid(), r));
            bad(v).then(|| (v, centroid()))
        });
    match found {
        Some((v, p)) => Err(bad_value(name, v, p)),
        None => Ok(()),
    }
}

/// Checks sampled vertex values: finite, and non-negative when asked.
pub(super) fn check_vertices(
    mesh: &Mesh,
    name: &str,
    values: &[f64],
    non_negative: bool,
) -> Result<()> {
    match crate::sparse::first_where(values, |v| !v.is_finite() | (non_negative & (v < 0.0))) {
        Some(i) => Err(bad_value(name, values[i], mesh.points[i])),
        None => Ok(()),
    }
}
