//! [`Discretization`]: the discrete problem built once per problem: the mesh levels (read
//! or generated, refined, renumbered for locality) and the model assembled on the finest.

use super::binding::BoundData;
use super::meshing::build_mesh_checked;
use crate::error::{Invalid, Result};
use crate::mesh::refine::Hierarchy;
use crate::mesh::{DofMap, Mesh, MeshQuality};
use crate::model::Model;
use crate::problem::{MeshSource, MeshSpec, Problem};
use crate::solve::multigrid::Levels;
use crate::solve::Observer;
use crate::solve::Settings;
use crate::sparse::Csr;
use std::sync::Arc;
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
    /// The geometric multigrid levels, built beforehand by
    /// [`Discretization::for_one_solve`] (a solve builds its own otherwise).
    built: Option<Arc<Levels>>,
    /// Set by [`Discretization::release_solver_data`]: S is gone, nothing can be solved.
    released: bool,
    /// Set by [`Discretization::release_mesh`]: the finest mesh's vertices, triangles and
    /// regions are released until [`Discretization::restore_mesh`] builds them again from
    /// this spec; the hash checks that they come back the same.
    mesh_released: Option<(MeshSpec, u64)>,
    /// The run's bytes per vertex of the finest mesh, for its memory estimate
    /// ([`super::meshing::bytes_per_vertex`]).
    per_vertex: f64,
}

impl Discretization {
    /// Builds the mesh the problem describes and assembles the model on it.
    pub fn new(problem: &Problem, observer: &mut dyn Observer) -> Result<Discretization> {
        problem.validate().map_err(Invalid::into_error)?;
        observer.phase_started("mesh");
        let t0 = Instant::now();
        let per_vertex = super::meshing::bytes_per_vertex(problem, false);
        let (hierarchy, warnings) = build_mesh_checked(&problem.mesh, Some(per_vertex))?;
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
    /// numbering is scattered are first renumbered for locality (vertices along a
    /// Hilbert curve); outputs come back in the user's numbering.
    pub fn assemble(
        problem: &Problem,
        hierarchy: Hierarchy,
        observer: &mut dyn Observer,
    ) -> Result<Discretization> {
        let (hierarchy, t_reorder) = reorder(hierarchy, observer)?;
        Discretization::assemble_reordered(problem, hierarchy, t_reorder, observer)
    }

    /// The discretisation for one solve with `settings` and, after it, only the writing of
    /// its outcome (`memcontact solve` of a case without steps): the mesh is built and
    /// renumbered as by [`Discretization::new`], then the coarser levels' meshes are
    /// released before assembly (their vertex counts and the refinement relations are all
    /// multigrid reads of them), and after assembly the geometric multigrid levels the
    /// solve will use are built and the refinement relations released too. The coarser
    /// levels stay in [`Discretization::hierarchy`] as empty meshes, so that its depth is
    /// still reported. Call [`Discretization::release_solver_data`] after the solve.
    pub(crate) fn for_one_solve(
        problem: &Problem,
        settings: &Settings,
        observer: &mut dyn Observer,
    ) -> Result<Discretization> {
        problem.validate().map_err(Invalid::into_error)?;
        observer.phase_started("mesh");
        let t0 = Instant::now();
        let per_vertex = super::meshing::bytes_per_vertex(problem, true);
        let (hierarchy, warnings) = build_mesh_checked(&problem.mesh, Some(per_vertex))?;
        let t_mesh = t0.elapsed().as_secs_f64();
        observer.phase_finished("mesh", t_mesh);
        if observer.cancelled() {
            return Err(crate::error::Error::Cancelled);
        }
        let (mut hierarchy, t_reorder) = reorder(hierarchy, observer)?;
        let counts = hierarchy.vertex_counts();
        let depth = hierarchy.depth();
        for m in &mut hierarchy.levels[..depth - 1] {
            m.points = Vec::new();
            m.triangles = Vec::new();
            m.regions = Vec::new();
            m.numbering = None;
        }
        let mut d = Discretization::assemble_reordered(problem, hierarchy, t_reorder, observer)?;
        d.per_vertex = per_vertex;
        d.warnings = warnings;
        d.phases.insert(
            0,
            Phase {
                name: "mesh".into(),
                seconds: t_mesh,
            },
        );
        // The levels multigrid will build from the mesh's hierarchy, built now (part of
        // the symbolic phase), so that the refinement relations can go.
        if d.solves_on_mesh_levels(settings) {
            d.build_levels(&counts, None, observer)?;
        }
        d.hierarchy.refinements = Vec::new();
        Ok(d)
    }

    /// Whether a solve with `settings` runs multigrid on the mesh levels: multigrid chosen,
    /// the algebraic levels not asked for, and a hierarchy of more than one mesh.
    pub(crate) fn solves_on_mesh_levels(&self, settings: &Settings) -> bool {
        self.method_for(settings) == crate::solve::Method::Multigrid
            && settings.hierarchy != crate::solve::HierarchyChoice::Algebraic
            && self.hierarchy.depth() > 1
    }

    /// Builds the geometric multigrid levels the solves will use (the `levels` phase,
    /// counted in `assembly`); `counts` are the vertex counts of the hierarchy's meshes.
    /// With the `previous` step's levels of an adaptive loop and that step's unknowns,
    /// whose mesh this hierarchy refined into its finest, only the new finest level is
    /// added to them ([`Levels::extended`]) when they fit; otherwise every level is built.
    pub(crate) fn build_levels(
        &mut self,
        counts: &[usize],
        previous: Option<(Arc<Levels>, &DofMap)>,
        observer: &mut dyn Observer,
    ) -> Result<()> {
        let t0 = Instant::now();
        observer.phase_started("levels");
        let h = &self.hierarchy;
        let mut levels = None;
        if let (Some((prev, top)), Some(refinement), Some(last)) =
            (previous, h.refinements.last(), h.levels.last())
        {
            levels = Arc::unwrap_or_clone(prev).extended(
                top,
                refinement,
                last,
                &self.model.dofs,
                self.model.s.pattern.clone(),
            )?;
        }
        let levels = match levels {
            Some(levels) => levels,
            None => crate::solve::multigrid::tnnmg::mesh_levels(
                &self.model,
                &h.refinements,
                counts,
                h.levels.last(),
            )?,
        };
        self.built = Some(Arc::new(levels));
        let seconds = t0.elapsed().as_secs_f64();
        observer.phase_finished("levels", seconds);
        if let Some(p) = self.phases.iter_mut().find(|p| p.name == "assembly") {
            p.seconds += seconds;
        }
        Ok(())
    }

    /// Takes the multigrid levels built beforehand, if any, out of this discretisation
    /// (an adaptive loop's next step extends them).
    pub(crate) fn take_levels(&mut self) -> Option<Arc<Levels>> {
        self.built.take()
    }

    /// Releases what only a solve reads (S and the multigrid levels), once a discretisation
    /// made by [`Discretization::for_one_solve`] has been solved and its outcome is about
    /// to be written. The outcome's fields, totals and report are kept; a later solve is
    /// refused with an error.
    pub(crate) fn release_solver_data(&mut self) {
        self.built = None;
        self.model.s = Csr {
            pattern: Arc::new(crate::sparse::Pattern {
                row_ptr: vec![0],
                col: Vec::new(),
            }),
            val: Vec::new(),
        };
        self.released = true;
    }

    /// Releases the finest mesh's vertices, triangles and regions until
    /// [`Discretization::restore_mesh`] (a one-step run whose solve does not read them:
    /// `memcontact solve`), when the mesh comes from a generator of `spec` (the rectangle,
    /// disc and polygon generators are deterministic, so the mesh is built again, the
    /// same, for the fields and the writers; a mesh read from a file or given as data is
    /// kept). Returns whether it released them. Assembly, the checks on the mesh and the
    /// multigrid levels must be done: nothing reads the mesh until it is restored.
    pub(crate) fn release_mesh(&mut self, spec: &MeshSpec) -> bool {
        let generated = matches!(
            spec.source,
            MeshSource::Rectangle { .. } | MeshSource::Disk { .. } | MeshSource::Polygon { .. }
        );
        if !generated || self.mesh_released.is_some() {
            return false;
        }
        let finest = self.hierarchy.levels.last_mut().expect("a level");
        let hash = geometry_hash(finest);
        finest.points = Vec::new();
        finest.triangles = Vec::new();
        finest.regions = Vec::new();
        self.mesh_released = Some((spec.clone(), hash));
        true
    }

    /// Builds the finest mesh again after [`Discretization::release_mesh`] (as
    /// [`Discretization::for_one_solve`] built it: generated, refined, renumbered) and puts
    /// its vertices, triangles and regions back; its seconds are added to the `mesh`
    /// phase. A mesh that does not come back the same is an error. Nothing to do when
    /// nothing was released.
    pub(crate) fn restore_mesh(&mut self, observer: &mut dyn Observer) -> Result<()> {
        let Some((spec, hash)) = self.mesh_released.take() else {
            return Ok(());
        };
        observer.phase_started("mesh");
        let t0 = Instant::now();
        let (hierarchy, _) = build_mesh_checked(&spec, None)?;
        let mesh = hierarchy.levels.into_iter().last().expect("a level");
        let mesh = match crate::mesh::reorder::renumbering_for_locality(&mesh) {
            Some(r) => Arc::new(r).apply_shared(&mesh),
            None => mesh,
        };
        if geometry_hash(&mesh) != hash {
            return Err(crate::error::Error::Mesh(
                "the mesh built again for the outputs differs from the one solved on".into(),
            ));
        }
        let finest = self.hierarchy.levels.last_mut().expect("a level");
        finest.points = mesh.points;
        finest.triangles = mesh.triangles;
        finest.regions = mesh.regions;
        let seconds = t0.elapsed().as_secs_f64();
        observer.phase_finished("mesh", seconds);
        if let Some(p) = self.phases.iter_mut().find(|p| p.name == "mesh") {
            p.seconds += seconds;
        }
        Ok(())
    }

    /// Releases the multigrid levels built beforehand (a solve builds its own again).
    pub(crate) fn release_levels(&mut self) {
        self.built = None;
    }

    /// Whether [`Discretization::release_solver_data`] was called.
    pub(crate) fn is_released(&self) -> bool {
        self.released
    }

    /// The geometric multigrid levels built beforehand, if any.
    pub(crate) fn built_levels(&self) -> Option<&Levels> {
        self.built.as_deref()
    }

    /// Gives the solves multigrid levels built beforehand for the model's pattern (the
    /// aggregation hierarchy a fit builds once and keeps for every iterate's solve).
    pub(crate) fn share_levels(&mut self, levels: Arc<Levels>) {
        self.built = Some(levels);
    }

    /// [`Discretization::assemble`] on a hierarchy already renumbered (in `t_reorder`
    /// seconds).
    fn assemble_reordered(
        problem: &Problem,
        hierarchy: Hierarchy,
        t_reorder: f64,
        observer: &mut dyn Observer,
    ) -> Result<Discretization> {
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
            built: None,
            released: false,
            mesh_released: None,
            per_vertex: super::meshing::bytes_per_vertex(problem, false),
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

/// Renumbers the levels of `hierarchy` for locality (the `reorder` phase); returns it with
/// the seconds taken.
fn reorder(hierarchy: Hierarchy, observer: &mut dyn Observer) -> Result<(Hierarchy, f64)> {
    observer.phase_started("reorder");
    let t0 = Instant::now();
    let (hierarchy, _) = hierarchy.reordered();
    let t_reorder = t0.elapsed().as_secs_f64();
    observer.phase_finished("reorder", t_reorder);
    if observer.cancelled() {
        return Err(crate::error::Error::Cancelled);
    }
    Ok((hierarchy, t_reorder))
}

/// A hash of a mesh's vertices, triangles and regions: xxh3 of their little-endian bytes
/// in fixed blocks (on all threads), then of the blocks' hashes in order.
fn geometry_hash(mesh: &Mesh) -> u64 {
    use rayon::prelude::*;
    const BLOCK: usize = 1 << 16;
    fn blocks<T: Sync>(items: &[T], bytes: impl Fn(&T, &mut Vec<u8>) + Sync) -> Vec<u64> {
        items
            .par_chunks(BLOCK)
            .map(|block| {
                let mut buf = Vec::with_capacity(block.len() * 16);
                for x in block {
                    bytes(x, &mut buf);
                }
                xxhash_rust::xxh3::xxh3_64(&buf)
            })
            .collect()
    }
    let mut all = blocks(&mesh.points, |p, b| {
        b.extend_from_slice(&p[0].to_le_bytes());
        b.extend_from_slice(&p[1].to_le_bytes());
    });
    all.extend(blocks(&mesh.triangles, |t, b| {
        for v in t {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }));
    all.extend(blocks(&mesh.regions, |r, b| {
        b.extend_from_slice(&r.to_le_bytes())
    }));
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    for d in all {
        h.update(&d.to_le_bytes());
    }
    h.digest()
}

impl Discretization {
    /// The estimated memory of the run on this mesh besides a solver's factorisation
    /// (bytes): the vertices of the finest mesh times the bytes per vertex of its problem
    /// and kind of run (the constants of [`crate::limits`]).
    pub fn run_bytes(&self) -> f64 {
        self.per_vertex * self.mesh().n_vertices() as f64
    }
}
