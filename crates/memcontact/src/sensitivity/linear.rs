//! The Jacobian of a smooth piece and its linear solves (docs/theory.md#tangent):
//! `K = S + E_P L E_P (+ E_Q L_low E_Q)` on the free unknowns, the held ones eliminated
//! (their rows and columns zero), filled by the solvers' own truncated Newton system
//! ([`crate::solve::newton`]). K is symmetric positive definite: tangent and adjoint solves
//! use the same matrix, by a sparse Cholesky factorisation on small problems and by
//! conjugate gradients preconditioned by the project's multigrid cycle (geometric levels
//! when the mesh has them, aggregation otherwise) on large ones. Every solve is certified
//! by its own residual `‖b − K x‖∞ / ‖b‖∞`, recorded.

use super::states::PieceStates;
use crate::error::{Error, Result};
use crate::mesh::refine::Hierarchy;
use crate::model::Model;
use crate::solve::multigrid::cycle::{FcgWork, Multigrid};
use crate::solve::multigrid::Levels;
use crate::solve::newton::newton_system;
use crate::sparse::{Cholesky, Csr};
use std::time::Instant;

/// Below this many unknowns the linear systems are factorised (sparse Cholesky, faer);
/// from it on, multigrid-preconditioned conjugate gradients.
pub const DIRECT_BELOW: usize = 30_000;

/// The relative residual each iterative solve is driven to.
pub const ITERATIVE_TOLERANCE: f64 = 1e-12;

/// The most preconditioned CG steps per round of a solve.
const MAX_STEPS: usize = 100;

/// The most rounds of CG restarted on the true residual.
const ROUNDS: usize = 4;

/// One linear solve of a sensitivity run, as `summary.json` reports it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolveRecord {
    /// `tangent:KEY`, `tangent+:KEY`, `tangent-:KEY` (one-sided), `adjoint:OUTPUT`.
    pub what: String,
    /// `cholesky` or `multigrid-cg`.
    pub solver: String,
    /// Preconditioned CG steps (1 for a factorisation's solve).
    pub iterations: usize,
    /// `‖b − K x‖∞ / ‖b‖∞` (0 for b = 0).
    pub residual: f64,
    /// Wall-clock seconds (the factorisation or the multigrid setup counted in the first
    /// solve that needed it).
    pub seconds: f64,
}

/// How the systems are solved.
enum Backend<'a> {
    Direct(Option<Cholesky>),
    Multigrid(Box<Multigrid<'a>>, FcgWork),
}

/// The Jacobian of one piece, ready to solve with.
pub struct Jacobian<'a> {
    /// K with held rows and columns zero.
    a: Csr,
    /// The held unknowns (zero rows and columns of K; unit diagonal in the factorised
    /// matrix).
    held: Vec<bool>,
    backend: Backend<'a>,
    /// Seconds of setup not yet charged to a solve.
    pending: f64,
    /// The relative residual of the iterative solves.
    tolerance: f64,
}

/// The multigrid levels for the model (geometric from the mesh's hierarchy when it has
/// one, else aggregation of `S + diag(L)`), or `None` when the systems are factorised.
pub fn levels_for(model: &Model, hierarchy: Option<&Hierarchy>) -> Result<Option<Levels>> {
    if model.n() < DIRECT_BELOW {
        return Ok(None);
    }
    Ok(Some(match hierarchy {
        Some(h) if h.depth() >= 2 => crate::solve::multigrid::tnnmg::mesh_levels_of(model, h)?,
        _ => Levels::algebraic(
            &crate::solve::multigrid::tnnmg::setup_matrix(model),
            crate::solve::multigrid::aggregation::COARSEST,
        ),
    }))
}

impl<'a> Jacobian<'a> {
    /// The Jacobian of the piece `states` of `model`, factorised (or its multigrid set up
    /// on `levels`, its solves driven to the relative residual `tolerance`).
    pub fn new(
        model: &'a Model,
        states: &PieceStates,
        levels: Option<&'a Levels>,
        tolerance: f64,
    ) -> Result<Self> {
        let t0 = Instant::now();
        let nst = states.newton(model);
        let n = model.n();
        let mut a = Csr::zeros(model.s.pattern.clone());
        let (mut g, mut r) = (vec![0.0; n], vec![0.0; n]);
        newton_system(model, &model.phi, &nst, &mut a, None, &mut g, &mut r);
        let held = nst.truncated;
        let backend = match levels {
            None => {
                let mut f = a.clone();
                for (i, &h) in held.iter().enumerate() {
                    if h {
                        if let Some(k) = f.pattern.find(i, i) {
                            f.val[k] = 1.0;
                        }
                    }
                }
                let chol = Cholesky::new(&f).map_err(|e| singular(&e))?;
                Backend::Direct(Some(chol))
            }
            Some(levels) => {
                let mut mg = Multigrid::new(levels, levels.len() - 1);
                mg.update(&a, None)?;
                Backend::Multigrid(Box::new(mg), FcgWork::default())
            }
        };
        Ok(Jacobian {
            a,
            held,
            backend,
            pending: t0.elapsed().as_secs_f64(),
            tolerance,
        })
    }

    /// The name of the solver.
    pub fn solver_name(&self) -> &'static str {
        match self.backend {
            Backend::Direct(_) => "cholesky",
            Backend::Multigrid(..) => "multigrid-cg",
        }
    }

    /// The held (eliminated) unknowns.
    pub fn held(&self) -> &[bool] {
        &self.held
    }

    /// Solves `K x = b` on the free unknowns (`b` must be zero on the held ones; `x` is
    /// zero there), certified by its residual; `what` names the solve in the record.
    pub fn solve(&mut self, b: &[f64], what: &str) -> Result<(Vec<f64>, SolveRecord)> {
        let t0 = Instant::now();
        let n = b.len();
        debug_assert!(b.iter().zip(&self.held).all(|(v, &h)| !h || *v == 0.0));
        let norm_b = crate::sparse::norm_inf(b);
        let (x, iterations) = if norm_b == 0.0 {
            (vec![0.0; n], 0)
        } else {
            match &mut self.backend {
                Backend::Direct(chol) => {
                    let mut x = b.to_vec();
                    chol.as_ref().expect("factorised").solve_in_place(&mut x);
                    (x, 1)
                }
                Backend::Multigrid(mg, work) => {
                    // Preconditioned CG, restarted on the true residual while it keeps
                    // falling (iterative refinement: the recurrence's residual drifts from
                    // the true one near the rounding floor).
                    let target = self.tolerance * norm_b;
                    let mut x = vec![0.0; n];
                    let mut r = b.to_vec();
                    let mut steps = 0;
                    let mut last = norm_b;
                    for _ in 0..ROUNDS {
                        let mut dx = vec![0.0; n];
                        let mut rr = r.clone();
                        steps += mg.fcg(
                            &self.a, &mut dx, &mut rr, target, MAX_STEPS, &self.held, work,
                        );
                        for (xi, di) in x.iter_mut().zip(&dx) {
                            *xi += di;
                        }
                        let kx = self.a.mul(&x);
                        for i in 0..n {
                            r[i] = b[i] - kx[i];
                        }
                        let now = crate::sparse::norm_inf(&r);
                        if now <= target || now >= 0.5 * last {
                            break;
                        }
                        last = now;
                    }
                    (x, steps)
                }
            }
        };
        let kx = self.a.mul(&x);
        let res = kx
            .iter()
            .zip(b)
            .map(|(k, b)| (b - k).abs())
            .fold(0.0, f64::max);
        let residual = if norm_b == 0.0 { 0.0 } else { res / norm_b };
        let seconds = t0.elapsed().as_secs_f64() + std::mem::take(&mut self.pending);
        // Certified: a residual far above the one asked for is a failure, not an answer.
        if residual.is_nan() || residual > (100.0 * self.tolerance).max(1e-6) {
            return Err(Error::Solver {
                solver: format!("sensitivity {}", self.solver_name()),
                message: format!(
                    "the {what} solve left the relative residual {residual:.3e} (after \
                     {iterations} steps)"
                ),
            });
        }
        let record = SolveRecord {
            what: what.to_string(),
            solver: self.solver_name().into(),
            iterations,
            residual,
            seconds,
        };
        Ok((x, record))
    }
}

/// The error of a Jacobian that could not be factorised.
fn singular(e: &Error) -> Error {
    Error::Solver {
        solver: "sensitivity cholesky".into(),
        message: format!(
            "the Jacobian S + L on the free unknowns is singular ({e}): a part of the \
             membrane is held by no fixed edge, no penetrated body and no contact"
        ),
    }
}
