//! Problem 2b by exact coordinatewise minimisation of J: nonsmooth Gauss-Seidel sweeps
//! (docs/theory.md#coordinatewise-optimality: coordinatewise optimality is global
//! optimality, so the sweeps converge to U). Simple and robust, but the number of sweeps
//! grows like the square of the mesh size: meant for verification on small meshes.

use super::relax::sweep_forward;
use super::{IterationRecord, Method, Observer, PhaseTimer, Settings, Solution};
use crate::error::Result;
use crate::model::Model;

/// Default limit on sweeps.
pub(crate) const MAX_SWEEPS: usize = 1_000_000;

/// Problem 2b by exact coordinatewise minimisation, from `start` (made feasible for a rigid
/// obstacle) when given: sweeps until the KKT residual is below the tolerance (checked
/// every few sweeps).
pub fn solve_from(
    model: &Model,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<Solution> {
    let mut timer = PhaseTimer::default();
    let max = settings.max_iterations.unwrap_or(MAX_SWEEPS);
    let mut v = super::active_set::start_from(model, start);
    let mut history = Vec::new();
    let mut sweeps = 0;
    let mut check_every = 1;
    let mut certificate = model.certificate(&v);
    let mut watch = crate::certificate::FloorWatch::default();
    while sweeps < max {
        let todo = check_every.min(max - sweeps);
        timer.time("sweeps", || {
            for _ in 0..todo {
                if settings.cancel.is_cancelled() {
                    break;
                }
                sweep_forward(model, &mut v);
            }
        });
        settings.cancel.check()?;
        sweeps += todo;
        let ev = timer.time("certificate", || crate::certificate::evaluate(model, &v));
        certificate = ev.certificate;
        let record = IterationRecord::new(sweeps, &ev);
        observer.iteration(&record);
        settings.cancel.check()?;
        history.push(record);
        if certificate.settled(settings.tolerance) || watch.stuck(&certificate) {
            break;
        }
        // Check less often as sweeps accumulate (at most ~2% of the work is checking).
        check_every = (sweeps / 50).clamp(1, 200);
    }
    Ok(Solution {
        energy: model.energy(&v),
        u: v,
        method: Method::Coordinate,
        iterations: sweeps,
        certificate,
        multipliers: None,
        history,
        phases: timer.into_phases(),
        coarsening: None,
    })
}
