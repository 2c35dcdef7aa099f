//! One run: a problem solved on its discretisation, by the method the settings name or the
//! one `auto` picks, checked before anyone reports or writes it.

use super::checks::check_case_on_mesh;
use crate::case::Case;
use crate::discretization::{Discretization, Phase};
use crate::error::Error;
use crate::error::{Invalid, Result};
use crate::outcome::fields::derive_from;
use crate::outcome::{Outcome, Report};
use crate::problem::Problem;
use crate::solve::{self, Choice, Method, Observer, Settings};
use std::time::Instant;

impl Discretization {
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
    /// this mesh ([`Discretization::run_bytes`]) and the solver's factorisation
    /// ([`crate::solve::solver_bytes`]).
    pub fn memory_estimate(&self, settings: &Settings) -> f64 {
        self.run_bytes() + crate::solve::solver_bytes(self.method_for(settings), self.model.n())
    }

    /// Solves the discrete problem with `settings`.
    pub fn solve(&self, settings: &Settings, observer: &mut dyn Observer) -> Result<Report> {
        self.solve_from(settings, None, observer)
    }

    /// Solves the discrete problem with `settings`, starting from `start` (U over the
    /// unknowns, e.g. the answer of a neighbouring load step) when given. Refused first
    /// when the solver would not fit in memory, and afterwards when J, the certificate,
    /// the fields or the totals of the answer are not finite ([`crate::outcome::checks`]).
    pub fn solve_from(
        &self,
        settings: &Settings,
        start: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Result<Report> {
        let t0 = self.begin_solve(settings, observer)?;
        let a = self.attempt(settings, start, observer)?;
        self.finish_solve(a, settings, t0, 0.0, observer)
    }

    /// [`Discretization::solve`] for a discretisation made by
    /// [`Discretization::for_one_solve`] whose finest mesh may be released
    /// ([`Discretization::release_mesh`]): the mesh is built again after the solver is done
    /// and before the fields are derived on it (its seconds count in the `mesh` phase, not
    /// in `solve`).
    pub fn solve_once(
        &mut self,
        settings: &Settings,
        observer: &mut dyn Observer,
    ) -> Result<Report> {
        let t0 = self.begin_solve(settings, observer)?;
        let a = self.attempt(settings, None, observer)?;
        // Only the solver reads the multigrid levels: they go before the mesh comes back.
        self.release_levels();
        let t_mesh = Instant::now();
        self.restore_mesh(&mut crate::solve::Silent)?;
        let rebuilt = t_mesh.elapsed().as_secs_f64();
        self.finish_solve(a, settings, t0, rebuilt, observer)
    }

    /// The checks before a solve (not released, fits in memory); starts its phase.
    fn begin_solve(&self, settings: &Settings, observer: &mut dyn Observer) -> Result<Instant> {
        if self.is_released() {
            return Err(Error::Solver {
                solver: self.method_for(settings).name().into(),
                message: "this discretisation was solved once and its matrices released: \
                          build it again to solve it again"
                    .into(),
            });
        }
        self.check_memory(settings)?;
        observer.phase_started("solve");
        Ok(Instant::now())
    }

    /// The solver's attempt on the model (with the levels built beforehand, if any).
    fn attempt(
        &self,
        settings: &Settings,
        start: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Result<solve::Attempt> {
        solve::attempt_with_levels(
            &self.model,
            self.levels(),
            self.built_levels(),
            settings,
            start,
            observer,
        )
    }

    /// The report of an attempt: its answer checked, its fields and totals derived on the
    /// mesh and checked, the phase ended after `t0` (less `excluded` seconds spent on
    /// something else).
    fn finish_solve(
        &self,
        a: solve::Attempt,
        settings: &Settings,
        t0: Instant,
        excluded: f64,
        observer: &mut dyn Observer,
    ) -> Result<Report> {
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
        let seconds = (t0.elapsed().as_secs_f64() - excluded).max(0.0);
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

/// Runs a case of one step end to end (the paper's problem, or with any of its extensions):
/// the whole case validated, the mesh built and the model assembled, everything that needs
/// the mesh checked (regions, data on the boundary, the profile line of `[output]`), then
/// the solve. The outcome is returned whatever the solve's status; bad input is an `Err`.
/// A case with steps (`[sweep]`, `[[load_case]]`) is refused: [`super::run_sweep`] runs
/// those.
pub fn run(case: &Case, observer: &mut dyn Observer) -> Result<Outcome> {
    check_one_step(case)?;
    let observer = &mut solve::Cancellable {
        inner: observer,
        cancel: &case.settings.cancel,
    };
    let discretization = Discretization::new(&case.problem, observer)?;
    case.settings.cancel.check()?;
    check_case_on_mesh(case, discretization.mesh(), false)?;
    let report = discretization.solve(&case.settings, observer)?;
    Ok(Outcome {
        discretization,
        report,
    })
}

/// [`run`] for a run whose outcome is only written afterwards (`memcontact solve`): the
/// discretisation keeps only what the solve and then the writers read
/// ([`Discretization::for_one_solve`], [`Discretization::release_solver_data`]), so that
/// the peak memory of a large run is lower. The outcome's discretisation cannot be solved
/// again.
pub fn run_for_writing(case: &Case, observer: &mut dyn Observer) -> Result<Outcome> {
    check_one_step(case)?;
    let observer = &mut solve::Cancellable {
        inner: observer,
        cancel: &case.settings.cancel,
    };
    let mut discretization =
        Discretization::for_one_solve(&case.problem, &case.settings, observer)?;
    case.settings.cancel.check()?;
    check_case_on_mesh(case, discretization.mesh(), false)?;
    discretization.release_mesh(&case.problem.mesh);
    let report = discretization.solve_once(&case.settings, observer)?;
    discretization.release_solver_data();
    Ok(Outcome {
        discretization,
        report,
    })
}

/// The discretisation `memcontact solve` of `case` solves on, built as that run builds it
/// (not solved): the lean one of [`run_for_writing`] for one solve, everything kept for a
/// sweep, load cases, the adaptive loop, sensitivities or a fit. `memcontact check` reports on it, so that its
/// memory estimate is the one the run checks.
pub fn discretize_as_run(case: &Case, observer: &mut dyn Observer) -> Result<Discretization> {
    if case.is_sweep() || case.adapt.is_some() || case.sensitivity.is_some() || case.fit.is_some() {
        Discretization::new(&case.problem, observer)
    } else {
        Discretization::for_one_solve(&case.problem, &case.settings, observer)
    }
}

/// Runs a problem end to end (mesh, assembly, solve) with `settings`: [`run`] for a
/// problem and settings without the rest of a case.
pub fn run_problem(
    problem: &Problem,
    settings: &Settings,
    observer: &mut dyn Observer,
) -> Result<Outcome> {
    settings.validate().map_err(Invalid::into_error)?;
    let observer = &mut solve::Cancellable {
        inner: observer,
        cancel: &settings.cancel,
    };
    let discretization = Discretization::new(problem, observer)?;
    settings.cancel.check()?;
    let report = discretization.solve(settings, observer)?;
    Ok(Outcome {
        discretization,
        report,
    })
}

/// What the one-step runs ([`run`], [`run_for_writing`]) refuse before any work: a case
/// with steps, an invalid case, a case with `[adapt]`.
fn check_one_step(case: &Case) -> Result<()> {
    refuse_steps(case)?;
    case.validate().map_err(Invalid::into_error)?;
    refuse_adapt(case)
}

/// A case with steps is refused by the one-step runs.
fn refuse_steps(case: &Case) -> Result<()> {
    if case.is_sweep() {
        return Err(Error::Case {
            file: None,
            line: None,
            key: if case.sweep.is_some() {
                "sweep".into()
            } else {
                "load_case".into()
            },
            message: "the case has steps to solve in turn: run them as a sweep".into(),
        });
    }
    Ok(())
}

/// A case with `[adapt]` is refused by the one-step runs.
fn refuse_adapt(case: &Case) -> Result<()> {
    if case.adapt.is_some() {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "adapt".into(),
            message: "the case refines its mesh adaptively: run its adaptive loop".into(),
        });
    }
    Ok(())
}
