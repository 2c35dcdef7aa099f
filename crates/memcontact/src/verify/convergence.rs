//! Convergence studies: the paper's main result, `u_n → u` in H¹ as the mesh is refined,
//! measured (docs/theory.md#manufactured-solutions: O(l_n) in the H¹ seminorm, about
//! O(l_n²) in L²).
//!
//! [`run`] solves one problem on a base mesh and on `K` successive uniform refinements of
//! it (the levels of a [`Hierarchy`], refined once more per level), and measures every
//! level's error against a [`Target`]:
//!
//! * [`Target::Exact`]: a closed-form solution ([`crate::verify::exact`]), with
//!   [`crate::verify::norms::error_norms`] (degree-5 quadrature per triangle; on a disc the gap
//!   between the inscribed polygon Ω_n and Ω is integrated exactly, `u_h = 0` there);
//! * [`Target::Finest`]: no closed form is known (a discontinuous obstacle, say): every
//!   level is compared with the finest level's own solution (a *reference solution*); the
//!   coarse solutions are carried to the finest mesh by the hierarchy's P1 prolongation and
//!   the norms of the difference are computed exactly for P1 functions there;
//! * [`Target::Discrete`]: the same against a given reference on the finest mesh (so that
//!   two variants of a problem can be measured against one reference).
//!
//! Every level also reports the *successive difference* `u_k − u_{k−1}` (the coarser
//! solution prolongated), whose rates estimate the convergence rate without any reference,
//! and an estimate of the contact area and radius ([`contact_estimate`]).
//!
//! The problem data ([`ProblemData`]) are the same functions of the position and region on
//! every level: regions are inherited by refinement, so binding the case's fields once is
//! enough. The mollifier radius of [`crate::model::Sampling::Mollified`] with the paper's
//! `ε_n` is recomputed by the assembly on every level.
//!
//! [`rigid_limit_sweep`] measures the other limit (docs/theory.md#limits): on a fixed mesh,
//! the distance between the discrete solutions for a growing constant stiffness `h` and the
//! discrete rigid-obstacle solution.
//!
//! Nothing here prints or writes files: the command-line tool formats the results.

use crate::error::{Error, Result};
use crate::fem::Element;
use crate::field::Coefficient;
use crate::mesh::refine::Hierarchy;
use crate::mesh::{Mesh, Point};
use crate::model::{BodyStiffness, Extensions, Model, ProblemData};
use crate::solve::{self, Method, Settings, Silent, Solution};
use crate::verify::exact::ExactSolution;
use crate::verify::norms::{error_norms, rates, ErrorNorms};
use std::time::Instant;

/// The load of a manufactured solution (docs/theory.md#manufactured-solutions): `f = −t
/// Δu + h (u − φ)⁺`, from the exact Laplacian of `exact` and the problem's own `h` and `φ`
/// evaluated at the same point and region (so `h` and `φ` may be expressions or region
/// tables); with a body below (docs/theory.md#second-body) its reaction `− h_low (φ_low −
/// u)⁺` too. It is [`crate::verify::exact::manufactured_load`] as an assembly coefficient:
/// NaN outside Ω (which the model's data checks then report), never an evaluation of the
/// exact solution there.
pub struct ManufacturedLoad<'a> {
    /// The manufactured solution u.
    pub exact: &'a dyn ExactSolution,
    /// The tension t.
    pub tension: f64,
    /// The foundation stiffness h.
    pub stiffness: &'a dyn Coefficient,
    /// The obstacle φ.
    pub shape: &'a dyn Coefficient,
    /// The body below's stiffness h_low and surface φ_low, when there is one.
    pub lower: Option<(&'a dyn Coefficient, &'a dyn Coefficient)>,
}

impl Coefficient for ManufacturedLoad<'_> {
    fn at(&self, p: Point, region: u32) -> f64 {
        if !self.exact.contains(p) {
            return f64::NAN;
        }
        let h = self.stiffness.at(p, region);
        let phi = self.shape.at(p, region);
        let u = self.exact.value(p);
        let f = -self.tension * self.exact.laplacian(p) + h * (u - phi).max(0.0);
        match self.lower {
            Some((h_low, phi_low)) => {
                f - h_low.at(p, region) * (phi_low.at(p, region) - u).max(0.0)
            }
            None => f,
        }
    }

    fn on_region(&self, _region: u32) -> Option<f64> {
        None
    }
}

/// What the discrete solutions are compared with.
#[derive(Clone, Copy)]
pub enum Target<'a> {
    /// A closed-form solution of Problem 1.
    Exact(&'a dyn ExactSolution),
    /// The finest level's own solution (a reference solution).
    Finest,
    /// A reference solution on the finest level's mesh: one value per vertex of it.
    Discrete(&'a [f64]),
}

/// How many levels to solve and how.
#[derive(Debug, Clone)]
pub struct StudySettings {
    /// Refinement levels beyond the base mesh (`K ≥ 1`): `K + 1` levels are solved.
    pub levels: usize,
    /// The solver settings of every level. With [`Method::Auto`], each level is solved by
    /// the library's one policy ([`solve::attempt`]: multigrid when the hierarchy allows
    /// it, the active-set method when multigrid does not converge; the row's `method` and
    /// `note` say so).
    pub solver: Settings,
}

/// An estimate of the discrete contact zone.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactEstimate {
    /// Its area `A_h` (see [`contact_estimate`]).
    pub area: f64,
    /// `√(A_h / π)`: the radius of a disc of that area.
    pub radius: f64,
}

/// One level of a study.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LevelResult {
    /// 0 for the base mesh, `k` after `k` refinements.
    pub level: usize,
    /// Mesh vertices.
    pub vertices: usize,
    /// Mesh triangles.
    pub triangles: usize,
    /// Unknowns (interior vertices).
    pub unknowns: usize,
    /// The largest triangle diameter `l_n`.
    pub l_n: f64,
    /// The errors against the target (`None` for the reference level of
    /// [`Target::Finest`]). For a discrete target `max_nodal` is the largest difference at
    /// the finest mesh's vertices, and the gap fields are 0.
    pub errors: Option<ErrorNorms>,
    /// `‖u_k − u_{k−1}‖_{L²}` and `|u_k − u_{k−1}|_{H¹}` (`None` on level 0).
    pub increment: Option<[f64; 2]>,
    /// The discrete contact zone.
    pub contact: ContactEstimate,
    /// `|a_h − a|` when the target knows its contact radius `a`.
    pub contact_radius_error: Option<f64>,
    /// `|A_h − A|` when the target knows its contact area `A`.
    pub contact_area_error: Option<f64>,
    /// The mollifier radius ε used on this level (mollified sampling only).
    pub epsilon: Option<f64>,
    /// The method that solved the level.
    pub method: Method,
    /// Its iterations.
    pub iterations: usize,
    /// The scaled KKT residual reached.
    pub kkt: f64,
    /// Seconds to refine the mesh to this level (0 on level 0).
    pub refine_seconds: f64,
    /// Seconds to assemble the model.
    pub assembly_seconds: f64,
    /// Seconds to solve.
    pub solve_seconds: f64,
    /// Seconds to measure the errors.
    pub error_seconds: f64,
    /// Anything the reader should know (e.g. a multigrid failure and its fallback).
    pub note: Option<String>,
}

/// The result of [`run`].
#[derive(Debug, Clone)]
pub struct Study {
    /// One row per level, coarsest first.
    pub levels: Vec<LevelResult>,
    /// Observed L² rates between consecutive levels (`None` for level 0 and where an error
    /// is missing), from [`crate::verify::norms::rates`].
    pub l2_rates: Vec<Option<f64>>,
    /// Observed H¹-seminorm rates.
    pub h1_rates: Vec<Option<f64>>,
    /// Observed rates of the max nodal error.
    pub max_nodal_rates: Vec<Option<f64>>,
    /// Rates of the successive differences in L².
    pub l2_increment_rates: Vec<Option<f64>>,
    /// Rates of the successive differences in the H¹ seminorm.
    pub h1_increment_rates: Vec<Option<f64>>,
    /// The finest level's solution at every vertex of the finest mesh.
    pub finest_u: Vec<f64>,
    /// The mesh levels (the base mesh's own hierarchy first, then one per study level).
    pub hierarchy: Hierarchy,
}

/// Runs a convergence study: solves `data` on the finest mesh of `hierarchy` (level 0)
/// and on `settings.levels` successive uniform refinements of it, and measures each level
/// against `target` (see the module documentation). `progress` is called after each level
/// is solved (with the errors already measured for [`Target::Exact`], `None` otherwise).
///
/// Errors: `levels == 0`; a level whose assembly or solve fails; a target whose domain
/// does not contain the mesh ([`error_norms`]); a [`Target::Discrete`] reference whose
/// length is not the finest mesh's vertex count.
pub fn run(
    hierarchy: Hierarchy,
    data: &ProblemData,
    target: Target,
    settings: &StudySettings,
    progress: &mut dyn FnMut(&LevelResult),
) -> Result<Study> {
    run_with(
        hierarchy,
        data,
        &Extensions::default(),
        target,
        settings,
        progress,
    )
}

/// [`run`] with the data beyond the paper's frame (boundary heights and free edges, rigid
/// regions, a body below; docs/theory.md#extensions): the same on every level, like `data`.
pub fn run_with(
    mut hierarchy: Hierarchy,
    data: &ProblemData,
    ext: &Extensions,
    target: Target,
    settings: &StudySettings,
    progress: &mut dyn FnMut(&LevelResult),
) -> Result<Study> {
    if settings.levels == 0 {
        return Err(Error::Data(
            "a convergence study needs at least one refinement level (levels ≥ 1)".into(),
        ));
    }
    let base = crate::limits::MeshSize::of(hierarchy.finest());
    crate::limits::check_mesh_fits(
        base,
        settings.levels,
        &format!(
            "a convergence study of {} levels on a mesh of {:.0} triangles",
            settings.levels, base.triangles
        ),
    )?;
    let base_depth = hierarchy.depth();
    let mut rows: Vec<LevelResult> = Vec::with_capacity(settings.levels + 1);
    // Vertex solutions of every level (kept only when compared with a discrete reference).
    let keep_all = !matches!(target, Target::Exact(_));
    let mut kept: Vec<Vec<f64>> = Vec::new();
    let mut previous: Option<Vec<f64>> = None;
    for level in 0..=settings.levels {
        let t0 = Instant::now();
        if level > 0 {
            hierarchy.refine(1);
        }
        let refine_seconds = t0.elapsed().as_secs_f64();
        let mesh = hierarchy.finest();
        let t1 = Instant::now();
        let model =
            crate::model::assemble_checked(mesh, data, ext).map_err(|e| at_level(level, e))?;
        let assembly_seconds = t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        let (solution, note) =
            solve_level(&model, &hierarchy, &settings.solver).map_err(|e| at_level(level, e))?;
        let solve_seconds = t2.elapsed().as_secs_f64();
        let u = model.to_vertices(&solution.u);
        let t3 = Instant::now();
        let errors = match target {
            Target::Exact(exact) => {
                Some(error_norms(mesh, &u, exact).map_err(|e| at_level(level, e))?)
            }
            _ => None,
        };
        let increment = previous.as_ref().map(|prev| {
            let coarse = hierarchy.prolongate(hierarchy.depth() - 2, prev);
            let diff: Vec<f64> = u.iter().zip(&coarse).map(|(a, b)| a - b).collect();
            let n = p1_norms(mesh, &diff);
            [n[0], n[1]]
        });
        let error_seconds = t3.elapsed().as_secs_f64();
        let contact = contact_estimate(mesh, &model, &solution.u);
        let (contact_radius_error, contact_area_error) = match target {
            Target::Exact(exact) => (
                exact.contact_radius().map(|a| (contact.radius - a).abs()),
                exact.contact_area().map(|a| (contact.area - a).abs()),
            ),
            _ => (None, None),
        };
        let q = mesh.quality();
        let row = LevelResult {
            level,
            vertices: q.vertices,
            triangles: q.triangles,
            unknowns: q.unknowns,
            l_n: q.l_n,
            errors,
            increment,
            contact,
            contact_radius_error,
            contact_area_error,
            epsilon: model.epsilon,
            method: solution.method,
            iterations: solution.iterations,
            kkt: solution.certificate.kkt(),
            refine_seconds,
            assembly_seconds,
            solve_seconds,
            error_seconds,
            note,
        };
        progress(&row);
        rows.push(row);
        if keep_all {
            kept.push(u.clone());
        }
        previous = Some(u);
    }
    let finest_u = previous.expect("at least one level");
    if keep_all {
        let reference: &[f64] = match target {
            Target::Discrete(r) => {
                if r.len() != finest_u.len() {
                    return Err(Error::Data(format!(
                        "the reference solution has {} values, the finest mesh {} vertices",
                        r.len(),
                        finest_u.len()
                    )));
                }
                r
            }
            _ => &finest_u,
        };
        let finest = hierarchy.finest();
        let last = settings.levels;
        for (k, u) in kept.into_iter().enumerate() {
            if k == last && matches!(target, Target::Finest) {
                continue;
            }
            let t = Instant::now();
            let mut v = u;
            for l in k..last {
                v = hierarchy.prolongate(base_depth - 1 + l, &v);
            }
            let diff: Vec<f64> = v.iter().zip(reference).map(|(a, b)| a - b).collect();
            let [l2, h1, max] = p1_norms(finest, &diff);
            rows[k].errors = Some(ErrorNorms {
                l2,
                h1_semi: h1,
                max_nodal: max,
                gap_area: 0.0,
                gap_l2: 0.0,
                gap_h1_semi: 0.0,
            });
            rows[k].error_seconds += t.elapsed().as_secs_f64();
        }
    }
    let l_n: Vec<f64> = rows.iter().map(|r| r.l_n).collect();
    let series = |f: &dyn Fn(&LevelResult) -> Option<f64>| -> Vec<Option<f64>> {
        let e: Vec<f64> = rows.iter().map(|r| f(r).unwrap_or(f64::NAN)).collect();
        rates(&l_n, &e)
    };
    Ok(Study {
        l2_rates: series(&|r| r.errors.map(|e| e.l2)),
        h1_rates: series(&|r| r.errors.map(|e| e.h1_semi)),
        max_nodal_rates: series(&|r| r.errors.map(|e| e.max_nodal)),
        l2_increment_rates: series(&|r| r.increment.map(|d| d[0])),
        h1_increment_rates: series(&|r| r.increment.map(|d| d[1])),
        levels: rows,
        finest_u,
        hierarchy,
    })
}

/// Prefixes a library error with the study level it happened on.
fn at_level(level: usize, e: Error) -> Error {
    match e {
        Error::Data(m) => Error::Data(format!("level {level}: {m}")),
        Error::Mesh(m) => Error::Mesh(format!("level {level}: {m}")),
        Error::Solver { solver, message } => Error::Solver {
            solver,
            message: format!("level {level}: {message}"),
        },
        other => other,
    }
}

/// Solves one level with `settings` on the finest mesh of `hierarchy` through the runs'
/// pipeline ([`solve::solve_model`]: the library's one policy, the memory check of its
/// solver, the answer's J and certificate checked). A status the settings do not accept
/// is an error here (a study measures accepted answers only); a fallback of `auto` is
/// returned as a note.
fn solve_level(
    model: &Model,
    hierarchy: &Hierarchy,
    settings: &Settings,
) -> Result<(Solution, Option<String>)> {
    let a = solve::solve_model(model, Some(hierarchy), None, settings, None, &mut Silent)?;
    if !a.status.is_accepted(settings) {
        return Err(solve::not_converged(&a, settings));
    }
    let note = a.fallback.as_ref().map(|f| {
        format!(
            "auto: {} ended {} at KKT {:.1e}{}; {} used",
            f.from.name(),
            f.status.name().replace('_', " "),
            f.residual,
            f.message
                .as_deref()
                .map(|m| format!(" ({m})"))
                .unwrap_or_default(),
            a.solution.method.name()
        )
    });
    Ok((a.solution, note))
}

/// `[‖e‖_{L²}, |e|_{H¹}, max_i |e_i|]` of the P1 function with vertex values `e` on `mesh`,
/// exactly: `∫_T e² = |T| (Σ e_i² + (Σ e_i)²) / 12` and `∇e` constant per triangle.
pub fn p1_norms(mesh: &Mesh, e: &[f64]) -> [f64; 3] {
    let (mut l2, mut h1) = (0.0, 0.0);
    for (k, t) in mesh.triangles.iter().enumerate() {
        let el = Element::of(mesh, k);
        let v = [e[t[0] as usize], e[t[1] as usize], e[t[2] as usize]];
        let (sq, sum) = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2], v[0] + v[1] + v[2]);
        l2 += el.area.abs() * (sq + sum * sum) / 12.0;
        let g = [
            v[0] * el.grad[0][0] + v[1] * el.grad[1][0] + v[2] * el.grad[2][0],
            v[0] * el.grad[0][1] + v[1] * el.grad[1][1] + v[2] * el.grad[2][1],
        ];
        h1 += el.area.abs() * (g[0] * g[0] + g[1] * g[1]);
    }
    let max = e.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    [l2.sqrt(), h1.sqrt(), max]
}

/// The discrete contact zone of a solution `u` (over the unknowns) of `model` on `mesh`.
///
/// * Elastic obstacle: `A_h = |{u_h > φ_h}|`, with `u_h` and `φ_h` the P1 interpolants of
///   the vertex values (`u = 0` on the boundary, `φ` as sampled), computed exactly: on each
///   triangle the set where a linear function is positive is a triangle or a quadrilateral
///   cut off by its zero line.
/// * Rigid obstacle (`u_h ≤ φ_h`, so the set above is empty): `A_h = Σ |Q_i|/3` over the
///   vertices that touch (`U_i = φ_i`), the nodal areas also used by
///   [`crate::outcome::fields::Totals::contact_area`].
///
/// The radius is `√(A_h/π)`, meaningful when the contact zone is a disc.
pub fn contact_estimate(mesh: &Mesh, model: &Model, u: &[f64]) -> ContactEstimate {
    let uv = model.to_vertices(u);
    // A rigid body's zone: the nodal areas of the vertices on its surface.
    let touching_area = |touching: &dyn Fn(usize, u32) -> bool| -> f64 {
        let mut on = vec![false; mesh.n_vertices()];
        for (i, &v) in model.dofs.vertex.iter().enumerate() {
            on[v as usize] = touching(i, v);
        }
        mesh.triangles
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let n = t.iter().filter(|&&v| on[v as usize]).count();
                mesh.area(k).abs() * n as f64 / 3.0
            })
            .sum()
    };
    // An elastic body's zone: where the interpolated gap (positive inside) is positive.
    let penetrated_area = |gap: &dyn Fn(usize) -> f64| -> f64 {
        mesh.triangles
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let gv = [gap(t[0] as usize), gap(t[1] as usize), gap(t[2] as usize)];
                mesh.area(k).abs() * positive_fraction(gv)
            })
            .sum()
    };
    let upper = if model.is_rigid() {
        touching_area(&|i, _| model.can_touch[i] && u[i] == model.phi[i])
    } else if model.lower.is_some() && !model.can_touch.iter().any(|&c| c) {
        0.0
    } else {
        let phi = model.phi_vertices();
        penetrated_area(&|v| uv[v] - phi[v])
    };
    let lower = match &model.lower {
        Some(low) if low.l.is_rigid() => {
            touching_area(&|i, _| low.can_touch[i] && u[i] == low.phi[i])
        }
        Some(low) if low.can_touch.iter().any(|&c| c) => {
            let phi = low.phi_vertices(&model.dofs);
            penetrated_area(&|v| phi[v] - uv[v])
        }
        _ => 0.0,
    };
    let area = upper + lower;
    ContactEstimate {
        area,
        radius: (area / std::f64::consts::PI).sqrt(),
    }
}

/// The fraction of a triangle where the linear function with vertex values `g` is `> 0`.
fn positive_fraction(g: [f64; 3]) -> f64 {
    let pos = g.iter().filter(|&&x| x > 0.0).count();
    match pos {
        0 => 0.0,
        3 => 1.0,
        1 => {
            // The positive corner p and the two others n₁, n₂ ≤ 0: a corner triangle with
            // sides cut at g_p/(g_p − g_n) along each edge.
            let p = g.iter().position(|&x| x > 0.0).expect("one positive");
            let (a, b) = (g[(p + 1) % 3], g[(p + 2) % 3]);
            g[p] * g[p] / ((g[p] - a) * (g[p] - b))
        }
        _ => {
            let q = g.iter().position(|&x| x <= 0.0).expect("one non-positive");
            let (a, b) = (g[(q + 1) % 3], g[(q + 2) % 3]);
            1.0 - g[q] * g[q] / ((a - g[q]) * (b - g[q]))
        }
    }
}

/// One stiffness of a [`rigid_limit_sweep`].
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct RigidLimitRow {
    /// The constant stiffness h.
    pub h: f64,
    /// `max_i |U_i(h) − U_i(∞)|`.
    pub max_nodal: f64,
    /// `|u_h(h) − u_h(∞)|_{H¹}`.
    pub h1_semi: f64,
    /// `‖u_h(h) − u_h(∞)‖_{L²}`.
    pub l2: f64,
    /// The contact estimate of the elastic solution.
    pub contact: ContactEstimate,
    /// The method that solved it.
    pub method: Method,
    /// Its iterations.
    pub iterations: usize,
    /// Seconds to solve.
    pub solve_seconds: f64,
}

/// The result of [`rigid_limit_sweep`].
#[derive(Debug, Clone)]
pub struct RigidLimit {
    /// One row per stiffness, in the order given.
    pub rows: Vec<RigidLimitRow>,
    /// The rigid solution at every vertex.
    pub rigid_u: Vec<f64>,
    /// The contact estimate of the rigid solution.
    pub rigid_contact: ContactEstimate,
    /// Iterations of the rigid solve.
    pub rigid_iterations: usize,
}

/// The rigid limit (docs/theory.md#limits, `h → ∞`), measured on the finest mesh of
/// `hierarchy`: solves `data` with the obstacle made rigid, then with each constant
/// stiffness of `stiffnesses` (replacing `data.stiffness`; the foundation variant and
/// sampling are kept), and returns the distances between the discrete solutions.
///
/// Errors: a stiffness that is not finite and `> 0`; an assembly or solve failure.
pub fn rigid_limit_sweep(
    hierarchy: &Hierarchy,
    data: &ProblemData,
    stiffnesses: &[f64],
    solver: &Settings,
) -> Result<RigidLimit> {
    if let Some(h) = stiffnesses.iter().find(|h| !(h.is_finite() && **h > 0.0)) {
        return Err(Error::Data(format!(
            "sweep stiffness h = {h} must be finite and > 0"
        )));
    }
    let mesh = hierarchy.finest();
    let rigid_data = ProblemData {
        stiffness: BodyStiffness::Rigid,
        ..*data
    };
    let rigid_model = crate::model::assemble_checked(mesh, &rigid_data, &Extensions::default())?;
    let (rigid, _) = solve_level(&rigid_model, hierarchy, solver)?;
    let rigid_u = rigid_model.to_vertices(&rigid.u);
    let rigid_contact = contact_estimate(mesh, &rigid_model, &rigid.u);
    let mut rows = Vec::with_capacity(stiffnesses.len());
    for &h in stiffnesses {
        let d = ProblemData {
            stiffness: BodyStiffness::Elastic(&h),
            ..*data
        };
        let model = crate::model::assemble_checked(mesh, &d, &Extensions::default())?;
        let t = Instant::now();
        let (s, _) = solve_level(&model, hierarchy, solver)?;
        let solve_seconds = t.elapsed().as_secs_f64();
        let u = model.to_vertices(&s.u);
        let diff: Vec<f64> = u.iter().zip(&rigid_u).map(|(a, b)| a - b).collect();
        let [l2, h1_semi, max_nodal] = p1_norms(mesh, &diff);
        rows.push(RigidLimitRow {
            h,
            max_nodal,
            h1_semi,
            l2,
            contact: contact_estimate(mesh, &model, &s.u),
            method: s.method,
            iterations: s.iterations,
            solve_seconds,
        });
    }
    Ok(RigidLimit {
        rows,
        rigid_u,
        rigid_contact,
        rigid_iterations: rigid.iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FnCoefficient;
    use crate::mesh::generate::{self, Diagonal, RectangleSpec};
    use crate::model::{Foundation, Sampling};
    use crate::verify::exact::{DiskSolution, Manufactured};

    fn settings(levels: usize) -> StudySettings {
        StudySettings {
            levels,
            solver: Settings {
                method: Method::ActiveSet,
                ..Settings::default()
            },
        }
    }

    fn last(r: &[Option<f64>]) -> f64 {
        r.last().copied().flatten().expect("a rate")
    }

    /// The disc of `examples/disk.toml` (t = 1, f = 8, h = 100, φ = 1), size 0.2 + 3 levels.
    fn disc_study(foundation: Foundation) -> Study {
        let exact = DiskSolution::new([0.0, 0.0], 1.0, 1.0, 8.0, Some(100.0), 1.0).unwrap();
        let mesh = generate::disk([0.0, 0.0], 1.0, 0.2).unwrap();
        let data = ProblemData {
            tension: 1.0,
            load: &8.0,
            shape: &1.0,
            stiffness: BodyStiffness::Elastic(&100.0),
            foundation,
            sampling: Sampling::Nodal,
        };
        run(
            Hierarchy::single(mesh),
            &data,
            Target::Exact(&exact),
            &settings(3),
            &mut |_| {},
        )
        .unwrap()
    }

    #[test]
    fn disc_converges_at_the_optimal_rates_consistent_and_lumped() {
        for foundation in [Foundation::Consistent, Foundation::Lumped] {
            let s = disc_study(foundation);
            assert_eq!(s.levels.len(), 4);
            let (l2, h1) = (last(&s.l2_rates), last(&s.h1_rates));
            assert!(h1 >= 0.9, "{foundation:?}: H¹ rate {h1}");
            assert!(l2 >= 1.8, "{foundation:?}: L² rate {l2}");
            // Errors decrease at every level, and the contact radius converges.
            for w in s.levels.windows(2) {
                let (a, b) = (w[0].errors.unwrap(), w[1].errors.unwrap());
                assert!(b.l2 < a.l2 && b.h1_semi < a.h1_semi);
            }
            let r = s.levels.last().unwrap().contact_radius_error.unwrap();
            assert!(r < 5e-3, "{foundation:?}: contact radius error {r}");
            // Successive differences shrink at about the H¹ rate too.
            assert!(last(&s.h1_increment_rates) > 0.8);
            for r in &s.levels {
                assert!(r.kkt <= 1e-10 && r.note.is_none());
            }
        }
    }

    /// What a manufactured test study is measured against.
    enum Against {
        Exact,
        Finest,
        Discrete(Vec<f64>),
    }

    /// The manufactured case: unit square (4 × 4 cells, 4 levels), t = 1.5, varying h and
    /// φ, contact on part of the square.
    fn manufactured_study(
        foundation: Foundation,
        against: Against,
        levels: usize,
    ) -> Result<Study> {
        let exact = Manufactured::rectangle(0.0, 0.0, 1.0, 1.0, 1.0).unwrap();
        let h = FnCoefficient(|p: Point| 50.0 * (1.0 + p[1]));
        let phi = FnCoefficient(|p: Point| 0.55 + 0.3 * (p[0] - 0.5).powi(2) + 0.1 * p[1]);
        let load = ManufacturedLoad {
            exact: &exact,
            tension: 1.5,
            stiffness: &h,
            shape: &phi,
            lower: None,
        };
        let base = generate::rectangle(&RectangleSpec {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            nx: 4,
            ny: 4,
            diagonal: Diagonal::Right,
        })
        .unwrap();
        let data = ProblemData {
            tension: 1.5,
            load: &load,
            shape: &phi,
            stiffness: BodyStiffness::Elastic(&h),
            foundation,
            sampling: Sampling::Nodal,
        };
        let target = match &against {
            Against::Exact => Target::Exact(&exact),
            Against::Finest => Target::Finest,
            Against::Discrete(u) => Target::Discrete(u),
        };
        run(base, &data, target, &settings(levels), &mut |_| {})
    }

    #[test]
    fn manufactured_converges_at_the_optimal_rates_consistent_and_lumped() {
        for foundation in [Foundation::Consistent, Foundation::Lumped] {
            let s = manufactured_study(foundation, Against::Exact, 4).unwrap();
            let (l2, h1) = (last(&s.l2_rates), last(&s.h1_rates));
            assert!(h1 >= 0.9, "{foundation:?}: H¹ rate {h1}");
            assert!(l2 >= 1.8, "{foundation:?}: L² rate {l2}");
            // There is contact (and not everywhere).
            let c = s.levels.last().unwrap().contact.area;
            assert!(c > 0.05 && c < 0.9, "contact area {c}");
            // No contact radius is known for a manufactured solution.
            assert!(s.levels[0].contact_radius_error.is_none());
        }
    }

    #[test]
    fn reference_solution_mode_matches_the_exact_rates() {
        let s = manufactured_study(Foundation::Consistent, Against::Finest, 4).unwrap();
        let finest = s.levels.last().unwrap();
        assert!(finest.errors.is_none());
        // Against the finest level the coarse errors look like the exact ones.
        let e = s.levels[1].errors.unwrap();
        let exact = manufactured_study(Foundation::Consistent, Against::Exact, 4).unwrap();
        let x = exact.levels[1].errors.unwrap();
        assert!((e.h1_semi / x.h1_semi - 1.0).abs() < 0.1, "{e:?} {x:?}");
        let r = s.h1_rates[s.h1_rates.len() - 2].unwrap();
        assert!(r > 0.9, "H¹ rate against the reference {r}");
        // A discrete target equal to the finest solution gives the same numbers.
        let d = manufactured_study(
            Foundation::Consistent,
            Against::Discrete(s.finest_u.clone()),
            4,
        )
        .unwrap();
        assert_eq!(d.levels[1].errors.unwrap().l2, e.l2);
        assert_eq!(d.levels[4].errors.unwrap().l2, 0.0);
        // A reference of the wrong size, or no level, is an error.
        let e = manufactured_study(Foundation::Consistent, Against::Discrete(vec![0.0; 3]), 1)
            .unwrap_err();
        assert!(e.to_string().contains("reference"), "{e}");
        let e = manufactured_study(Foundation::Consistent, Against::Exact, 0).unwrap_err();
        assert!(e.to_string().contains("levels"), "{e}");
    }

    #[test]
    fn rigid_limit_distance_decreases_monotonically() {
        let mesh = generate::disk([0.0, 0.0], 1.0, 0.1).unwrap();
        let h = Hierarchy::single(mesh);
        let data = ProblemData {
            tension: 1.0,
            load: &8.0,
            shape: &1.0,
            stiffness: BodyStiffness::Elastic(&0.0),
            foundation: Foundation::Consistent,
            sampling: Sampling::Nodal,
        };
        let hs: Vec<f64> = (1..=6).map(|k| 10f64.powi(k)).collect();
        let solver = Settings {
            method: Method::ActiveSet,
            ..Settings::default()
        };
        let sweep = rigid_limit_sweep(&h, &data, &hs, &solver).unwrap();
        for w in sweep.rows.windows(2) {
            assert!(
                w[1].max_nodal < w[0].max_nodal && w[1].h1_semi < w[0].h1_semi,
                "h = {} → {}: {:?} {:?}",
                w[0].h,
                w[1].h,
                w[0],
                w[1]
            );
            // The contact zone shrinks towards the rigid one.
            assert!(w[1].contact.area <= w[0].contact.area);
        }
        let last = sweep.rows.last().unwrap();
        assert!(last.max_nodal < 1e-3, "{last:?}");
        // The discrete rigid solution is close to the exact one (classical obstacle problem).
        let exact = DiskSolution::new([0.0, 0.0], 1.0, 1.0, 8.0, None, 1.0).unwrap();
        let e = error_norms(h.finest(), &sweep.rigid_u, &exact).unwrap();
        assert!(e.max_nodal < 1e-2, "{e:?}");
        assert!(rigid_limit_sweep(&h, &data, &[0.0], &solver).is_err());
    }

    #[test]
    fn positive_fraction_is_exact() {
        assert_eq!(positive_fraction([1.0, 1.0, 1.0]), 1.0);
        assert_eq!(positive_fraction([-1.0, 0.0, -2.0]), 0.0);
        // g = x on the triangle (0,0), (1,0), (0,1) shifted: g = x − ½ is positive on a
        // corner triangle of area ⅛ out of ½.
        assert!((positive_fraction([-0.5, 0.5, -0.5]) - 0.25).abs() < 1e-15);
        // and its complement
        assert!((positive_fraction([0.5, -0.5, 0.5]) - 0.75).abs() < 1e-15);
        assert_eq!(positive_fraction([0.0, 1.0, 1.0]), 1.0);
        assert_eq!(positive_fraction([2.0, 0.0, 0.0]), 1.0);
    }

    #[test]
    fn p1_norms_are_exact_for_linear_functions() {
        let mesh = generate::rectangle(&RectangleSpec {
            x0: 0.0,
            y0: 0.0,
            x1: 2.0,
            y1: 1.0,
            nx: 3,
            ny: 2,
            diagonal: Diagonal::Alternate,
        })
        .unwrap()
        .finest()
        .clone();
        // e = x + 2y: ∫ e² over [0,2]×[0,1] = 28/3, |∇e|² = 5 on area 2.
        let e: Vec<f64> = mesh.points.iter().map(|p| p[0] + 2.0 * p[1]).collect();
        let [l2, h1, max] = p1_norms(&mesh, &e);
        assert!((l2 * l2 - 28.0 / 3.0).abs() < 1e-12, "{l2}");
        assert!((h1 * h1 - 10.0).abs() < 1e-12, "{h1}");
        assert_eq!(max, 4.0);
    }
}
