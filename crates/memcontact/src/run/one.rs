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
    /// the fields or the totals of the answer are not finite ([`crate::outcome::checks`]).
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

/// Runs a case of one step end to end (the paper's problem, or with any of its extensions):
/// the whole case validated, the mesh built and the model assembled, everything that needs
/// the mesh checked (regions, data on the boundary, the profile line of `[output]`), then
/// the solve. The outcome is returned whatever the solve's status; bad input is an `Err`.
/// A case with steps (`[sweep]`, `[[load_case]]`) is refused: [`super::run_sweep`] runs
/// those.
pub fn run(case: &Case, observer: &mut dyn Observer) -> Result<Outcome> {
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
    case.validate().map_err(Invalid::into_error)?;
    if case.adapt.is_some() {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "adapt".into(),
            message: "the case refines its mesh adaptively: run its adaptive loop".into(),
        });
    }
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
