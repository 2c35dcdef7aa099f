//! The adaptive loop itself ([`run_adapt`]), as the module's overview describes it.

use super::row::AdaptRow;
use super::{bisect, estimate::estimate, mark};
use crate::case::{AdaptSpec, Case};
use crate::discretization::{build_mesh, check_case_on_mesh, BoundData, Discretization};
use crate::error::{Error, Invalid, Result};
use crate::field::{Field, Stiffness};
use crate::mesh::boundary::FixedBoundary;
use crate::mesh::refine::{Hierarchy, Refinement};
use crate::mesh::reorder::renumbering_for_locality;
use crate::mesh::{Mesh, VertexTriangles};
use crate::outcome::summary::AdaptTotals;
use crate::outcome::Outcome;
use crate::problem::Problem;
use crate::solve::{Cancellable, Observer};
use rayon::prelude::*;
use std::time::Instant;

/// Why the adaptive loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdaptStop {
    /// The estimator met `[adapt] tolerance`.
    Tolerance,
    /// `[adapt] steps` were solved.
    Steps,
    /// The next mesh would have had more than `[adapt] max_vertices` vertices.
    MaxVertices,
    /// A step's solve was not accepted by the settings (its outcome is the last).
    NotAccepted,
    /// A step's estimator was not a finite number (the step before it is the last).
    EstimatorNotFinite,
    /// The next mesh would not fit in the memory available (the error says how much).
    Memory,
}

impl AdaptStop {
    /// The name in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            AdaptStop::Tolerance => "tolerance",
            AdaptStop::Steps => "steps",
            AdaptStop::MaxVertices => "max_vertices",
            AdaptStop::NotAccepted => "not_accepted",
            AdaptStop::EstimatorNotFinite => "estimator_not_finite",
            AdaptStop::Memory => "memory",
        }
    }
}

/// What the adaptive loop produced.
#[derive(Debug)]
pub struct AdaptRun {
    /// One row per step solved (the rows of `adapt.csv`).
    pub rows: Vec<AdaptRow>,
    /// The last step kept: its mesh is the final mesh.
    pub outcome: Outcome,
    /// η_T² of the last step kept, per triangle of its mesh in the user's order.
    pub indicators: Vec<f64>,
    /// Why the loop stopped.
    pub stop: AdaptStop,
    /// The error that stopped it (a solve not accepted, an estimator not finite, a mesh
    /// beyond the memory available).
    pub error: Option<Error>,
    /// The keys of the data given per vertex that were interpolated onto new vertices.
    pub interpolated: Vec<String>,
    /// The case's problem with its data on the final mesh (per-vertex arrays
    /// interpolated): what the last step solved.
    pub problem: Problem,
    /// Seconds of the whole loop.
    pub seconds: f64,
}

/// What the loop tells its caller after every step: the step's row, its outcome and its
/// η_T² in the user's triangle order. An error stops the loop with that error.
pub type OnStep<'a> = dyn FnMut(&AdaptRow, &Outcome, &[f64]) -> Result<()> + 'a;

impl AdaptRun {
    /// The loop's totals for `summary.json`.
    pub fn totals(&self) -> AdaptTotals {
        AdaptTotals {
            adapt_steps: self.rows.len(),
            adapt_estimator: self.rows.last().map_or(f64::NAN, |r| r.estimator),
            adapt_start_vertices: self.rows.first().map_or(0, |r| r.vertices),
            adapt_iterations: self.rows.iter().map(|r| r.iterations).sum(),
            adapt_seconds: self.seconds,
            adapt_stop: self.stop.name().to_string(),
            adapt_interpolated: self.interpolated.clone(),
        }
    }
}

/// Runs the adaptive loop of `case` (which needs an `[adapt]` section). `on_step` sees
/// every step as soon as it is solved and estimated: its row, its outcome and its η_T² in
/// the user's triangle order (to write or draw it). Bad input is an `Err`.
pub fn run_adapt(
    case: &Case,
    observer: &mut dyn Observer,
    on_step: &mut OnStep<'_>,
) -> Result<AdaptRun> {
    case.validate().map_err(Invalid::into_error)?;
    let Some(spec) = case.adapt.clone() else {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "adapt".into(),
            message: "the case has no [adapt] section".into(),
        });
    };
    let started = Instant::now();
    let observer = &mut Cancellable::new(observer, &case.settings.cancel);
    let (mut hierarchy, warnings) = build_mesh(&case.problem.mesh)?;
    // The refinement edge of every triangle: its longest (once, on the start mesh).
    let labelled = bisect::label_longest_edge(hierarchy.finest());
    *hierarchy.levels.last_mut().expect("a level") = labelled;
    check_adapt_on_mesh(&spec, hierarchy.finest())?;
    let mut problem = case.problem.clone();
    let mut interpolated = Vec::new();
    let mut start: Option<Vec<f64>> = None;
    let mut rows = Vec::new();
    let mut kept: Option<(Outcome, Vec<f64>)> = None;
    let mut step = 0;
    let (stop, error) = loop {
        case.settings.cancel.check()?;
        let t0 = Instant::now();
        observer.step_started(step, spec.steps, &format!("step {step}"));
        let mut discretization = Discretization::assemble(&problem, hierarchy.clone(), observer)?;
        if step == 0 {
            discretization.warnings = warnings.clone();
            check_case_on_mesh(case, discretization.mesh(), false)?;
        }
        // The multigrid levels: the previous step's, with this step's mesh on top.
        if discretization.solves_on_mesh_levels(&case.settings) {
            let counts = discretization.hierarchy.vertex_counts();
            let previous = kept.as_mut().and_then(|(o, _)| {
                let levels = o.discretization.take_levels()?;
                Some((levels, &o.discretization.model.dofs))
            });
            discretization.build_levels(&counts, previous, observer)?;
        }
        let start_unknowns = start.as_ref().map(|values| {
            let mesh = discretization.mesh();
            let values = mesh.vertex_values_from_user(values);
            discretization
                .model
                .dofs
                .vertex
                .iter()
                .map(|&v| values[v as usize])
                .collect::<Vec<f64>>()
        });
        let report =
            discretization.solve_from(&case.settings, start_unknowns.as_deref(), observer)?;
        let outcome = Outcome {
            discretization,
            report,
        };
        let indicators = match indicators(&problem, &outcome) {
            Ok(ind) => ind,
            Err(e @ Error::Data(_)) if kept.is_some() => {
                break (AdaptStop::EstimatorNotFinite, Some(e));
            }
            Err(e) => return Err(e),
        };
        let total = indicators.iter().sum::<f64>().sqrt();
        let row = AdaptRow::of(step, &outcome, total, t0.elapsed().as_secs_f64());
        on_step(&row, &outcome, &indicators)?;
        rows.push(row);
        let accepted = outcome.report.accepted;
        let error = outcome.report.error();
        let (fields, _) = outcome.fields();
        let u_user = fields.u.clone();
        let contact_up: Vec<bool> = fields.state.iter().map(|&s| s >= 0).collect();
        let contact_low: Option<Vec<bool>> = fields
            .lower
            .as_ref()
            .map(|l| l.state.iter().map(|&s| s >= 0).collect());
        drop(fields);
        kept = Some((outcome, indicators));
        if !accepted {
            break (AdaptStop::NotAccepted, error);
        }
        if spec.tolerance.is_some_and(|tol| total <= tol) {
            break (AdaptStop::Tolerance, None);
        }
        if step + 1 >= spec.steps {
            break (AdaptStop::Steps, None);
        }
        // Mark, on the mesh in the user's numbering.
        let mesh = hierarchy.finest();
        let eta2 = &kept.as_ref().expect("kept").1;
        let bulk = mark::dorfler(eta2, spec.theta)?;
        let mut marked = bulk.clone();
        let rings = spec.free_boundary_rings;
        if rings > 0 {
            let mut sets = vec![mark::free_boundary(mesh, &contact_up, rings)?];
            if let Some(low) = &contact_low {
                sets.push(mark::free_boundary(mesh, low, rings)?);
            }
            let refs: Vec<&[u32]> = sets.iter().map(Vec::as_slice).collect();
            let free = mark::largest(mesh, &mark::union(&refs), &bulk, bulk.len());
            marked = mark::union(&[&bulk, &free]);
        }
        let max = spec.max_vertices.unwrap_or(usize::MAX);
        let Some(b) = bisect::bisect_within(mesh, &marked, max)? else {
            break (AdaptStop::MaxVertices, None);
        };
        // Without refinements the check reads the vertices and triangles alone: the edges
        // are not counted (that would cost a pass over the mesh's adjacency every step).
        let size = crate::limits::MeshSize::simply_connected(
            b.mesh.n_vertices() as f64,
            b.mesh.n_triangles() as f64,
        );
        if let Err(e) = crate::limits::check_mesh_fits(
            size,
            0,
            &format!("the adaptive loop's step {}", step + 1),
        ) {
            break (AdaptStop::Memory, Some(e));
        }
        start = Some(b.refinement.prolongate(&u_user));
        interpolate_nodal(&mut problem, &b.refinement, &mut interpolated);
        let mut refinement = b.refinement;
        renumber_finished_level(&mut hierarchy, &mut refinement);
        hierarchy.levels.push(b.mesh);
        hierarchy.refinements.push(refinement);
        step += 1;
    };
    let (mut outcome, indicators) = kept.expect("step 0 is kept or is an error");
    // Only a next step would extend the multigrid levels: they go before the writing.
    outcome.discretization.release_levels();
    Ok(AdaptRun {
        rows,
        outcome,
        indicators,
        stop,
        error,
        interpolated,
        problem,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The finest level of `hierarchy`, solved and refined (`next` leads from it to the next
/// mesh), renumbered for locality as every step's discretization would renumber it, with
/// the relations into and out of it renumbered to match. Done once here, so that every
/// later step finds this coarse level's order already local and keeps it instead of
/// renumbering every level of the growing hierarchy again; every level ends with the
/// numbering it had before, so the results are the same.
fn renumber_finished_level(hierarchy: &mut Hierarchy, next: &mut Refinement) {
    let last = hierarchy.levels.len() - 1;
    let Some(order) = renumbering_for_locality(&hierarchy.levels[last]) else {
        return;
    };
    let order = std::sync::Arc::new(order);
    hierarchy.levels[last] = order.apply_shared(&hierarchy.levels[last]);
    let (new_of_old, old_of_new) = (&order.vertices.new_of_old, &order.vertices.old_of_new);
    if let Some(into) = last.checked_sub(1).map(|k| &mut hierarchy.refinements[k]) {
        into.parents = old_of_new
            .par_iter()
            .with_min_len(8192)
            .map(|&old| into.parents[old as usize])
            .collect();
    }
    next.parents
        .par_iter_mut()
        .with_min_len(8192)
        .for_each(|p| {
            *p = p.map(|c| new_of_old[c as usize]);
        });
}

/// The checks of `[adapt]` that need the start mesh: `max_vertices` at least its vertices,
/// and a mesh of `max_vertices` vertices within the memory available. `check` and the
/// loop call it.
pub fn check_adapt_on_mesh(spec: &AdaptSpec, start: &Mesh) -> Result<()> {
    let Some(max) = spec.max_vertices else {
        return Ok(());
    };
    let start_vertices = start.n_vertices();
    if max < start_vertices {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "adapt.max_vertices".into(),
            message: format!(
                "is {max}, below the start mesh's {start_vertices} vertices: raise it, or \
                 start from a coarser mesh"
            ),
        });
    }
    // A triangulation has about twice as many triangles as vertices.
    let m = max as f64;
    crate::limits::check_mesh_fits(
        crate::limits::MeshSize::simply_connected(m, 2.0 * m),
        0,
        &format!("adapt.max_vertices = {max}"),
    )
}

/// η_T² of a solved step, per triangle in the user's order.
fn indicators(problem: &Problem, outcome: &Outcome) -> Result<Vec<f64>> {
    let d = &outcome.discretization;
    let mesh = d.mesh();
    let bound = BoundData::new(problem, mesh)?;
    let free = free_edges(mesh, &problem.boundary.free)?;
    let ind = estimate(
        mesh,
        &d.model,
        &bound.load,
        &bound.shape,
        &free,
        &outcome.report.u,
    )?;
    Ok(match &mesh.numbering {
        Some(n) => n.triangles.to_old(&ind.eta2),
        None => ind.eta2,
    })
}

/// The boundary edges with the natural condition: those of the regions `free` names.
fn free_edges(mesh: &Mesh, free: &[String]) -> Result<Vec<[u32; 2]>> {
    if free.is_empty() {
        return Ok(Vec::new());
    }
    let adj = VertexTriangles::new(mesh);
    let fixed = FixedBoundary::new(mesh, &adj, free)?;
    let held: std::collections::HashSet<(u32, u32)> = fixed
        .edges
        .iter()
        .map(|&([a, b], _)| (a.min(b), a.max(b)))
        .collect();
    Ok(mesh
        .boundary_edges_with(&adj)
        .into_iter()
        .filter(|&[a, b]| !held.contains(&(a.min(b), a.max(b))))
        .collect())
}

/// The data given per vertex, carried onto the new vertices of `refinement` by P1
/// interpolation; `names` collects their keys.
fn interpolate_nodal(
    problem: &mut Problem,
    refinement: &crate::mesh::refine::Refinement,
    names: &mut Vec<String>,
) {
    let mut carry = |key: &str, f: &mut Field| {
        if let Field::Nodal(values) = f {
            *values = refinement.prolongate(values).into();
            if !names.iter().any(|n| n == key) {
                names.push(key.to_string());
            }
        }
    };
    carry("membrane.load", &mut problem.membrane.load);
    carry("obstacle.shape", &mut problem.obstacle.shape);
    if let Stiffness::Elastic(h) = &mut problem.obstacle.stiffness {
        carry("obstacle.stiffness", h);
    }
    carry("boundary.height", &mut problem.boundary.height);
    if let Some(low) = &mut problem.lower {
        carry("lower.shape", &mut low.shape);
        if let Stiffness::Elastic(h) = &mut low.stiffness {
            carry("lower.stiffness", h);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adapt::bisect::{bisect, label_longest_edge};

    /// The loop's hierarchy after `steps` bisections of the triangles near one corner of
    /// the unit square, with or without renumbering each finished level as the loop does.
    fn grown(steps: usize, renumber: bool) -> Hierarchy {
        let mut h = Hierarchy::single(label_longest_edge(&crate::mesh::test_square(10)));
        for _ in 0..steps {
            let mesh = h.finest();
            let marked: Vec<u32> = (0..mesh.n_triangles() as u32)
                .filter(|&k| {
                    let c = mesh.triangles[k as usize].map(|v| mesh.points[v as usize]);
                    c.iter().all(|p| p[0] + 2.0 * p[1] < 0.9)
                })
                .collect();
            let b = bisect(mesh, &marked).unwrap();
            let mut refinement = b.refinement;
            if renumber {
                renumber_finished_level(&mut h, &mut refinement);
            }
            h.levels.push(b.mesh);
            h.refinements.push(refinement);
        }
        h
    }

    #[test]
    fn levels_renumbered_once_are_those_every_step_would_renumber() {
        let (plain, once) = (grown(6, false), grown(6, true));
        let (a, orders_a) = plain.reordered();
        let (b, orders_b) = once.reordered();
        // Without the loop's renumbering, bisected levels are scattered and renumbered at
        // every step; with it, only the newest level is left to renumber.
        let renumbered = |o: &[Option<_>]| o.iter().filter(|x| x.is_some()).count();
        assert!(renumbered(&orders_a[..6]) >= 2);
        assert_eq!(renumbered(&orders_b[..6]), 0);
        // The same numbering of every level and the same relations between them.
        for (k, (ma, mb)) in a.levels.iter().zip(&b.levels).enumerate() {
            assert_eq!(ma.points, mb.points, "level {k}");
            assert_eq!(ma.triangles, mb.triangles, "level {k}");
            assert_eq!(ma.regions, mb.regions, "level {k}");
        }
        for (k, (ra, rb)) in a.refinements.iter().zip(&b.refinements).enumerate() {
            assert_eq!(ra.parents, rb.parents, "relation {k}");
        }
    }
}
