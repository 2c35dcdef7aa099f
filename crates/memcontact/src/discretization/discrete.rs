//! [`Discretization`]: the discrete problem built once per problem: the mesh levels (read
//! or generated, refined, renumbered for locality) and the model assembled on the finest.

use super::binding::BoundData;
use super::meshing::build_mesh;
use crate::error::{Invalid, Result};
use crate::mesh::refine::Hierarchy;
use crate::mesh::{Mesh, MeshQuality};
use crate::model::Model;
use crate::problem::Problem;
use crate::solve::Observer;
use std::time::Instant;

/// A named phase of a run and its wall-clock seconds.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Phase {
    /// `mesh`, `assembly`, `solve`, ...
    pub name: String,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The discrete problem: the mesh levels (the finest is solved on) and the assembled model
/// of the paper's §2. Built once per problem; solves reuse it.
#[derive(Debug, Clone)]
pub struct Discretization {
    /// The mesh levels; the finest is the solved mesh.
    pub hierarchy: Hierarchy,
    /// S, L, D, φₙ, M on the finest mesh.
    pub model: Model,
    /// The finest mesh's quality report (counts, `l_n`, `s_n`, smallest angle, area).
    pub quality: MeshQuality,
    /// Warnings from reading the mesh (skipped element types, ...).
    pub warnings: Vec<String>,
    /// Wall-clock seconds of `mesh` and `assembly`.
    pub phases: Vec<Phase>,
}

impl Discretization {
    /// Builds the mesh the problem describes and assembles the model on it.
    pub fn new(problem: &Problem, observer: &mut dyn Observer) -> Result<Discretization> {
        problem.validate().map_err(Invalid::into_error)?;
        observer.phase_started("mesh");
        let t0 = Instant::now();
        let (hierarchy, warnings) = build_mesh(&problem.mesh)?;
        let t_mesh = t0.elapsed().as_secs_f64();
        observer.phase_finished("mesh", t_mesh);
        if observer.cancelled() {
            return Err(crate::error::Error::Cancelled);
        }
        let mut d = Discretization::assemble(problem, hierarchy, observer)?;
        d.warnings = warnings;
        d.phases.insert(
            0,
            Phase {
                name: "mesh".into(),
                seconds: t_mesh,
            },
        );
        Ok(d)
    }

    /// Assembles the problem's data on a given mesh hierarchy (the finest level is solved
    /// on; its coarser levels serve multigrid). `problem.mesh` is not used. Levels whose
    /// numbering is scattered are first renumbered for locality
    /// ([`crate::mesh::reorder`]); outputs come back in the user's numbering.
    pub fn assemble(
        problem: &Problem,
        hierarchy: Hierarchy,
        observer: &mut dyn Observer,
    ) -> Result<Discretization> {
        observer.phase_started("reorder");
        let t0 = Instant::now();
        let (hierarchy, _) = hierarchy.reordered();
        let t_reorder = t0.elapsed().as_secs_f64();
        observer.phase_finished("reorder", t_reorder);
        if observer.cancelled() {
            return Err(crate::error::Error::Cancelled);
        }
        observer.phase_started("assembly");
        let t0 = Instant::now();
        let mesh = hierarchy.finest();
        // The adjacency and the boundary serve the checks, assembly and the quality report.
        let (adj, boundary) = mesh.patches();
        if observer.cancelled() {
            return Err(crate::error::Error::Cancelled);
        }
        let bound = BoundData::new(problem, mesh)?;
        let data = bound.data(problem);
        let model = crate::model::assemble_checked_on(
            mesh,
            &adj,
            &boundary,
            &data,
            &bound.extensions(problem),
        )?;
        let quality = mesh.quality_with(&boundary);
        let seconds = t0.elapsed().as_secs_f64();
        observer.phase_finished("assembly", seconds);
        Ok(Discretization {
            hierarchy,
            model,
            quality,
            warnings: Vec::new(),
            phases: vec![
                Phase {
                    name: "reorder".into(),
                    seconds: t_reorder,
                },
                Phase {
                    name: "assembly".into(),
                    seconds,
                },
            ],
        })
    }

    /// The solved mesh, in the solver's numbering (see [`Mesh::numbering`]).
    pub fn mesh(&self) -> &Mesh {
        self.hierarchy.finest()
    }

    /// The mesh levels in the user's numbering (the renumbering for locality undone).
    pub fn user_hierarchy(&self) -> Hierarchy {
        let levels: Vec<Mesh> = self
            .hierarchy
            .levels
            .iter()
            .map(|m| m.in_user_numbering().into_owned())
            .collect();
        let refinements = self
            .hierarchy
            .refinements
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let (coarse, fine) = (&self.hierarchy.levels[k], &self.hierarchy.levels[k + 1]);
                let to_user = |v: u32| {
                    coarse
                        .numbering
                        .as_ref()
                        .map_or(v, |n| n.vertices.old_of_new[v as usize])
                };
                let parents = (0..fine.n_vertices() as u32)
                    .map(|u| {
                        // User vertex u of the fine level is its vertex `v` here.
                        let v = fine
                            .numbering
                            .as_ref()
                            .map_or(u, |n| n.vertices.new_of_old[u as usize]);
                        r.parents[v as usize].map(to_user)
                    })
                    .collect();
                crate::mesh::refine::Refinement { parents }
            })
            .collect();
        Hierarchy {
            levels,
            refinements,
        }
    }

    /// The mesh levels multigrid can use (`None` for a single level).
    pub fn levels(&self) -> Option<&Hierarchy> {
        (self.hierarchy.depth() > 1).then_some(&self.hierarchy)
    }
}
