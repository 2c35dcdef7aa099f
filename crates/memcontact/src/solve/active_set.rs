//! Problem 2f by a semismooth Newton / primal-dual active-set method with the three vertex
//! states of the consistent model, globalised so that it converges from any start.
//!
//! One iteration:
//! 1. a nonsmooth Gauss-Seidel sweep (exact one-variable minimisation, [`super::local`]):
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
//! J decreases monotonically; the sweep alone is a globally convergent method (SPEC §3),
//! so the iteration converges from any start, and once the states are right the Newton
//! step lands on U exactly (finite termination in exact arithmetic).

use super::line_search::{apply_step, exact_step, Line};
use super::local::sweep_forward;
use super::{IterationRecord, Method, Observer, PhaseTimer, Settings, Solution};
use crate::model::{FoundationMatrix, Model};
use crate::sparse::{dot, Cholesky, Csr};
use crate::{Error, Result};
use rayon::prelude::*;

/// Default iteration limit.
pub(crate) const MAX_ITERATIONS: usize = 500;

/// A starting point: zero, moved below φ where the obstacle is rigid.
pub fn feasible_start(model: &Model) -> Vec<f64> {
    let mut v: Vec<f64> = vec![0.0; model.n()];
    if model.is_rigid() {
        for ((vi, fi), &c) in v.iter_mut().zip(&model.phi).zip(&model.can_touch) {
            if c {
                *vi = vi.min(*fi);
            }
        }
    }
    v
}

/// The states of the truncated Newton step at V: which vertices are held (touching, or at
/// the rigid obstacle) and which penetrate.
#[derive(Debug, Clone)]
pub struct NewtonStates {
    /// Held fixed on φ_i: `V_i = φ_i` on M.
    pub truncated: Vec<bool>,
    /// `V_i > φ_i` on M (elastic obstacle only).
    pub penetrating: Vec<bool>,
}

impl NewtonStates {
    /// The states of V.
    pub fn of(model: &Model, v: &[f64]) -> NewtonStates {
        let n = model.n();
        let mut truncated = vec![false; n];
        let mut penetrating = vec![false; n];
        for i in 0..n {
            if model.can_touch[i] {
                truncated[i] = v[i] == model.phi[i];
                penetrating[i] = !model.is_rigid() && v[i] > model.phi[i];
            }
        }
        NewtonStates {
            truncated,
            penetrating,
        }
    }
}

/// The gradient of the smooth piece of J selected by the states: `S V − D + E_P L p`, zero
/// on truncated vertices. Also returns `SV − D`.
pub fn piece_gradient(model: &Model, v: &[f64], st: &NewtonStates) -> (Vec<f64>, Vec<f64>) {
    let r = model.residual(v);
    let p = model.penetration(v);
    let mut g: Vec<f64> = vec![0.0; model.n()];
    g.par_iter_mut()
        .enumerate()
        .with_min_len(4096)
        .for_each(|(i, gi)| {
            if st.truncated[i] {
                return;
            }
            *gi = r[i];
            if st.penetrating[i] {
                *gi += model.l.row_dot(i, &p);
            }
        });
    (g, r)
}

/// Fills `a` (on the pattern of S) with the truncated Hessian of the piece: `S + E_P L E_P`
/// with the rows and columns of truncated vertices replaced by the identity.
pub fn fill_truncated_hessian(model: &Model, st: &NewtonStates, a: &mut Csr) {
    let pat = model.s.pattern.clone();
    let rows: Vec<(usize, usize)> = (0..pat.n())
        .map(|i| (pat.row_ptr[i], pat.row_ptr[i + 1]))
        .collect();
    let sval = &model.s.val;
    let lumped = match &model.l {
        FoundationMatrix::Lumped(d) => Some(d),
        _ => None,
    };
    let consistent = match &model.l {
        FoundationMatrix::Consistent(l) => Some(&l.val),
        _ => None,
    };
    // Each row is written independently.
    let mut chunks: Vec<&mut [f64]> = Vec::with_capacity(rows.len());
    let mut rest: &mut [f64] = &mut a.val;
    for &(s, e) in &rows {
        let (h, t) = rest.split_at_mut(e - s);
        chunks.push(h);
        rest = t;
    }
    chunks
        .par_iter_mut()
        .enumerate()
        .with_min_len(2048)
        .for_each(|(i, row)| {
            let (s, e) = rows[i];
            let cols = &pat.col[s..e];
            for (k, &j) in cols.iter().enumerate() {
                let j = j as usize;
                row[k] = if st.truncated[i] || st.truncated[j] {
                    if i == j {
                        1.0
                    } else {
                        0.0
                    }
                } else {
                    let mut v = sval[s + k];
                    if st.penetrating[i] && st.penetrating[j] {
                        if let Some(l) = consistent {
                            v += l[s + k];
                        } else if let Some(d) = lumped {
                            if i == j {
                                v += d[i];
                            }
                        }
                    }
                    v
                };
            }
        });
}

/// One globalised step from `v` along `dir` (exact line search); returns the step length
/// (0 when `dir` is not a descent direction).
pub fn line_step(model: &Model, v: &mut [f64], dir: &[f64], r: &[f64]) -> f64 {
    let sd = model.s.mul(dir);
    let line = Line {
        v,
        dir,
        g0: dot(dir, r),
        s2: dot(dir, &sd),
    };
    match exact_step(model, &line) {
        Some(alpha) if alpha > 0.0 => {
            apply_step(model, v, dir, alpha);
            alpha
        }
        _ => 0.0,
    }
}

/// Solves Problem 2f by the globalised semismooth Newton method described above.
pub fn solve(model: &Model, settings: &Settings, observer: &mut dyn Observer) -> Result<Solution> {
    let mut timer = PhaseTimer::default();
    let max = settings.max_iterations.unwrap_or(MAX_ITERATIONS);
    let mut v = feasible_start(model);
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
        let st = NewtonStates::of(model, &v);
        let (mut rhs, r) = timer.time("newton system", || {
            fill_truncated_hessian(model, &st, &mut a);
            piece_gradient(model, &v, &st)
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
            // For the rigid obstacle the feasible line search stops at the first vertex that
            // hits φ; the projected full step min(V + δ, φ) lets the whole contact set move
            // at once (as a primal-dual active-set method does). Keep whichever is lower.
            let projected = model.is_rigid().then(|| {
                let mut w = v.clone();
                for i in 0..w.len() {
                    w[i] += rhs[i];
                    if model.can_touch[i] && w[i] > model.phi[i] {
                        w[i] = model.phi[i];
                    }
                }
                w
            });
            line_step(model, &mut v, &rhs, &r);
            if let Some(w) = projected {
                if model.energy(&w) < model.energy(&v) {
                    v = w;
                }
            }
        });
        certificate = timer.time("certificate", || model.certificate(&v));
        let record = IterationRecord {
            iteration: iterations,
            energy: model.energy(&v),
            residual: certificate.kkt(),
        };
        observer.iteration(&record);
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
    })
}
