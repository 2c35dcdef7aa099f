//! The adaptive loop (SPEC §6): solve → estimate → mark → refine → solve, from the case's
//! mesh, until the estimator meets `[adapt] tolerance`, the steps run out, or the next
//! mesh would have more than `max_vertices` vertices.
//!
//! - **Estimate**: the residual indicators of [`crate::estimate`] (elastic bodies,
//!   rigid ones and rigid regions, a body below, free edges).
//! - **Mark**: Dörfler's bulk criterion on η_T² with fraction θ, together with the
//!   triangles on the free boundary (those holding both contact and non-contact vertices,
//!   of either body) and `free_boundary_rings` rings of neighbours.
//! - **Refine**: newest-vertex bisection ([`crate::mesh::bisect`]) of the mesh in the
//!   user's numbering (the start mesh labelled by its longest edges once): conforming,
//!   nested and shape-regular, regions and boundary regions carried, new vertices on the
//!   circle of a disc. Every mesh of the loop stays a level of the hierarchy, so
//!   multigrid runs on the nested meshes (the start mesh's own levels below them).
//! - **Solve**: each step starts from the previous answer interpolated onto the new mesh;
//!   data given per vertex are interpolated (P1) onto the new vertices, and the run says
//!   so ([`AdaptRun::interpolated`]).

use super::checks::check_case_on_mesh;
use crate::case::Case;
use crate::discretization::{build_mesh, BoundData, Discretization};
use crate::error::{Error, Invalid, Result};
use crate::estimate::estimate;
use crate::field::{Field, Stiffness};
use crate::mesh::boundary::FixedBoundary;
use crate::mesh::{bisect, mark, Mesh, VertexTriangles};
use crate::outcome::{AdaptRow, Outcome};
use crate::problem::Problem;
use crate::solve::{Cancellable, Observer};
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
    /// The error that stopped it (a solve not accepted, an estimator not finite).
    pub error: Option<Error>,
    /// The keys of the data given per vertex that were interpolated onto new vertices.
    pub interpolated: Vec<String>,
    /// Seconds of the whole loop.
    pub seconds: f64,
}

/// Runs the adaptive loop of `case` (which needs an `[adapt]` section). `on_step` sees
/// every step as soon as it is solved and estimated: its row, its outcome and its η_T² in
/// the user's triangle order (to write or draw it). Bad input is an `Err`.
pub fn run_adapt(
    case: &Case,
    observer: &mut dyn Observer,
    on_step: &mut dyn FnMut(&AdaptRow, &Outcome, &[f64]) -> Result<()>,
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
    let observer = &mut Cancellable {
        inner: observer,
        cancel: &case.settings.cancel,
    };
    let (mut hierarchy, warnings) = build_mesh(&case.problem.mesh)?;
    // The refinement edge of every triangle: its longest (once, on the start mesh).
    let labelled = bisect::label_longest_edge(hierarchy.finest());
    *hierarchy.levels.last_mut().expect("a level") = labelled;
    let start_vertices = hierarchy.finest().n_vertices();
    if let Some(max) = spec.max_vertices {
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
    }
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
        let mut sets = vec![bulk];
        let rings = spec.free_boundary_rings;
        if rings > 0 {
            sets.push(mark::free_boundary(mesh, &contact_up, rings)?);
            if let Some(low) = &contact_low {
                sets.push(mark::free_boundary(mesh, low, rings)?);
            }
        }
        let refs: Vec<&[u32]> = sets.iter().map(Vec::as_slice).collect();
        let marked = mark::union(&refs);
        let b = bisect::bisect(mesh, &marked)?;
        if spec
            .max_vertices
            .is_some_and(|max| b.mesh.n_vertices() > max)
        {
            break (AdaptStop::MaxVertices, None);
        }
        start = Some(b.refinement.prolongate(&u_user));
        interpolate_nodal(&mut problem, &b.refinement, &mut interpolated);
        hierarchy.levels.push(b.mesh);
        hierarchy.refinements.push(b.refinement);
        step += 1;
    };
    let (outcome, indicators) = kept.expect("step 0 is kept or is an error");
    Ok(AdaptRun {
        rows,
        outcome,
        indicators,
        stop,
        error,
        interpolated,
        seconds: started.elapsed().as_secs_f64(),
    })
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
