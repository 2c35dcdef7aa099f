//! `summary.json`: the scalar results of a run, as one serde struct. Its keys are a
//! contract with users (scripts read them): extend, never rename.

use crate::mesh::MeshQuality;
use crate::outcome::fields::Totals;
use crate::outcome::Outcome;
use crate::solve::{Choice, Fallback, IterationRecord, Status};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One output file of a result set: its size and a hash of its bytes, so that a directory
/// mixing the files of two runs can be detected.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileRecord {
    /// Size in bytes.
    pub bytes: u64,
    /// XXH3-64 of the bytes, 16 hex digits.
    pub xxh3: String,
}

impl From<crate::io::Written> for FileRecord {
    fn from(w: crate::io::Written) -> FileRecord {
        FileRecord {
            bytes: w.bytes,
            xxh3: w.hex(),
        }
    }
}

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    /// The case (file path, or a label for a case built in code).
    pub case: String,
    /// Mesh vertices.
    pub vertices: usize,
    /// Mesh triangles.
    pub triangles: usize,
    /// Unknowns m (interior vertices).
    pub unknowns: usize,
    /// Mesh levels (1 without a refinement hierarchy).
    pub levels: usize,
    /// The largest triangle diameter l_n.
    pub l_n: f64,
    /// The largest ratio diameter / inscribed-circle diameter s_n.
    pub s_n: f64,
    /// The smallest angle of the mesh, degrees.
    pub min_angle_deg: f64,
    /// The area of Ω_n.
    pub area: f64,
    /// The method that produced the answer.
    pub solver: String,
    /// `consistent`, `lumped` or `rigid`.
    pub foundation: String,
    /// Whether the obstacle is rigid.
    pub rigid: bool,
    /// `nodal` or `mollified`.
    pub sampling: String,
    /// The mollifier radius, for mollified sampling.
    pub epsilon: Option<f64>,
    /// The tension t.
    pub tension: f64,
    /// The tolerance on the scaled KKT residual.
    pub tolerance: f64,
    /// Iterations of the method.
    pub iterations: usize,
    /// J(U).
    pub energy: f64,
    /// The larger of the two residuals below.
    pub kkt_residual: f64,
    /// The scaled residual of the Kuhn-Tucker system 2e.
    pub residual_2e: f64,
    /// The scaled residual of the complementarity problem 2f.
    pub residual_2f: f64,
    /// The force the residuals are divided by (the largest force of the iterate).
    pub force_scale: f64,
    /// The rounding floor of the residuals at U: what double precision can resolve.
    pub rounding_floor: f64,
    /// |M|: unknowns the obstacle can touch.
    pub can_touch_vertices: usize,
    /// Vertices in contact (touching or penetrating).
    pub contact_vertices: usize,
    /// Vertices exactly on φ.
    pub touching_vertices: usize,
    /// Vertices above φ.
    pub penetrating_vertices: usize,
    /// Unknowns clear of the obstacle.
    pub clear_vertices: usize,
    /// Σ |Qᵢ|/3 over the vertices in contact.
    pub contact_area: f64,
    /// ∫ f.
    pub total_load: f64,
    /// Σ X₁.
    pub total_contact_force: f64,
    /// max |u|.
    pub max_deflection: f64,
    /// Area covered by the body where the membrane is clear of it.
    pub liftoff_area: f64,
    /// The largest contact pressure.
    pub max_pressure: f64,
    /// min u.
    pub min_u: f64,
    /// max u.
    pub max_u: f64,
    /// Energy and residual per iteration.
    pub history: Vec<IterationRecord>,
    /// The solver's phases, seconds.
    pub solver_phases_s: BTreeMap<String, f64>,
    /// Seconds reading or generating the mesh.
    pub time_mesh_s: f64,
    /// Seconds assembling S, L, D, φₙ.
    pub time_assembly_s: f64,
    /// Seconds solving.
    pub time_solve_s: f64,
    /// Seconds writing the outputs.
    pub time_write_s: f64,
    /// Seconds from start to end.
    pub time_total_s: f64,
    /// How the solve ended (`converged`, `iteration_limit`, `stalled`,
    /// `numerical_failure`).
    pub status: Status,
    /// `status == converged`: the residual meets the tolerance.
    pub converged: bool,
    /// The outcome is accepted: converged, or at the rounding floor of double precision
    /// when the settings accept that. Files written with `false` hold an unaccepted iterate.
    pub accepted: bool,
    /// The method the case asked for (maybe `auto`).
    pub requested_solver: String,
    /// Why `solver` was used.
    pub solver_choice: Choice,
    /// The method `auto` tried first and gave up on.
    pub fallback: Option<Fallback>,
    /// What went wrong, for a numerical failure.
    pub message: Option<String>,
    /// The multigrid method's coarse levels: `geometric` (the mesh's refinement levels) or
    /// `algebraic` (aggregation); absent for the other methods.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hierarchy: Option<crate::solve::multigrid::Kind>,
    /// A random identifier of this run, shared by the files of its result set.
    pub run_id: String,
    /// A hash of the case (XXH3-64 of its canonical JSON), to tell inputs apart.
    pub input_hash: String,
    /// The other files of the result set, by name.
    pub files: BTreeMap<String, FileRecord>,
    /// How the pictures were drawn (so `memcontact plot` redraws them identically).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plot_options: Option<serde_json::Value>,
    /// Vertices on the fixed boundary Γ_D (present with boundary heights or free edges).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_vertices: Option<usize>,
    /// Boundary vertices on free edges only (they carry unknowns).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_boundary_vertices: Option<usize>,
    /// Unknowns the obstacle holds rigidly when it is rigid in some regions only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid_vertices: Option<usize>,
    /// The body below: `consistent`, `lumped` or `rigid` (present with a body below).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_foundation: Option<String>,
    /// Whether the body below is rigid everywhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_rigid: Option<bool>,
    /// Unknowns the body below holds rigidly when it is rigid in some regions only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid_low_vertices: Option<usize>,
    /// Unknowns the body below can touch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub can_touch_low_vertices: Option<usize>,
    /// Vertices in contact with the body below (touching or sunk into it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_low_vertices: Option<usize>,
    /// Vertices exactly on the body below.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub touching_low_vertices: Option<usize>,
    /// Vertices sunk into the body below.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub penetrating_low_vertices: Option<usize>,
    /// Vertices in contact with both bodies at once.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub squeezed_vertices: Option<usize>,
    /// Σ |Qᵢ|/3 over the vertices in contact with the body below.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_area_low: Option<f64>,
    /// The body below's total force on the membrane (positive pushing up).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub total_contact_force_low: Option<f64>,
    /// The body below's largest contact pressure.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_pressure_low: Option<f64>,
    /// Area where the body below lies under the membrane but the membrane is clear of it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub liftoff_area_low: Option<f64>,
    /// The adaptive loop's totals (with `[adapt]`).
    #[serde(default, flatten, skip_serializing_if = "Option::is_none")]
    pub adapt: Option<AdaptTotals>,
    /// The sensitivity run's totals (with `[sensitivity]`).
    #[serde(default, flatten, skip_serializing_if = "Option::is_none")]
    pub sensitivity: Option<super::SensitivityTotals>,
}

/// The totals of an adaptive loop, in `summary.json` beside the final step's values.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AdaptTotals {
    /// Steps solved (the start mesh's solve is step 0).
    pub adapt_steps: usize,
    /// The final step's estimator η.
    pub adapt_estimator: f64,
    /// The start mesh's vertices.
    pub adapt_start_vertices: usize,
    /// Iterations of all steps together.
    pub adapt_iterations: usize,
    /// Seconds of all steps together (refinement, assembly, solve, estimate).
    pub adapt_seconds: f64,
    /// Why the loop stopped: `tolerance`, `steps`, `max_vertices`, `not_accepted`,
    /// `estimator_not_finite`, `memory`.
    pub adapt_stop: String,
    /// The data given per vertex that were interpolated (P1) onto the new vertices.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub adapt_interpolated: Vec<String>,
}

impl Summary {
    /// The summary of `outcome` (`totals` from its fields, `quality` of its mesh); the write
    /// time, total time, run identity and files are filled in by the writer.
    pub fn new(case: &str, outcome: &Outcome, quality: &MeshQuality, totals: &Totals) -> Summary {
        let r = &outcome.report;
        let m = &outcome.discretization.model;
        Summary {
            case: case.to_string(),
            vertices: quality.vertices,
            triangles: quality.triangles,
            unknowns: m.n(),
            levels: outcome.discretization.hierarchy.depth(),
            l_n: quality.l_n,
            s_n: quality.s_n,
            min_angle_deg: quality.min_angle_deg,
            area: quality.area,
            solver: r.method.name().into(),
            foundation: if m.is_rigid() {
                "rigid".into()
            } else {
                m.foundation.name().into()
            },
            rigid: m.is_rigid(),
            sampling: if m.epsilon.is_some() {
                "mollified".into()
            } else {
                "nodal".into()
            },
            epsilon: m.epsilon,
            tension: m.tension,
            tolerance: r.tolerance,
            iterations: r.iterations,
            energy: r.energy,
            kkt_residual: r.certificate.kkt(),
            residual_2e: r.certificate.residual_2e,
            residual_2f: r.certificate.residual_2f,
            force_scale: r.certificate.force_scale,
            rounding_floor: r.certificate.rounding_floor,
            can_touch_vertices: m.can_touch.iter().filter(|&&c| c).count(),
            contact_vertices: totals.contact_vertices,
            touching_vertices: totals.touching_vertices,
            penetrating_vertices: totals.penetrating_vertices,
            clear_vertices: totals.clear_vertices,
            contact_area: totals.contact_area,
            total_load: totals.total_load,
            total_contact_force: totals.total_contact_force,
            max_deflection: totals.max_deflection,
            liftoff_area: totals.liftoff_area,
            max_pressure: totals.max_pressure,
            min_u: totals.min_u,
            max_u: totals.max_u,
            history: r.history.clone(),
            solver_phases_s: r
                .solver_phases
                .iter()
                .map(|p| (p.name.clone(), p.seconds))
                .collect(),
            time_mesh_s: r.seconds("mesh"),
            time_assembly_s: r.seconds("assembly"),
            time_solve_s: r.seconds("solve"),
            time_write_s: 0.0,
            time_total_s: 0.0,
            status: r.status,
            converged: r.status.is_converged(),
            accepted: r.accepted,
            requested_solver: r.requested.name().into(),
            solver_choice: r.choice,
            fallback: r.fallback.clone(),
            message: r.message.clone(),
            hierarchy: r.coarsening,
            run_id: String::new(),
            input_hash: String::new(),
            files: BTreeMap::new(),
            plot_options: None,
            fixed_vertices: None,
            free_boundary_vertices: None,
            rigid_vertices: m.rigid.as_ref().map(|r| r.iter().filter(|&&x| x).count()),
            lower_foundation: m.lower.as_ref().map(|b| {
                if b.l.is_rigid() {
                    "rigid".to_string()
                } else {
                    b.foundation.name().to_string()
                }
            }),
            lower_rigid: m.lower.as_ref().map(|b| b.l.is_rigid()),
            rigid_low_vertices: m
                .lower
                .as_ref()
                .and_then(|b| b.rigid.as_ref())
                .map(|r| r.iter().filter(|&&x| x).count()),
            can_touch_low_vertices: totals.lower.map(|t| t.can_touch_low_vertices),
            contact_low_vertices: totals.lower.map(|t| t.contact_low_vertices),
            touching_low_vertices: totals.lower.map(|t| t.touching_low_vertices),
            penetrating_low_vertices: totals.lower.map(|t| t.penetrating_low_vertices),
            squeezed_vertices: totals.lower.map(|t| t.squeezed_vertices),
            contact_area_low: totals.lower.map(|t| t.contact_area_low),
            total_contact_force_low: totals.lower.map(|t| t.total_contact_force_low),
            max_pressure_low: totals.lower.map(|t| t.max_pressure_low),
            liftoff_area_low: totals.lower.map(|t| t.liftoff_area_low),
            adapt: None,
            sensitivity: None,
        }
        .with_boundary(outcome, quality)
    }

    /// The boundary counts, when the case has boundary heights or free edges.
    fn with_boundary(mut self, outcome: &Outcome, quality: &MeshQuality) -> Summary {
        let m = &outcome.discretization.model;
        // Every vertex off the boundary is an unknown: the other unknowns are the free
        // boundary vertices.
        let free = m.n().saturating_sub(quality.unknowns);
        let heights = m.boundary_values.iter().any(|&g| g != 0.0);
        if free > 0 || heights {
            self.fixed_vertices = Some(m.dofs.per_vertex().filter(|d| d.is_none()).count());
            self.free_boundary_vertices = Some(free);
        }
        self
    }
}
