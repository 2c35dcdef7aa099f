//! A run with `[fit]`: case parameters fitted to measured deflections
//! (docs/theory.md#back-analysis). The mesh is built and the model assembled once;
//! every parameter enters the model linearly, so an iterate's model is the start's
//! moved by the parameters' derivative data
//! ([`crate::sensitivity::parameters::DataDerivative::move_model`]), solved warm from
//! the previous answer; the Jacobian of the sensors' deflections comes from tangent
//! solves on the certified active set. The optimiser is [`crate::fit::optimizer`].

use crate::case::{Case, ParameterKey, Sensor};
use crate::discretization::check_case_on_mesh;
use crate::discretization::Discretization;
use crate::error::{Error, Invalid, Result};
use crate::fit::{optimizer, statistics, FitIteration, FitResult, Fitted, FittedParameter};
use crate::model::Model;
use crate::outcome::{Outcome, Report};
use crate::sensitivity::{Prepared, Request, Sensitivities};
use crate::solve::{self, Observer};
use std::time::Instant;

/// The loosest relative residual of the tangent solves of a fit's Jacobians (far from the
/// answer): the Jacobian is the exact derivative to this accuracy. It tightens with the
/// misfit down to [`JACOBIAN_TOLERANCE_FINAL`] (see `Variables::jacobian`).
pub const JACOBIAN_TOLERANCE: f64 = 1e-3;

/// The tightest relative residual of a fit's tangent solves (at the answer, where the
/// Jacobian also gives the statistics).
pub const JACOBIAN_TOLERANCE_FINAL: f64 = 1e-10;

/// Where a fit's Jacobian was computed: the parameters, the answer (over the unknowns)
/// and its tangents dU/dp, one per parameter.
type Anchor = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// A fit's model: the residuals `(Q(p) − m)/σ` of the measured deflections and their
/// Jacobian in the parameters p (physical units), one warm-started solve per new p. The
/// Python module hands this to `scipy.optimize.least_squares`.
#[derive(Debug)]
pub struct FitProblem {
    case: Case,
    discretization: Discretization,
    base: Model,
    prepared: Prepared,
    keys: Vec<ParameterKey>,
    bounds: Vec<[f64; 2]>,
    sensors: Vec<Sensor>,
    measured: Vec<f64>,
    sigma: Vec<f64>,
    sigmas_given: bool,
    /// The parameters of the model now in the discretisation, and its solve.
    current: Option<(Vec<f64>, Report)>,
    /// The last accepted answer (the warm start).
    warm: Option<Vec<f64>>,
    /// Where the Jacobian was last computed: the parameters, the answer and its tangents
    /// dU/dp; the next solves start from the first-order prediction
    /// `U + Σⱼ (dU/dpⱼ) (p − p₀)ⱼ`.
    anchor: Option<Anchor>,
    solves: usize,
    /// Seconds in forward solves, and in derivatives.
    seconds: (f64, f64),
    /// Every forward solve.
    log: Vec<crate::fit::FitSolve>,
}

impl FitProblem {
    /// The fit of `case` (its `[fit]`): the case validated, the mesh built and the model
    /// assembled, the measurements read (the file, or the sensors' `measured` values) and
    /// located on the mesh; nothing solved yet.
    pub fn new(case: &Case, observer: &mut dyn Observer) -> Result<FitProblem> {
        case.validate().map_err(Invalid::into_error)?;
        let spec = case.fit.as_ref().ok_or_else(|| Error::Case {
            file: None,
            line: None,
            key: "fit".into(),
            message: "the case has no [fit] section".into(),
        })?;
        let (sensors, from_file) = measured_sensors(case)?;
        let discretization = Discretization::new(&case.problem, observer)?;
        check_case_on_mesh(case, discretization.mesh(), false)?;
        locate_measured(case, discretization.mesh(), &sensors, from_file)?;
        let keys: Vec<ParameterKey> = spec
            .parameters
            .0
            .keys()
            .map(|k| {
                ParameterKey::parse(&case.problem, k).map_err(|m| Error::Case {
                    file: None,
                    line: None,
                    key: format!("fit.parameters.{k}"),
                    message: m,
                })
            })
            .collect::<Result<_>>()?;
        let request = Request {
            outputs: sensors
                .iter()
                .map(|s| format!("sensor:{}", s.name))
                .collect(),
            parameters: keys.iter().map(|k| k.key.clone()).collect(),
            influence: false,
        };
        let mut prepared = Prepared::new(
            &case.problem,
            &sensors,
            &request,
            discretization.mesh(),
            &discretization.model,
        )?;
        prepared.keep_tangents = true;
        prepared.linear_tolerance = JACOBIAN_TOLERANCE_FINAL;
        let mut discretization = discretization;
        // One aggregation hierarchy for every solve of the fit, forward and tangent, when
        // the mesh has no refinement levels (built from the start's matrices: the
        // iterates' matrices share its pattern and differ little).
        if discretization.levels().is_none()
            && case.settings.hierarchy == crate::solve::HierarchyChoice::Auto
        {
            if let Some(levels) =
                prepared.shared_levels(&discretization.model, discretization.levels())?
            {
                discretization.share_levels(levels);
            }
        }
        let measured = sensors.iter().map(|s| s.measured.unwrap_or(0.0)).collect();
        let sigma = sensors.iter().map(|s| s.sigma.unwrap_or(1.0)).collect();
        let sigmas_given = sensors.iter().all(|s| s.sigma.is_some());
        Ok(FitProblem {
            bounds: spec.parameters.0.values().copied().collect(),
            base: discretization.model.clone(),
            case: case.clone(),
            discretization,
            prepared,
            keys,
            sensors,
            measured,
            sigma,
            sigmas_given,
            current: None,
            warm: None,
            anchor: None,
            solves: 0,
            seconds: (0.0, 0.0),
            log: Vec::new(),
        })
    }

    /// The fitted keys, in order.
    pub fn parameter_names(&self) -> Vec<String> {
        self.keys.iter().map(|k| k.key.clone()).collect()
    }

    /// The start: the case's values.
    pub fn start(&self) -> Vec<f64> {
        self.keys.iter().map(|k| k.value).collect()
    }

    /// The bounds `[min, max]`, in order.
    pub fn bounds(&self) -> Vec<[f64; 2]> {
        self.bounds.clone()
    }

    /// The measured sensors' names.
    pub fn measurement_names(&self) -> Vec<String> {
        self.sensors.iter().map(|s| s.name.clone()).collect()
    }

    /// The forward solves done.
    pub fn solves(&self) -> usize {
        self.solves
    }

    /// Solves the model at the parameters `p` (warm from the last accepted answer) unless
    /// it is already solved there; `Ok(false)` when the solve was not accepted.
    fn solve_at(&mut self, p: &[f64], observer: &mut dyn Observer) -> Result<bool> {
        if self.current.as_ref().is_some_and(|(q, _)| q == p) {
            return Ok(self.current.as_ref().is_some_and(|(_, r)| r.accepted));
        }
        if p.len() != self.keys.len() || p.iter().any(|v| !v.is_finite()) {
            return Err(Error::Data(format!(
                "the fit's model takes {} finite parameters, got {p:?}",
                self.keys.len()
            )));
        }
        let mut model = self.base.clone();
        for ((d, k), &v) in self.prepared.parameters.iter().zip(&self.keys).zip(p) {
            d.move_model(&mut model, v - k.value);
        }
        crate::model::check_model(self.discretization.mesh(), &model)?;
        self.discretization.model = model;
        // The start: the first-order prediction from the last Jacobian's tangents, else
        // the last accepted answer.
        let predicted = self.anchor.as_ref().map(|(p0, u0, tangents)| {
            let mut u = u0.clone();
            for (t, (&a, &b)) in tangents.iter().zip(p.iter().zip(p0)) {
                for (ui, ti) in u.iter_mut().zip(t) {
                    *ui += ti * (a - b);
                }
            }
            u
        });
        let start = predicted
            .filter(|u| u.iter().all(|v| v.is_finite()))
            .or_else(|| self.warm.clone());
        let t0 = Instant::now();
        let report =
            self.discretization
                .solve_from(&self.case.settings, start.as_deref(), observer)?;
        let seconds = t0.elapsed().as_secs_f64();
        self.seconds.0 += seconds;
        self.solves += 1;
        self.log.push(crate::fit::FitSolve {
            parameters: p.to_vec(),
            iterations: report.iterations,
            seconds,
            accepted: report.accepted,
        });
        let accepted = report.accepted;
        if accepted {
            self.warm = Some(report.u.clone());
        }
        self.current = Some((p.to_vec(), report));
        Ok(accepted)
    }

    /// The weighted residuals `(Q(p) − m)/σ` at the parameters `p` (one solve unless `p`
    /// is where the model was last solved). A solve that is not accepted is an error.
    pub fn residuals(&mut self, p: &[f64]) -> Result<Vec<f64>> {
        if !self.solve_at(p, &mut solve::Silent)? {
            let (_, r) = self.current.as_ref().expect("solved");
            return Err(r
                .error()
                .unwrap_or_else(|| Error::Data("not accepted".into())));
        }
        let q = self.values_now();
        Ok(self.weighted(&q))
    }

    /// `(Q − m)/σ` of the values `q`.
    fn weighted(&self, q: &[f64]) -> Vec<f64> {
        q.iter()
            .zip(&self.measured)
            .zip(&self.sigma)
            .map(|((q, m), s)| (q - m) / s)
            .collect()
    }

    /// The sensors' values at the current solution.
    fn values_now(&self) -> Vec<f64> {
        let (_, report) = self.current.as_ref().expect("solved");
        let d = &self.discretization;
        self.prepared.values(
            d.mesh(),
            &d.model,
            &report.u,
            &report.certificate,
            report.energy,
        )
    }

    /// The sensors' values and derivatives at the current solution.
    fn sensitivities_at(&self) -> Result<Sensitivities> {
        let (_, report) = self.current.as_ref().expect("solved");
        let d = &self.discretization;
        self.prepared.evaluate(
            d.mesh(),
            &d.model,
            d.levels(),
            &report.u,
            &report.certificate,
            report.energy,
        )
    }

    /// The Jacobian `∂r/∂p` of the weighted residuals at the parameters last solved,
    /// row-major (measurements × parameters): the exact derivatives of the discrete
    /// problem (tangent solves; at biactive vertices the mean of the one-sided ones).
    pub fn jacobian(&mut self) -> Result<Vec<f64>> {
        if self.current.is_none() {
            return Err(Error::Data(
                "the fit's model has not been solved yet".into(),
            ));
        }
        let t0 = Instant::now();
        let s = self.sensitivities_at()?;
        self.seconds.1 += t0.elapsed().as_secs_f64();
        if s.tangents.len() == self.keys.len() {
            let (p, report) = self.current.as_ref().expect("solved");
            self.anchor = Some((p.clone(), report.u.clone(), s.tangents));
        }
        let np = self.keys.len();
        Ok((0..self.sensors.len() * np)
            .map(|k| s.derivative[k] / self.sigma[k / np])
            .collect())
    }

    /// Both, at `p` (for `scipy.optimize.least_squares(fun, x0, jac=...)`).
    pub fn residuals_and_jacobian(&mut self, p: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let r = self.residuals(p)?;
        Ok((r, self.jacobian()?))
    }
}

/// The measured sensors of a case's `[fit]`: the measurements file's rows, or the
/// sensors with a `measured` value; and whether they come from the file. Too few for the
/// parameters (without a prior) is an error naming the key.
pub(crate) fn measured_sensors(case: &Case) -> Result<(Vec<Sensor>, bool)> {
    let spec = case.fit.as_ref().ok_or_else(|| Error::Case {
        file: None,
        line: None,
        key: "fit".into(),
        message: "the case has no [fit] section".into(),
    })?;
    let (sensors, from_file) = match &spec.measurements {
        Some(path) => (crate::fit::measurements::read_measurements(path)?, true),
        None => (
            case.sensors
                .iter()
                .filter(|s| s.measured.is_some())
                .cloned()
                .collect::<Vec<_>>(),
            false,
        ),
    };
    crate::case::sensitivity::check_enough(sensors.len(), spec).map_err(|m| Error::Case {
        file: None,
        line: None,
        key: if from_file {
            "fit.measurements".into()
        } else {
            "fit".into()
        },
        message: m,
    })?;
    Ok((sensors, from_file))
}

/// Every measured sensor inside the mesh (an error naming the sensor, or the file's row).
pub(crate) fn locate_measured(
    case: &Case,
    mesh: &crate::mesh::Mesh,
    sensors: &[Sensor],
    from_file: bool,
) -> Result<()> {
    let keyed: Vec<(String, &Sensor)> = sensors
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let key = if from_file {
                format!(
                    "fit.measurements (row {} of the file, sensor {})",
                    i + 1,
                    s.name
                )
            } else {
                let k = case
                    .sensors
                    .iter()
                    .position(|c| c.name == s.name)
                    .unwrap_or(i);
                format!("sensor.{k}")
            };
            (key, s)
        })
        .collect();
    crate::sensitivity::outputs::sensor_outputs(mesh, &keyed)?;
    Ok(())
}

/// The variables the optimiser moves: ln p for positive parameters fitted on positive
/// bounds, p otherwise.
struct Variables<'a> {
    problem: &'a mut FitProblem,
    log: Vec<bool>,
    /// The start in both forms (so that the start's variables give back its parameters
    /// exactly, not through `exp(ln p)`).
    x0: Vec<f64>,
    p0: Vec<f64>,
    observer: &'a mut dyn Observer,
    /// The cost of the last residuals, and of the first.
    cost: (f64, f64),
}

impl Variables<'_> {
    fn to_p(&self, x: &[f64]) -> Vec<f64> {
        to_parameters(x, &self.log, &self.x0, &self.p0)
    }
}

/// The parameters of the variables x (`exp x` for logarithmic ones; the start's exactly).
fn to_parameters(x: &[f64], log: &[bool], x0: &[f64], p0: &[f64]) -> Vec<f64> {
    (0..x.len())
        .map(|j| {
            if x[j] == x0[j] {
                p0[j]
            } else if log[j] {
                x[j].exp()
            } else {
                x[j]
            }
        })
        .collect()
}

impl optimizer::LeastSquares for Variables<'_> {
    fn residuals(&mut self, x: &[f64]) -> Result<Vec<f64>> {
        let p = self.to_p(x);
        if !self.problem.solve_at(&p, self.observer)? {
            // A trial whose solve is not accepted is a step too far: an infinite cost.
            return Ok(vec![f64::INFINITY; self.problem.sensors.len()]);
        }
        let q = self.problem.values_now();
        let r = self.problem.weighted(&q);
        let cost = 0.5 * r.iter().map(|v| v * v).sum::<f64>();
        self.cost = (cost, if self.cost.1 > 0.0 { self.cost.1 } else { cost });
        Ok(r)
    }

    fn jacobian(&mut self) -> Result<Vec<f64>> {
        let (p, _) = self.problem.current.clone().expect("solved");
        // Inexact Gauss-Newton: the tangent solves of the Jacobian to a residual that
        // tightens with the misfit (a Jacobian accurate to η contracts the error by about
        // η besides the step's quadratic term): 1e-3 at the start, 1e-10 at the answer.
        let (cost, first) = self.cost;
        self.problem.prepared.linear_tolerance = (1e-3 * cost / first.max(f64::MIN_POSITIVE))
            .clamp(JACOBIAN_TOLERANCE_FINAL, JACOBIAN_TOLERANCE);
        let j = self.problem.jacobian()?;
        let np = p.len();
        Ok(j.iter()
            .enumerate()
            .map(|(k, v)| if self.log[k % np] { v * p[k % np] } else { *v })
            .collect())
    }
}

/// What [`run_fit`] produced: the outcome at the fitted (or, without convergence, the
/// best) parameters, the fit, the case with the fitted values, and the case's
/// `[sensitivity]` at them when it has one.
#[derive(Debug)]
pub struct FitRun {
    /// The solve at the fitted parameters.
    pub outcome: Outcome,
    /// The fit.
    pub fit: FitResult,
    /// The case with the fitted values.
    pub fitted_case: Case,
    /// The case's `[sensitivity]` at the fitted parameters.
    pub sensitivities: Option<Sensitivities>,
}

/// Runs a case with `[fit]`: bounded Levenberg-Marquardt (in ln p for positive
/// parameters) with the exact Jacobian and every forward solve warm-started, then the
/// statistics of the answer (covariance `σ̂² (JᵀWJ)⁻¹`, standard errors, correlations,
/// singular values of the scaled Jacobian, the identifiability warning). A fit that does
/// not converge is returned with its best iterate (`fit.converged` false); bad input, and
/// a start whose solve is not accepted, are errors.
pub fn run_fit(case: &Case, observer: &mut dyn Observer) -> Result<FitRun> {
    let t0 = Instant::now();
    let observer = &mut solve::Cancellable::new(observer, &case.settings.cancel);
    let mut problem = FitProblem::new(case, observer)?;
    let spec = case.fit.as_ref().expect("validated");
    let p0 = problem.start();
    let bounds = problem.bounds();
    let log: Vec<bool> = bounds
        .iter()
        .zip(&p0)
        .map(|(b, &p)| b[0] > 0.0 && p > 0.0)
        .collect();
    let to_x = |p: f64, l: bool| if l { p.ln() } else { p };
    let x0: Vec<f64> = p0.iter().zip(&log).map(|(&p, &l)| to_x(p, l)).collect();
    let lo: Vec<f64> = bounds
        .iter()
        .zip(&log)
        .map(|(b, &l)| to_x(b[0], l))
        .collect();
    let hi: Vec<f64> = bounds
        .iter()
        .zip(&log)
        .map(|(b, &l)| to_x(b[1], l))
        .collect();
    // The start must solve.
    if !problem.solve_at(&p0, observer)? {
        let (_, r) = problem.current.as_ref().expect("solved");
        return Err(r
            .error()
            .unwrap_or_else(|| Error::Data("the start was not accepted".into()))
            .context("the fit's start (the case's own values)"));
    }
    let options = optimizer::Options {
        max_iterations: spec.max_iterations,
        tolerance: spec.tolerance,
        prior: spec.prior.unwrap_or(0.0),
        radius: 1.0,
    };
    let mut history = Vec::new();
    let minimum = {
        let mut vars = Variables {
            problem: &mut problem,
            log: log.clone(),
            x0: x0.clone(),
            p0: p0.clone(),
            observer,
            cost: (0.0, 0.0),
        };
        let n_meas = vars.problem.sensors.len().max(1) as f64;
        let (log_c, x0_c, p0_c) = (log.clone(), x0.clone(), p0.clone());
        optimizer::minimize(&mut vars, &x0, &lo, &hi, &options, &mut |it| {
            history.push(FitIteration {
                iteration: it.iteration,
                parameters: to_parameters(&it.x, &log_c, &x0_c, &p0_c),
                rms: (2.0 * it.cost / n_meas).sqrt(),
                step: it.step,
                damping: it.damping,
                solves: it.evaluations,
            })
        })?
    };
    let p = to_parameters(&minimum.x, &log, &x0, &p0);
    // The discretisation holds the model of the best point (the optimiser's last
    // evaluation).
    problem.solve_at(&p, observer)?;
    let names = problem.parameter_names();
    let stats = statistics(
        &minimum.jacobian,
        &minimum.r,
        &p,
        &log,
        problem.sigmas_given,
        options.prior,
        &names,
    );
    let values = problem.values_now();
    let measurements: Vec<Fitted> = problem
        .sensors
        .iter()
        .zip(&values)
        .zip(&problem.sigma)
        .map(|((s, &q), &sigma)| Fitted {
            name: s.name.clone(),
            at: s.at,
            measured: s.measured.unwrap_or(0.0),
            sigma,
            computed: q,
        })
        .collect();
    let data_cost: f64 = 0.5 * minimum.r.iter().map(|v| v * v).sum::<f64>();
    let parameters: Vec<FittedParameter> = names
        .iter()
        .enumerate()
        .map(|(j, k)| FittedParameter {
            key: k.clone(),
            value: p[j],
            start: p0[j],
            bounds: bounds[j],
            log: log[j],
            std_error: stats.std_errors[j],
        })
        .collect();
    let mut fitted_case = case.clone();
    for (k, &v) in problem.keys.iter().zip(&p) {
        k.apply(&mut fitted_case.problem, v)
            .map_err(|m| Error::Data(format!("{}: {m}", k.key)))?;
    }
    let FitProblem {
        discretization,
        current,
        solves,
        seconds: (seconds_solves, seconds_derivatives),
        log: forward_solves,
        ..
    } = problem;
    let (_, report) = current.expect("solved");
    let sensitivities = match (&fitted_case.sensitivity, report.accepted) {
        (Some(spec), true) => {
            let prepared = Prepared::new(
                &fitted_case.problem,
                &fitted_case.sensors,
                &Request::of(spec),
                discretization.mesh(),
                &discretization.model,
            )?;
            Some(prepared.evaluate(
                discretization.mesh(),
                &discretization.model,
                discretization.levels(),
                &report.u,
                &report.certificate,
                report.energy,
            )?)
        }
        _ => None,
    };
    let n_meas = measurements.len().max(1) as f64;
    let fit = FitResult {
        parameters,
        statistics: stats,
        rms: (2.0 * data_cost / n_meas).sqrt(),
        cost: minimum.cost,
        iterations: minimum.history.len() - 1,
        solves,
        converged: minimum.stop.converged(),
        stop: minimum.stop,
        measurements,
        history,
        seconds: t0.elapsed().as_secs_f64(),
        seconds_solves,
        seconds_derivatives,
        forward_solves,
    };
    Ok(FitRun {
        outcome: Outcome {
            discretization,
            report,
        },
        fit,
        fitted_case,
        sensitivities,
    })
}
