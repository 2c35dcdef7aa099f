//! The library's front door: one [`run`] from a [`Problem`] and [`Settings`] to an
//! [`Outcome`]. Data flows one way:
//!
//! ```text
//! Problem ─► Discretization (mesh levels, data bound to regions, S, L, D, φₙ, M)
//!         ─► solve (method, auto policy, fallback) ─► Outcome (U, Status, Report)
//! ```
//!
//! Bad input is an `Err`; a numerical outcome (converged, iteration limit, stalled,
//! numerical failure) is a [`Status`] inside the [`Report`], always with the best iterate
//! and its certificate. The library prints nothing: progress reaches the caller through
//! the [`Observer`].

use crate::certificate::Certificate;
use crate::error::Invalid;
use crate::error::{Error, Result};
use crate::field::BoundField;
use crate::mesh::refine::Hierarchy;
use crate::mesh::{Mesh, MeshQuality};
use crate::model::{BodyData, BodyStiffness, BoundaryData, Extensions, Model, ProblemData};
use crate::problem::Problem;
use crate::results::{derive_from, NodalFields, Totals};
use crate::solve::{
    self, Choice, Fallback, IterationRecord, Method, Observer, Settings, Solution, Status,
};
use std::borrow::Cow;
use std::time::Instant;

/// The problem's data f, φ, h (and the data beyond the paper's frame: boundary heights,
/// rigid regions, the body below) bound to a mesh's regions.
#[derive(Debug, Clone)]
pub struct BoundData {
    /// The load f.
    pub load: BoundField,
    /// The obstacle's surface φ.
    pub shape: BoundField,
    /// The stiffness h (`None`: rigid).
    pub stiffness: Option<BoundField>,
    /// The obstacle's rigid regions when it is elastic elsewhere (mixed bodies).
    pub rigid_regions: Vec<u32>,
    /// The heights g on the fixed boundary, bound to the boundary regions, and the free
    /// regions (`None`: the whole boundary fixed at 0).
    pub boundary: Option<(BoundField, Vec<String>)>,
    /// The body below.
    pub lower: Option<BoundBody>,
}

/// A body's data bound to a mesh: surface, stiffness, rigid regions.
#[derive(Debug, Clone)]
pub struct BoundBody {
    /// The surface.
    pub shape: BoundField,
    /// The stiffness (`None`: rigid everywhere).
    pub stiffness: Option<BoundField>,
    /// The rigid regions when it is elastic elsewhere.
    pub rigid_regions: Vec<u32>,
}

impl BoundBody {
    fn new(section: &str, body: &crate::problem::Obstacle, mesh: &Mesh) -> Result<BoundBody> {
        let stiffness = body
            .stiffness
            .bind_to_mesh(&format!("{section}.stiffness"), mesh)?;
        let rigid_regions = if stiffness.is_rigid() {
            Vec::new()
        } else {
            stiffness.rigid_tags
        };
        Ok(BoundBody {
            shape: body.shape.bind_to_mesh(&format!("{section}.shape"), mesh)?,
            stiffness: stiffness.elastic,
            rigid_regions,
        })
    }

    fn stiffness(&self) -> BodyStiffness<'_> {
        match &self.stiffness {
            Some(h) => BodyStiffness::Elastic(h),
            None => BodyStiffness::Rigid,
        }
    }
}

impl BoundData {
    /// Binds the problem's f, φ and h to the regions of `mesh` (a region table must name
    /// regions the mesh has, or give a default) or, for nodal values, to its vertices; the
    /// boundary heights to the mesh's boundary regions.
    pub fn new(problem: &Problem, mesh: &Mesh) -> Result<BoundData> {
        let upper = BoundBody::new("obstacle", &problem.obstacle, mesh)?;
        let boundary = if problem.boundary.is_default() {
            None
        } else {
            let height = bind_height(&problem.boundary, mesh)?;
            Some((height, problem.boundary.free.clone()))
        };
        Ok(BoundData {
            load: problem.membrane.load.bind_to_mesh("membrane.load", mesh)?,
            shape: upper.shape,
            stiffness: upper.stiffness,
            rigid_regions: upper.rigid_regions,
            boundary,
            lower: match &problem.lower {
                Some(low) => Some(BoundBody::new("lower", low, mesh)?),
                None => None,
            },
        })
    }

    /// The model's view of the data, with the problem's tension and choices.
    pub fn data<'a>(&'a self, problem: &Problem) -> ProblemData<'a> {
        ProblemData {
            tension: problem.membrane.tension,
            load: &self.load,
            shape: &self.shape,
            stiffness: match &self.stiffness {
                Some(h) => BodyStiffness::Elastic(h),
                None => BodyStiffness::Rigid,
            },
            foundation: problem.obstacle.foundation,
            sampling: problem.obstacle.sampling(),
        }
    }

    /// The model's view of the data beyond the paper's frame (SPEC §5).
    pub fn extensions<'a>(&'a self, problem: &Problem) -> Extensions<'a> {
        Extensions {
            boundary: self
                .boundary
                .as_ref()
                .map(|(height, free)| BoundaryData { free, height }),
            rigid_regions: &self.rigid_regions,
            lower: match (&self.lower, &problem.lower) {
                (Some(b), Some(p)) => Some(BodyData {
                    shape: &b.shape,
                    stiffness: b.stiffness(),
                    rigid_regions: &b.rigid_regions,
                    foundation: p.foundation,
                    sampling: p.sampling(),
                }),
                _ => None,
            },
        }
    }
}

/// Binds the boundary heights to the boundary regions of `mesh` that are fixed (a table
/// needs a value for each of them, or a default), or, for nodal values, to its vertices.
fn bind_height(boundary: &crate::problem::Boundary, mesh: &Mesh) -> Result<BoundField> {
    let name = "boundary.height";
    if let crate::field::Field::Nodal(_) = &boundary.height {
        return boundary.height.bind_to_mesh(name, mesh);
    }
    let adj = crate::fem::VertexTriangles::new(mesh);
    let fixed = crate::mesh::boundary::FixedBoundary::new(mesh, &adj, &boundary.free)?;
    let tagged = mesh.tagged_boundary(&adj);
    let present = tagged.present();
    // Keys may name the free regions too (the value is then not used). Messages call the
    // edges no region covers `default`.
    let names = &mesh.boundary.labels();
    if let crate::field::Field::Regions(table) = &boundary.height {
        for key in table.keys() {
            if key != crate::field::DEFAULT_KEY && mesh.boundary.resolve(key, &present).is_empty() {
                return Err(mesh.no_boundary_region(name, key, &tagged));
            }
        }
        let fixed_only: std::collections::BTreeMap<String, crate::field::Field> = table
            .iter()
            .filter(|(k, _)| {
                k.as_str() == crate::field::DEFAULT_KEY
                    || mesh
                        .boundary
                        .resolve(k, &present)
                        .iter()
                        .any(|t| fixed.fixed_tags.contains(t))
            })
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if fixed_only.is_empty() {
            return crate::field::Field::Constant(0.0).bind(name, names, &fixed.fixed_tags);
        }
        return crate::field::Field::Regions(fixed_only)
            .bind(name, names, &fixed.fixed_tags)
            .map_err(|e| match e {
                Error::Data(m) => Error::Data(m.replace("(regions:", "(fixed boundary regions:")),
                other => other,
            });
    }
    boundary.height.bind(name, names, &fixed.fixed_tags)
}

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
        let (hierarchy, warnings) = problem.mesh.build()?;
        let t_mesh = t0.elapsed().as_secs_f64();
        observer.phase_finished("mesh", t_mesh);
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
        observer.phase_started("assembly");
        let t0 = Instant::now();
        let mesh = hierarchy.finest();
        // The adjacency and the boundary serve the checks, assembly and the quality report.
        let (adj, boundary) = mesh.patches();
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

    /// The method `auto` would use, and why.
    pub fn auto_choice(&self) -> (Method, Choice) {
        solve::auto_choice(&self.model, self.levels())
    }

    /// The method `settings` resolve to on this problem (`auto`'s choice).
    pub fn method_for(&self, settings: &Settings) -> Method {
        match settings.method {
            Method::Auto => self.auto_choice().0,
            m => m,
        }
    }

    /// Refuses a solve with `settings` whose factorisation would not fit in the memory
    /// available ([`crate::solve::check_solver_fits`]); `solve` and `check` call it.
    pub fn check_memory(&self, settings: &Settings) -> Result<()> {
        crate::solve::check_solver_fits(self.method_for(settings), self.model.n())
    }

    /// The estimated peak memory of solving with `settings` (bytes): the run's data on
    /// this mesh ([`crate::limits::run_bytes`]) and the solver's factorisation ([`crate::solve::solver_bytes`]).
    pub fn memory_estimate(&self, settings: &Settings) -> f64 {
        crate::limits::run_bytes(crate::limits::MeshSize::of(self.mesh()))
            + crate::solve::solver_bytes(self.method_for(settings), self.model.n())
    }

    /// Solves the discrete problem with `settings`.
    pub fn solve(&self, settings: &Settings, observer: &mut dyn Observer) -> Result<Report> {
        self.solve_from(settings, None, observer)
    }

    /// Solves the discrete problem with `settings`, starting from `start` (U over the
    /// unknowns, e.g. the answer of a neighbouring load step) when given. Refused first
    /// when the solver would not fit in memory, and afterwards when J, the certificate,
    /// the fields or the totals of the answer are not finite ([`crate::checks`]).
    pub fn solve_from(
        &self,
        settings: &Settings,
        start: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Result<Report> {
        self.check_memory(settings)?;
        observer.phase_started("solve");
        let t0 = Instant::now();
        let a = solve::attempt_from(&self.model, self.levels(), settings, start, observer)?;
        crate::outcome::checks::check_solution(
            a.solution.energy,
            a.solution.certificate.kkt(),
            self.model.is_rigid(),
        )?;
        // The fields and totals of the answer (pressures, forces, areas) must be finite
        // too: refused here, before any caller reports or writes them.
        let (fields, totals) = derive_from(self.mesh(), &self.model, &a.solution.u);
        crate::outcome::checks::check_results(self.mesh(), &fields, &totals)?;
        let derived = Some(std::sync::Arc::new((fields, totals)));
        let seconds = t0.elapsed().as_secs_f64();
        observer.phase_finished("solve", seconds);
        let mut phases = self.phases.clone();
        phases.push(Phase {
            name: "solve".into(),
            seconds,
        });
        let s = a.solution;
        Ok(Report {
            accepted: a.status.is_accepted(settings),
            status: a.status,
            requested: a.requested,
            method: s.method,
            coarsening: s.coarsening,
            choice: a.choice,
            fallback: a.fallback,
            message: a.message,
            iterations: s.iterations,
            energy: s.energy,
            certificate: s.certificate,
            tolerance: settings.tolerance,
            history: s.history,
            phases,
            solver_phases: s
                .phases
                .into_iter()
                .map(|(name, seconds)| Phase { name, seconds })
                .collect(),
            u: s.u,
            multipliers: s.multipliers,
            derived,
        })
    }
}

/// Binds the problem's data to `mesh`, checks it (on the boundary, and for overflow:
/// [`crate::model::assemble_checked`]) and assembles the model S, L, D, φₙ, M of the paper's §2.
/// `problem.mesh` is not used.
pub fn assemble_model(problem: &Problem, mesh: &Mesh) -> Result<Model> {
    let bound = BoundData::new(problem, mesh)?;
    crate::model::assemble_checked(mesh, &bound.data(problem), &bound.extensions(problem))
}

/// Binds the problem's data to `mesh` and checks it where assembly does not sample it (on
/// the boundary): the checks of [`assemble_model`] that need no assembly.
pub fn bind_and_check(problem: &Problem, mesh: &Mesh) -> Result<BoundData> {
    let bound = BoundData::new(problem, mesh)?;
    crate::model::check_boundary_data(mesh, &bound.data(problem), &bound.extensions(problem))?;
    Ok(bound)
}

/// How a solve went, with its iterate: the status, the method used and why, iterations,
/// J, the certificates of 2e and 2f, the history and the phase times.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// How the solve ended.
    pub status: Status,
    /// The settings accept the outcome (converged, or at the rounding floor when allowed).
    pub accepted: bool,
    /// The method the settings asked for (maybe `auto`).
    pub requested: Method,
    /// The method that produced the iterate.
    pub method: Method,
    /// The kind of multigrid hierarchy it ran on (multigrid only).
    pub coarsening: Option<crate::solve::multigrid::Kind>,
    /// Why that method was used.
    pub choice: Choice,
    /// The method `auto` tried first and gave up on.
    pub fallback: Option<Fallback>,
    /// What went wrong, for a numerical failure.
    pub message: Option<String>,
    /// Iterations of the method that produced the iterate.
    pub iterations: usize,
    /// J(U) (Problem 2b).
    pub energy: f64,
    /// The scaled residuals of 2e and 2f at U.
    pub certificate: Certificate,
    /// The tolerance the certificate was held to.
    pub tolerance: f64,
    /// Energy and residual per iteration.
    pub history: Vec<IterationRecord>,
    /// `mesh`, `assembly`, `solve` wall-clock seconds.
    pub phases: Vec<Phase>,
    /// The solver's own phases (setup, factorisation, smoothing, ...).
    pub solver_phases: Vec<Phase>,
    /// U over the unknowns (the best iterate).
    #[serde(skip)]
    pub u: Vec<f64>,
    /// The solver's multipliers of 2e, when it computes them (the QP does).
    #[serde(skip)]
    pub multipliers: Option<solve::Multipliers>,
    /// The vertex fields and totals of `u` in the solver's numbering, derived and checked
    /// once when the solve ended (`None`: derived again from `u` when asked for).
    #[serde(skip)]
    pub derived: Option<std::sync::Arc<(NodalFields, Totals)>>,
}

impl Report {
    /// Seconds of phase `name` (0 when it did not run).
    pub fn seconds(&self, name: &str) -> f64 {
        self.phases
            .iter()
            .filter(|p| p.name == name)
            .map(|p| p.seconds)
            .sum()
    }

    /// The error naming how the solve ended, when the settings do not accept it.
    pub fn error(&self) -> Option<crate::error::Error> {
        (!self.accepted).then(|| {
            solve::status_error(
                self.status,
                self.method,
                self.iterations,
                self.certificate.kkt(),
                self.tolerance,
                self.message.as_deref(),
            )
        })
    }

    /// The iterate as a [`Solution`] (for the functions that derive results from one).
    pub fn solution(&self) -> Solution {
        Solution {
            u: self.u.clone(),
            method: self.method,
            iterations: self.iterations,
            energy: self.energy,
            certificate: self.certificate,
            multipliers: self.multipliers.clone(),
            history: self.history.clone(),
            phases: self
                .solver_phases
                .iter()
                .map(|p| (p.name.clone(), p.seconds))
                .collect(),
            coarsening: self.coarsening,
        }
    }
}

/// What [`run`] produced: the discretisation and the report with the iterate.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Mesh levels and model.
    pub discretization: Discretization,
    /// Status, method, certificate, history, times, and U.
    pub report: Report,
}

impl Outcome {
    /// How the solve ended.
    pub fn status(&self) -> Status {
        self.report.status
    }

    /// The solved mesh in the user's numbering (the numbering of every output).
    pub fn mesh(&self) -> std::borrow::Cow<'_, Mesh> {
        self.discretization.mesh().in_user_numbering()
    }

    /// The vertex fields (u, φ, penetration, pressure, contact forces, states) in the
    /// user's vertex numbering, and the totals.
    pub fn fields(&self) -> (Cow<'_, NodalFields>, Totals) {
        let (fields, totals) = self.solver_fields();
        (self.to_user(fields), totals)
    }

    /// The totals of the answer (load, reaction, contact area, ...).
    pub fn totals(&self) -> Totals {
        self.solver_fields().1
    }

    /// [`Outcome::fields`], checked to be finite ([`crate::outcome::checks::check_results`]): the
    /// fields that result files hold.
    pub fn checked_fields(&self) -> Result<(Cow<'_, NodalFields>, Totals)> {
        let (fields, totals) = self.solver_fields();
        crate::outcome::checks::check_results(self.discretization.mesh(), &fields, &totals)?;
        Ok((self.to_user(fields), totals))
    }

    /// The fields and totals in the solver's numbering: those of the report, or derived
    /// from its `u` when it has none.
    fn solver_fields(&self) -> (Cow<'_, NodalFields>, Totals) {
        match &self.report.derived {
            Some(d) => (Cow::Borrowed(&d.0), d.1),
            None => {
                let d = &self.discretization;
                let (f, totals) = derive_from(d.mesh(), &d.model, &self.report.u);
                (Cow::Owned(f), totals)
            }
        }
    }

    /// Vertex fields in the solver's numbering mapped to the user's.
    fn to_user<'a>(&self, f: Cow<'a, NodalFields>) -> Cow<'a, NodalFields> {
        let mesh = self.discretization.mesh();
        if mesh.numbering.is_none() {
            return f;
        }
        let user = |x: &[f64]| mesh.vertex_values_to_user(x);
        Cow::Owned(NodalFields {
            u: user(&f.u),
            phi: user(&f.phi),
            penetration: user(&f.penetration),
            pressure: user(&f.pressure),
            contact_force: user(&f.contact_force),
            state: mesh.vertex_values_to_user(&f.state),
            covered: mesh.vertex_values_to_user(&f.covered),
            lower: f.lower.as_ref().map(|l| crate::results::LowerFields {
                phi: user(&l.phi),
                penetration: user(&l.penetration),
                pressure: user(&l.pressure),
                contact_force: user(&l.contact_force),
                state: mesh.vertex_values_to_user(&l.state),
                covered: mesh.vertex_values_to_user(&l.covered),
            }),
        })
    }
}

/// Runs a problem end to end: mesh, assembly, solve.
pub fn run(problem: &Problem, settings: &Settings, observer: &mut dyn Observer) -> Result<Outcome> {
    settings.validate().map_err(Invalid::into_error)?;
    let discretization = Discretization::new(problem, observer)?;
    let report = discretization.solve(settings, observer)?;
    Ok(Outcome {
        discretization,
        report,
    })
}
