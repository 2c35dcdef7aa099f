//! A run with `[sensitivity]`: the case solved, then the derivatives of its outputs in its
//! parameters (docs/theory.md#sensitivities).

use crate::case::Case;
use crate::discretization::check_case_on_mesh;
use crate::discretization::Discretization;
use crate::error::{Error, Invalid, Result};
use crate::outcome::Outcome;
use crate::sensitivity::{Prepared, Request, Sensitivities};
use crate::solve::{self, Observer};
use std::time::Instant;

/// What [`run_sensitivity`] produced: the outcome of the solve and, when the solve was
/// accepted, the derivatives (`None` otherwise: derivatives of an uncertified answer are
/// not computed).
#[derive(Debug)]
pub struct SensitivityRun {
    /// The solve.
    pub outcome: Outcome,
    /// The derivatives.
    pub sensitivities: Option<Sensitivities>,
}

/// Runs a case with `[sensitivity]`: validated, meshed and assembled; the sensors located,
/// the outputs and parameters bound to the mesh (every error before the solve); solved;
/// then the derivatives (phase `sensitivity`). A case without `[sensitivity]` is refused.
pub fn run_sensitivity(case: &Case, observer: &mut dyn Observer) -> Result<SensitivityRun> {
    let spec = case.sensitivity.as_ref().ok_or_else(|| Error::Case {
        file: None,
        line: None,
        key: "sensitivity".into(),
        message: "the case has no [sensitivity] section".into(),
    })?;
    run_request(case, &Request::of(spec), observer)
}

/// [`run_sensitivity`] with an explicit request (outputs, parameters, maps) instead of the
/// case's `[sensitivity]` (the Python module's `sensitivities`).
pub fn run_request(
    case: &Case,
    request: &Request,
    observer: &mut dyn Observer,
) -> Result<SensitivityRun> {
    case.validate().map_err(Invalid::into_error)?;
    if case.is_sweep() || case.adapt.is_some() {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "sensitivity".into(),
            message: "a case with steps or [adapt] has no sensitivities (one discrete \
                      problem is differentiated)"
                .into(),
        });
    }
    let observer = &mut solve::Cancellable::new(observer, &case.settings.cancel);
    let discretization = Discretization::new(&case.problem, observer)?;
    case.settings.cancel.check()?;
    check_case_on_mesh(case, discretization.mesh(), false)?;
    let prepared = Prepared::new(
        &case.problem,
        &case.sensors,
        request,
        discretization.mesh(),
        &discretization.model,
    )?;
    let report = discretization.solve(&case.settings, observer)?;
    let sensitivities = if report.accepted {
        observer.phase_started("sensitivity");
        let t0 = Instant::now();
        let s = prepared.evaluate(
            discretization.mesh(),
            &discretization.model,
            discretization.levels(),
            &report.u,
            &report.certificate,
            report.energy,
        )?;
        observer.phase_finished("sensitivity", t0.elapsed().as_secs_f64());
        Some(s)
    } else {
        None
    };
    Ok(SensitivityRun {
        outcome: Outcome {
            discretization,
            report,
        },
        sensitivities,
    })
}

/// Checks on the mesh what a case's `[[sensor]]`, `[sensitivity]` and `[fit]` need (for
/// `memcontact check`, before any solve): every sensor inside the mesh, the outputs'
/// regions and the parameters bound to the mesh, the measurements read and located.
pub fn check_sensitivity_on_mesh(case: &Case, discretization: &Discretization) -> Result<()> {
    let mesh = discretization.mesh();
    let keyed: Vec<(String, &crate::case::Sensor)> = case
        .sensors
        .iter()
        .enumerate()
        .map(|(i, s)| (format!("sensor.{i}"), s))
        .collect();
    crate::sensitivity::outputs::sensor_outputs(mesh, &keyed)?;
    if let Some(spec) = &case.sensitivity {
        Prepared::new(
            &case.problem,
            &case.sensors,
            &Request::of(spec),
            mesh,
            &discretization.model,
        )?;
    }
    if case.fit.is_some() {
        let (sensors, from_file) = super::fit::measured_sensors(case)?;
        super::fit::locate_measured(case, mesh, &sensors, from_file)?;
    }
    Ok(())
}
