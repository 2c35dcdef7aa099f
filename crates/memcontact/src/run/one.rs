//! One run: a problem solved on its discretisation, by the method the settings name or the
//! one `auto` picks, checked before anyone reports or writes it.

use crate::case::Case;
use crate::discretization::{check_case_on_mesh, Discretization, Phase};
use crate::error::{Error, Invalid, Result};
use crate::outcome::fields::derive_from;
use crate::outcome::{Outcome, Report, Summary};
use crate::solve::{self, Cancellable, Choice, Method, Observer, Settings};
use crate::write::WriteOptions;
use std::path::Path;
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
    /// the fields or the totals of the answer are not finite
    /// ([`crate::solve::check_solution`], [`Outcome::checked_fields`]).
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
    pub(crate) fn solve_once(
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

    /// The checks before a solve (not released); starts its phase.
    fn begin_solve(&self, settings: &Settings, observer: &mut dyn Observer) -> Result<Instant> {
        if self.is_released() {
            return Err(Error::Solver {
                solver: self.method_for(settings).name().into(),
                message: "this discretisation was solved once and its matrices released: \
                          build it again to solve it again"
                    .into(),
            });
        }
        observer.phase_started("solve");
        Ok(Instant::now())
    }

    /// The solver's attempt on the model ([`solve::solve_model`], with the levels built
    /// beforehand, if any).
    fn attempt(
        &self,
        settings: &Settings,
        start: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Result<solve::Attempt> {
        solve::solve_model(
            &self.model,
            self.levels(),
            self.built_levels(),
            settings,
            start,
            observer,
        )
    }

    /// The report of an attempt: its fields and totals derived on the mesh and checked,
    /// the phase ended after `t0` (less `excluded` seconds spent on something else).
    fn finish_solve(
        &self,
        a: solve::Attempt,
        settings: &Settings,
        t0: Instant,
        excluded: f64,
        observer: &mut dyn Observer,
    ) -> Result<Report> {
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
/// those, and [`super::run_adapt`] a case with `[adapt]`.
///
/// The outcome keeps everything: its discretisation can be solved again (with other
/// settings, from another start) and its matrices read. [`run_to_files`] is the same run
/// for a caller that only writes its result set, at a lower peak of memory.
pub fn run(case: &Case, observer: &mut dyn Observer) -> Result<Outcome> {
    check_one_step(case)?;
    let observer = &mut Cancellable::new(observer, &case.settings.cancel);
    let discretization = Discretization::new(&case.problem, observer)?;
    case.settings.cancel.check()?;
    check_case_on_mesh(case, discretization.mesh(), false)?;
    let report = discretization.solve(&case.settings, observer)?;
    Ok(Outcome {
        discretization,
        report,
    })
}

/// What [`run_to_files`] did: the outcome, and the summary of the result set written (none
/// when the solve was not accepted and [`WriteOptions::unconverged`] was not set).
#[derive(Debug)]
pub struct Written {
    /// The outcome (its discretisation cannot be solved again).
    pub outcome: Outcome,
    /// `summary.json`'s values, when the files were written.
    pub summary: Option<Summary>,
}

/// Runs a case of one step ([`run`]) and writes its result set into `target` as
/// `memcontact solve` does: `solution.vtu`, `nodes.csv`, the pictures of `[output]` and
/// `summary.json`, as one atomic set ([`crate::write::write_result`]). An outcome the
/// settings do not accept is written only with [`WriteOptions::unconverged`] (marked in
/// `summary.json`).
///
/// The run keeps only what the solve and then the writers read: a generated mesh is
/// built again after the solve instead of being held through it, and the matrices go
/// before the files are written, so the peak memory of a large run is lower than
/// [`run`]'s.
pub fn run_to_files(
    case: &Case,
    target: &Path,
    options: &WriteOptions,
    observer: &mut dyn Observer,
) -> Result<Written> {
    check_one_step(case)?;
    let observer = &mut Cancellable::new(observer, &case.settings.cancel);
    let mut discretization =
        Discretization::for_one_solve(&case.problem, &case.settings, observer)?;
    case.settings.cancel.check()?;
    check_case_on_mesh(case, discretization.mesh(), false)?;
    discretization.release_mesh(&case.problem.mesh);
    let report = discretization.solve_once(&case.settings, observer)?;
    discretization.release_solver_data();
    let outcome = Outcome {
        discretization,
        report,
    };
    let summary = if outcome.report.accepted || options.unconverged {
        let plots = crate::write::plot_options(case, &options.label);
        Some(crate::write::write_result(
            target, &outcome, case, options, &plots,
        )?)
    } else {
        None
    };
    Ok(Written { outcome, summary })
}

/// What [`check`] found: the discretisation the run would solve on (built as the run
/// builds it, not solved), every check of the case on its mesh passed.
#[derive(Debug)]
pub struct Checked {
    /// The mesh levels and the assembled model.
    pub discretization: Discretization,
    /// The method `auto` picks on this problem, and why.
    pub auto: (Method, Choice),
    /// The estimated peak memory of the run (bytes).
    pub memory_needed: f64,
    /// The memory available to the run (bytes), and where that figure comes from.
    pub memory_available: (u64, String),
}

/// Checks a case as `memcontact check` does: everything the run would refuse, without
/// solving. The case is validated; the mesh built and the model assembled as the run
/// builds them (lean for one solve; everything kept for a sweep, load cases, the adaptive
/// loop, sensitivities or a fit), so that the memory estimate is the one the run checks;
/// the load cases' data are assembled on the mesh, the profile line, the adaptive loop's
/// limits, the sensors, the outputs and parameters of `[sensitivity]` and the
/// measurements of `[fit]` checked against it; and a solve that would not fit in the
/// memory available is refused.
pub fn check(case: &Case, observer: &mut dyn Observer) -> Result<Checked> {
    case.validate().map_err(Invalid::into_error)?;
    // The memory available is read before the check's own mesh and model take theirs.
    let memory_available = crate::limits::available_memory();
    let observer = &mut Cancellable::new(observer, &case.settings.cancel);
    let keeps_everything =
        case.is_sweep() || case.adapt.is_some() || case.sensitivity.is_some() || case.fit.is_some();
    let discretization = if keeps_everything {
        Discretization::new(&case.problem, observer)?
    } else {
        Discretization::for_one_solve(&case.problem, &case.settings, observer)?
    };
    check_case_on_mesh(case, discretization.mesh(), true)?;
    discretization.check_memory(&case.settings)?;
    if let Some(a) = &case.adapt {
        crate::adapt::check_adapt_on_mesh(a, discretization.mesh())?;
    }
    super::sensitivity::check_sensitivity_on_mesh(case, &discretization)?;
    Ok(Checked {
        auto: discretization.auto_choice(),
        memory_needed: discretization.memory_estimate(&case.settings),
        memory_available,
        discretization,
    })
}

/// What the one-step runs ([`run`], [`run_to_files`]) refuse before any work: a case
/// with steps, an invalid case, a case with `[adapt]` or `[fit]` (a case with
/// `[sensitivity]` is solved, without its derivatives: [`super::run_sensitivity`] computes
/// them).
fn check_one_step(case: &Case) -> Result<()> {
    refuse_steps(case)?;
    case.validate().map_err(Invalid::into_error)?;
    refuse_adapt(case)?;
    refuse_fit(case)
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

/// A case with `[fit]` is refused by the one-step runs: its answer is at the fitted
/// parameters, not the case's own.
fn refuse_fit(case: &Case) -> Result<()> {
    if case.fit.is_some() {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "fit".into(),
            message: "the case fits parameters to measurements: run its fit".into(),
        });
    }
    Ok(())
}
