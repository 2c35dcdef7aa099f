//! Problem 2f by a semismooth Newton / primal-dual active-set method with the three vertex
//! states of the consistent model, globalised so that it converges from any start.
//!
//! One iteration:
//! 1. a nonsmooth Gauss-Seidel sweep (exact one-variable minimisation, [`super::relax`]):
//!    it moves every vertex whose state is wrong (a touching vertex whose multiplier has
//!    the wrong sign leaves the kink) and puts vertices exactly on φ_i where their local
//!    minimum is the kink;
//! 2. the states at the new iterate: *clear* (`V_i < φ_i`), *touching* (`V_i = φ_i`) and
//!    *penetrating* (`V_i > φ_i`);
//! 3. the Newton step on the smooth piece selected by the states, with the touching
//!    vertices held on φ (truncated): `(S + E_P L E_P) δ = −∇J` on the free vertices, a
//!    sparse Cholesky refactorisation on the fixed pattern;
//! 4. an exact line search on J ([`super::line_search`]), convex and piecewise quadratic
//!    along the line.
//!
//! J decreases monotonically; the sweep alone is a globally convergent method
//! (docs/theory.md#coordinatewise-optimality), so the iteration converges from any start,
//! and once the states are right the Newton step lands on U exactly (finite termination in
//! exact arithmetic).

use super::line_search::{apply_step, exact_step, line_data};
use super::newton::{newton_system, unit_diagonal_on_truncated, NewtonStates};
use super::relax::sweep_forward;
use super::{IterationRecord, Method, Observer, PhaseTimer, Settings, Solution};
use crate::error::{Error, Result};
use crate::model::Model;
use crate::sparse::{Cholesky, Csr};

/// Default iteration limit.
pub(crate) const MAX_ITERATIONS: usize = 500;

/// A starting point: zero, moved below φ where the obstacle is rigid (and above φ_low
/// where the body below is).
pub fn feasible_start(model: &Model) -> Vec<f64> {
    start_from(model, None)
}

/// The start of an iteration: `start` (a warm start) or zero, projected onto the rigid
/// bodies' constraints ([`Model::project`]).
pub fn start_from(model: &Model, start: Option<&[f64]>) -> Vec<f64> {
    let mut v: Vec<f64> = match start {
        Some(s) => s.to_vec(),
        None => vec![0.0; model.n()],
    };
    model.project(&mut v);
    v
}

/// One globalised step from `v` along `dir` (the exact line search on J); returns the step
/// length (0 when `dir` is not a descent direction). `r = SV − D` at `v`.
pub fn line_step(model: &Model, v: &mut [f64], dir: &[f64], r: &[f64]) -> f64 {
    let (g0, s2) = line_data(model, dir, r);
    match exact_step(model, v, dir, g0, s2) {
        Some(alpha) => {
            apply_step(model, v, dir, alpha);
            alpha
        }
        None => 0.0,
    }
}

/// Solves Problem 2f by the globalised semismooth Newton method described above, from
/// `start` (a warm start) or from zero.
pub fn solve(
    model: &Model,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<Solution> {
    let mut timer = PhaseTimer::default();
    let max = settings.max_iterations.unwrap_or(MAX_ITERATIONS);
    let mut v = start_from(model, start);
    let n = model.n();
    let (mut rhs, mut r) = (vec![0.0; n], vec![0.0; n]);
    let mut st = NewtonStates::of(model, &v);
    let mut a = Csr::zeros(model.s.pattern.clone());
    let mut chol: Option<Cholesky> = None;
    let mut history = Vec::new();
    let mut certificate = model.certificate(&v);
    let mut iterations = 0;
    let mut stalled = 0;
    let mut watch = crate::certificate::FloorWatch::default();
    while iterations < max {
        if certificate.settled(settings.tolerance) || watch.stuck(&certificate) {
            break;
        }
        iterations += 1;
        let before = v.clone();
        timer.time("smoothing", || sweep_forward(model, &mut v));
        timer.time("newton system", || {
            st.update(model, &v);
            newton_system(model, &v, &st, &mut a, None, &mut rhs, &mut r);
            unit_diagonal_on_truncated(&mut a, &st);
        });
        timer.time("factorisation", || -> Result<()> {
            match &mut chol {
                Some(c) => c.refactor(&a),
                None => {
                    chol = Some(Cholesky::new(&a)?);
                    Ok(())
                }
            }
        })?;
        for g in rhs.iter_mut() {
            *g = -*g;
        }
        timer.time("solve", || {
            chol.as_ref().expect("factorised").solve_in_place(&mut rhs)
        });
        timer.time("line search", || {
            // Where a body is rigid the feasible line search stops at the first vertex that
            // hits it; the projected full step (V + δ projected onto the rigid constraints)
            // lets the whole contact set move at once (as a primal-dual active-set method
            // does). Keep whichever is lower.
            let projected = model.has_rigid_part().then(|| {
                let mut w = v.clone();
                for i in 0..w.len() {
                    w[i] += rhs[i];
                }
                model.project(&mut w);
                w
            });
            line_step(model, &mut v, &rhs, &r);
            if let Some(w) = projected {
                if model.energy(&w) < model.energy(&v) {
                    v = w;
                }
            }
        });
        let ev = timer.time("certificate", || crate::certificate::evaluate(model, &v));
        certificate = ev.certificate;
        let record = IterationRecord::new(iterations, &ev);
        observer.iteration(&record);
        settings.cancel.check()?;
        history.push(record);
        if v == before {
            stalled += 1;
            if stalled >= 3 {
                return Err(Error::Solver {
                    solver: "active-set".into(),
                    message: format!(
                        "no progress at iteration {iterations}: scaled KKT residual {:.3e}",
                        certificate.kkt()
                    ),
                });
            }
        } else {
            stalled = 0;
        }
    }
    Ok(Solution {
        energy: model.energy(&v),
        u: v,
        method: Method::ActiveSet,
        iterations,
        certificate,
        multipliers: None,
        history,
        phases: timer.into_phases(),
        coarsening: None,
    })
}
