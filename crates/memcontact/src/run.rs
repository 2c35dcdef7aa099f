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

use crate::field::{BoundField, Stiffness as FieldStiffness};
use crate::mesh::refine::Hierarchy;
use crate::mesh::Mesh;
use crate::model::{Certificate, FoundationMatrix, Model, ProblemData, Stiffness};
use crate::problem::{Invalid, Problem};
use crate::results::{derive_from, NodalFields, Totals};
use crate::solve::{
    self, Choice, Fallback, IterationRecord, Method, Observer, Settings, Solution, Status,
};
use crate::{Error, Result};
use std::time::Instant;

/// The problem's data f, φ, h bound to a mesh's regions.
#[derive(Debug, Clone)]
pub struct BoundData {
    /// The load f.
    pub load: BoundField,
    /// The obstacle's surface φ.
    pub shape: BoundField,
    /// The stiffness h (`None`: rigid).
    pub stiffness: Option<BoundField>,
}

impl BoundData {
    /// Binds the problem's f, φ and h to the regions of `mesh` (a region table must name
    /// regions the mesh has, or give a default) or, for nodal values, to its vertices.
    pub fn new(problem: &Problem, mesh: &Mesh) -> Result<BoundData> {
        Ok(BoundData {
            load: problem.membrane.load.bind_to_mesh("membrane.load", mesh)?,
            shape: problem
                .obstacle
                .shape
                .bind_to_mesh("obstacle.shape", mesh)?,
            stiffness: match &problem.obstacle.stiffness {
                FieldStiffness::Rigid => None,
                FieldStiffness::Elastic(h) => Some(h.bind_to_mesh("obstacle.stiffness", mesh)?),
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
                Some(h) => Stiffness::Elastic(h),
                None => Stiffness::Rigid,
            },
            foundation: problem.obstacle.foundation,
            sampling: problem.obstacle.sampling(),
        }
    }
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
        let model = assemble_model(problem, hierarchy.finest())?;
        let seconds = t0.elapsed().as_secs_f64();
        observer.phase_finished("assembly", seconds);
        Ok(Discretization {
            hierarchy,
            model,
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

    /// Solves the discrete problem with `settings`.
    pub fn solve(&self, settings: &Settings, observer: &mut dyn Observer) -> Result<Report> {
        self.solve_from(settings, None, observer)
    }

    /// Solves the discrete problem with `settings`, starting from `start` (U over the
    /// unknowns, e.g. the answer of a neighbouring load step) when given.
    pub fn solve_from(
        &self,
        settings: &Settings,
        start: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Result<Report> {
        observer.phase_started("solve");
        let t0 = Instant::now();
        let a = solve::attempt_from(&self.model, self.levels(), settings, start, observer)?;
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
        })
    }
}

/// Binds the problem's data to `mesh`, checks it (on the boundary, and for overflow) and
/// assembles the model S, L, D, φₙ, M of the paper's §2. `problem.mesh` is not used.
pub fn assemble_model(problem: &Problem, mesh: &Mesh) -> Result<Model> {
    let bound = bind_and_check(problem, mesh)?;
    let model = Model::assemble(mesh, &bound.data(problem))?;
    check_overflow(mesh, &model)?;
    Ok(model)
}

/// Binds the problem's data to `mesh` and checks it where assembly does not sample it (on
/// the boundary): the checks of [`assemble_model`] that need no assembly.
pub fn bind_and_check(problem: &Problem, mesh: &Mesh) -> Result<BoundData> {
    let bound = BoundData::new(problem, mesh)?;
    check_boundary_data(mesh, &bound)?;
    Ok(bound)
}

/// Checks the data where assembly does not sample it: f on the boundary vertices (a load
/// singular on the boundary, like `1/x` on x = 0, is refused), and, for the rigid obstacle,
/// that φ is not below the fixed boundary (`u = 0 > φ` there: no continuous solution).
fn check_boundary_data(mesh: &Mesh, data: &BoundData) -> Result<()> {
    let boundary = mesh.boundary_vertices();
    let adj = crate::fem::VertexTriangles::new(mesh);
    for (v, &on) in boundary.iter().enumerate() {
        if !on {
            continue;
        }
        let p = mesh.points[v];
        for &k in adj.of(v) {
            let region = mesh.regions[k as usize];
            let f = data.load.eval(p, region);
            if !f.is_finite() {
                return Err(Error::Data(format!(
                    "membrane.load f is not finite on the boundary at ({}, {}) (f = {f}): the \
                     load must be bounded on the closed domain",
                    p[0], p[1]
                )));
            }
            if data.stiffness.is_none() {
                let phi = data.shape.eval(p, region);
                if phi < 0.0 {
                    return Err(Error::Data(format!(
                        "obstacle.shape φ = {phi} at the boundary point ({}, {}) lies below \
                         the fixed boundary (u = 0 there): with a rigid obstacle (u ≤ φ) the \
                         problem has no continuous solution; raise φ to at least 0 on the \
                         boundary or give the obstacle a finite stiffness",
                        p[0], p[1]
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Refuses a model whose matrices or data overflowed double precision, naming the data.
fn check_overflow(mesh: &Mesh, model: &Model) -> Result<()> {
    let smallest_area = (0..mesh.n_triangles())
        .map(|k| mesh.area(k).abs())
        .fold(f64::INFINITY, f64::min);
    if !model.s.is_finite() {
        return Err(Error::Data(format!(
            "the stiffness matrix S overflows double precision: tension t = {:e} on triangles \
             as small as {smallest_area:e} (S grows like t × edge² / area); rescale the \
             problem (units) so that t and the mesh are moderate",
            model.tension
        )));
    }
    if let FoundationMatrix::Consistent(l) = &model.l {
        if !l.is_finite() {
            return Err(Error::Data(
                "the foundation matrix L = ∫h gᵢgⱼ overflows double precision: \
                 obstacle.stiffness h is too large (use stiffness = \"rigid\" for a rigid \
                 body)"
                    .into(),
            ));
        }
    }
    if let FoundationMatrix::Lumped(d) = &model.l {
        if d.iter().any(|v| !v.is_finite()) {
            return Err(Error::Data(
                "the lumped foundation lᵢ = ∫h gᵢ overflows double precision: \
                 obstacle.stiffness h is too large (use stiffness = \"rigid\" for a rigid \
                 body)"
                    .into(),
            ));
        }
    }
    if let Some(i) = model.phi.iter().position(|v| !v.is_finite()) {
        let p = mesh.points[model.dofs.vertex[i] as usize];
        return Err(Error::Data(format!(
            "obstacle.shape φ is not finite at ({}, {})",
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
             {d_max:e} against a stiffness of {s_min:e} (membrane.load is too large for the \
             tension); rescale the problem (units)"
        )));
    }
    Ok(())
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
    pub fn error(&self) -> Option<crate::Error> {
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
    pub fn fields(&self) -> (NodalFields, Totals) {
        let mesh = self.discretization.mesh();
        let (f, totals) = derive_from(mesh, &self.discretization.model, &self.report.u);
        if mesh.numbering.is_none() {
            return (f, totals);
        }
        let user = |x: &[f64]| mesh.vertex_values_to_user(x);
        let fields = NodalFields {
            u: user(&f.u),
            phi: user(&f.phi),
            penetration: user(&f.penetration),
            pressure: user(&f.pressure),
            contact_force: user(&f.contact_force),
            state: mesh.vertex_values_to_user(&f.state),
            covered: mesh.vertex_values_to_user(&f.covered),
        };
        (fields, totals)
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
