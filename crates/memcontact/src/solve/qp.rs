//! Problem 2c (the paper's strictly convex quadratic programme) by the Clarabel
//! interior-point solver, with the multipliers of Problems 2d/2e read from its duals and an
//! exact polishing step on the piece of Problem 2f that the interior-point answer selects.
//!
//! **Problem 2c.** Variables `V₁ ∈ Rᵐ` (all unknowns) and `V₂ ∈ R^M` (one auxiliary
//! penetration per vertex of M):
//!
//! ```text
//! minimise   ½ V₁ᵀ S V₁ − V₁ᵀ D + ½ V₂ᵀ L̃ V₂
//! subject to Ṽ₁ − φ̃ − V₂ ≤ 0   (multiplier X₁ ≥ 0)
//!            −V₂ ≤ 0           (multiplier X₂ ≥ 0)
//! ```
//!
//! handed to Clarabel as `min ½xᵀPx + qᵀx, Ax + s = b, s ≥ 0` with
//! `x = (V₁, V₂)`, `P = diag(S, L̃)` (upper triangle), `q = (−D, 0)`,
//! `A = [[E_M, −I], [0, −I]]`, `b = (φ̃, 0)`. Clarabel's dual `z ≥ 0` satisfies
//! `Px + q + Aᵀz = 0`, i.e. `S V₁ − D + X̂₁ = 0` and `L̃V₂ − X₁ − X₂ = 0`: the rows of the
//! Kuhn-Tucker system 2e with `z = (X₁, X₂)`, the multipliers of the Lagrangian of 2d.
//! For the rigid obstacle there is no `V₂`: `min ½V₁ᵀSV₁ − V₁ᵀD` subject to `Ṽ₁ ≤ φ̃`,
//! and `z = X₁`.
//!
//! **Beyond the paper (docs/theory.md#extensions).** Where the obstacle is rigid in some
//! regions only, the vertices it holds rigidly have the constraint `V₁ᵢ ≤ φᵢ` and no `V₂ᵢ`.
//! A body below adds the variables `V₃` with `½ V₃ᵀ L̃_low V₃` in the objective and the
//! rows `φ̃_low − Ṽ₁ − V₃ ≤ 0`, `−V₃ ≤ 0` (`−Ṽ₁ ≤ −φ̃_low` where it is rigid); their duals
//! are the body's contact forces (pushing up) and the multipliers of `V₃ ≥ 0`. A vertex
//! both rigid bodies hold at one height (`φ_low = φ`) gets one equality row (a zero cone)
//! instead of two opposite inequalities, which would leave an interior point no room.
//!
//! **Scaling.** With a length `ℓ` (the largest |φ| on M, or the displacement one unit of
//! force scale produces) and the force scale `F` of the certificates, the solver sees
//! `x = ℓ y` and the objective divided by `ℓF`: `q/F` and `Pℓ/F` are of order one whatever
//! t, h and the mesh size, and the duals it returns are `z/F`. Clarabel's own Ruiz
//! equilibration does the rest.
//!
//! **Polishing.** An interior-point answer is only ~1e-9 accurate and never puts a vertex
//! exactly on φ_i, while the certificates of 2e/2f classify vertices by exact comparison.
//! So the three vertex states are read from the interior-point answer — constraint `k` is
//! taken as active when its scaled dual exceeds its scaled slack, `z'_k > s'_k` (strict
//! complementarity makes one of them vanish): both active ⇒ touching, only the first ⇒
//! penetrating, the first inactive ⇒ clear — and the equality-constrained QP of that
//! piece (touching vertices held at φ_i, the L coupling among penetrating vertices) is
//! solved exactly by one sparse Cholesky solve. If its certificate is not at the tolerance
//! the states are corrected from the polished point (a primal-dual active-set update) and
//! the piece is solved again, at most [`POLISH_ROUNDS`] times; the best certificate among
//! the raw and the polished answers is returned, so a wrong guess falls back to the raw
//! interior-point U. The multipliers of a polished answer are the exact
//! `X₁ = D − SU` on M and `X₂ = L̃U₂ − X₁` with `U₂ = (U − φ)⁺`.
//!
//! **Measured** (`cargo test -p memcontact --lib solve::qp -- --include-ignored
//! --nocapture` prints these; scaled KKT certificate `max(2e, 2f)` of the raw
//! interior-point U → of the polished U, interior-point iterations):
//!
//! | case | raw | polished | iterations |
//! | --- | --- | --- | --- |
//! | consistent, h = 1e4(1 + 0.2xy), 12×12, touching vertices | 2.7e-4 | 3.8e-16 | 19 |
//! | consistent, h = 1e6, 16×16 | 8.6e-6 | 3.1e-16 | 18 |
//! | lumped, h = 200, 10×10 | 2.8e-14 | 1.4e-15 | 20 |
//! | rigid, 10×10 | 3.3e-1 | 6.5e-16 | 10 |
//! | consistent, h = 0 / 500 on x < ½ / > ½ (M ⊊ unknowns), 12×12 | 1.2e-14 | 1.2e-15 | 18 |
//! | consistent, 64×64 (m = 3969) | 7.1e-4 | 3.3e-15 | 30 |
//! | consistent, h = 1e6, 64×64 | 7.8e-6 | 1.1e-15 | 23 |
//! | lumped, 64×64 | 4.7e-14 | 3.2e-15 | 19 |
//! | rigid, 64×64 | 9.5e-3 | 1.6e-15 | 19 |
//!
//! The raw certificate is poor wherever a vertex touches (it sits ~1e-10 off φ, and the
//! exact comparisons of 2f then demand `r_i = 0` or `r_i + (Lp)_i = 0` there); one
//! polishing round from the interior-point states reached the exact piece in every case.
//! Clarabel's duals agree with the exact multipliers at the polished U: X₁ to 1e-9 or
//! better relative to max |X|; X₂ to 1e-8 relative to the force scale but only to
//! 1e-7…3e-4 relative to max |X| (h = 1e6 worst), because `V₂ ≥ 0` is degenerate at clear
//! vertices (`V₂ = X₂ = 0`) and the interior point leaves both at `O(√μ)` there.

use super::newton::{truncated_hessian, NewtonStates};
use super::{Method, Multipliers, PhaseTimer, Settings, Solution};
use crate::certificate::Certificate;
use crate::error::{Error, Result};
use crate::model::{FoundationMatrix, Model};
use crate::sparse::{Cholesky, Csr};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// Default limit on interior-point iterations.
pub(crate) const MAX_ITERATIONS: u32 = 200;

/// Most polishing rounds (exact piece solves) after the interior point.
pub const POLISH_ROUNDS: usize = 4;

/// Clarabel's duality-gap tolerances (absolute and relative, on the scaled problem). The
/// multipliers `X₂` of the degenerate constraints `V₂ ≥ 0` at clear vertices (where
/// `V₂ = X₂ = 0`) are only `O(√μ)` accurate, so the gap is driven well below what U needs.
const TOL_GAP: f64 = 1e-14;

/// Clarabel's primal/dual feasibility tolerance. Not tighter: Clarabel stops with
/// "insufficient progress" when a residual bounces above `100 × tol_feas`, which happens
/// (residuals ~1e-11 for one iteration) on meshes of a few thousand unknowns.
const TOL_FEAS: f64 = 1e-11;

/// The reduced tolerances Clarabel accepts as "almost solved" when it stalls.
const REDUCED_TOL: f64 = 1e-8;

/// What the QP solve did, beyond the [`Solution`]: the raw interior-point answer and its
/// certificate next to the polished one.
#[derive(Debug, Clone)]
#[cfg_attr(not(test), allow(dead_code))] // the raw answer is read by the tests of the polish
pub struct QpReport {
    /// The returned solution (the polished U when its certificate is better).
    pub solution: Solution,
    /// Clarabel's final status.
    pub status: SolverStatus,
    /// Clarabel's U (`V₁`).
    pub raw_u: Vec<f64>,
    /// Clarabel's duals `(X₁, X₂)`, over the unknowns (zero off M).
    pub raw_multipliers: Multipliers,
    /// The certificate of the raw U.
    pub raw_certificate: Certificate,
    /// The best certificate reached by polishing (`None` when every polish failed).
    pub polished_certificate: Option<Certificate>,
    /// Polishing rounds run.
    pub polish_rounds: usize,
    /// `true` when the returned U is a polished one.
    pub polished: bool,
}

/// Solves Problem 2c with Clarabel and polishes the answer (see the module docs).
pub fn solve(model: &Model, settings: &Settings) -> Result<Solution> {
    solve_with_report(model, settings).map(|r| r.solution)
}

/// [`solve`], also returning the raw interior-point answer and both certificates.
pub fn solve_with_report(model: &Model, settings: &Settings) -> Result<QpReport> {
    let mut timer = PhaseTimer::default();
    let qp = timer.time("setup", || Qp2c::build(model));
    let max_iter = match settings.max_iterations {
        Some(k) => u32::try_from(k).unwrap_or(u32::MAX).max(1),
        None => MAX_ITERATIONS,
    };
    let mut solver = timer.time("setup", || qp.solver(max_iter))?;
    timer.time("interior point", || solver.solve());
    let sol = &solver.solution;
    let iterations = sol.iterations as usize;
    // At the iteration limit (or stopped for lack of progress with finite residuals) the
    // iterate is still polished and certified: the status of the solve follows from its
    // certificate.
    let stuck = sol.status == SolverStatus::InsufficientProgress
        && sol.r_prim.is_finite()
        && sol.r_dual.is_finite();
    if !stuck
        && !matches!(
            sol.status,
            SolverStatus::Solved
                | SolverStatus::AlmostSolved
                | SolverStatus::MaxIterations
                | SolverStatus::MaxTime
        )
    {
        return Err(Error::Solver {
            solver: "qp".into(),
            message: format!(
                "Clarabel stopped with status {:?} after {iterations} interior-point \
                 iterations (primal residual {:.3e}, dual residual {:.3e})",
                sol.status, sol.r_prim, sol.r_dual
            ),
        });
    }
    let status = sol.status;
    let raw = qp.unscale(model, &sol.x, &sol.z);
    if raw.u.iter().any(|v| !v.is_finite()) {
        return Err(Error::Solver {
            solver: "qp".into(),
            message: format!(
                "Clarabel returned a non-finite solution with status {status:?} after \
                 {iterations} iterations"
            ),
        });
    }
    let guess = qp.guess_states(model, &sol.s, &sol.z);
    drop(solver);

    let raw_certificate = timer.time("certificate", || model.certificate(&raw.u));
    let polish = timer.time("polish", || polish(model, guess, settings.tolerance));
    let polished_certificate = polish.as_ref().map(|p| p.certificate);
    let polish_rounds = polish.as_ref().map_or(POLISH_ROUNDS, |p| p.rounds);
    let (u, certificate, multipliers, polished) = match polish {
        Some(p) if p.certificate.kkt() <= raw_certificate.kkt() => {
            let m = exact_multipliers(model, &p.u);
            (p.u, p.certificate, m, true)
        }
        _ => (
            raw.u.clone(),
            raw_certificate,
            raw.multipliers.clone(),
            false,
        ),
    };
    let solution = Solution {
        energy: model.energy(&u),
        u,
        method: Method::Qp,
        iterations,
        certificate,
        multipliers: Some(multipliers),
        history: vec![],
        phases: timer.into_phases(),
        coarsening: None,
    };
    Ok(QpReport {
        solution,
        status,
        raw_u: raw.u,
        raw_multipliers: raw.multipliers,
        raw_certificate,
        polished_certificate,
        polish_rounds,
        polished,
    })
}

/// The exact multipliers of 2e at U: `X₁ = D − SU` and `X₂ = L̃U₂ − X₁` with
/// `U₂ = (U − φ)⁺`, on M (zero elsewhere; `X₂ = 0` for the rigid obstacle); with a body
/// below, the contact forces split between the bodies
/// ([`crate::certificate::contact_forces`]) and the body below's `X₁_low`, `X₂_low`.
pub fn exact_multipliers(model: &Model, u: &[f64]) -> Multipliers {
    let forces = crate::certificate::contact_forces(model, u);
    let p = model.penetration(u);
    let mut lp = vec![0.0; model.n()];
    model.l.mul_into(&p, &mut lp);
    let mut x1 = vec![0.0; model.n()];
    let mut x2 = vec![0.0; model.n()];
    for i in 0..model.n() {
        if model.can_touch[i] {
            x1[i] = forces.up[i];
            if !model.rigid_at(i) {
                x2[i] = lp[i] - forces.up[i];
            }
        }
    }
    let (mut x1_low, mut x2_low) = (Vec::new(), Vec::new());
    if let Some(low) = &model.lower {
        let q = low.penetration(u);
        let mut lq = vec![0.0; model.n()];
        low.l.mul_into(&q, &mut lq);
        x1_low = vec![0.0; model.n()];
        x2_low = vec![0.0; model.n()];
        for i in 0..model.n() {
            if low.can_touch[i] {
                x1_low[i] = forces.low[i];
                if !low.rigid_at(i) {
                    x2_low[i] = lq[i] - forces.low[i];
                }
            }
        }
    }
    Multipliers {
        x1,
        x2,
        x1_low,
        x2_low,
    }
}

/// One body's constraints in Problem 2c: the unknowns it can touch (its rows of the first
/// block), those among them with an auxiliary penetration variable (elastic), and where
/// those variables start in x.
struct BodyRows {
    /// Unknowns the body can touch, ascending (one first-block row each).
    touch: Vec<usize>,
    /// Row of unknown i in the first block (`usize::MAX` when the body cannot touch it).
    row: Vec<usize>,
    /// Unknowns with a penetration variable (elastic there), ascending.
    elastic: Vec<usize>,
    /// Index among `elastic` of unknown i (`usize::MAX` when rigid or untouchable).
    var: Vec<usize>,
}

impl BodyRows {
    fn new(n: usize, can_touch: &[bool], rigid: impl Fn(usize) -> bool) -> BodyRows {
        let touch: Vec<usize> = (0..n).filter(|&i| can_touch[i]).collect();
        let elastic: Vec<usize> = touch.iter().copied().filter(|&i| !rigid(i)).collect();
        let mut row = vec![usize::MAX; n];
        for (r, &i) in touch.iter().enumerate() {
            row[i] = r;
        }
        let mut var = vec![usize::MAX; n];
        for (r, &i) in elastic.iter().enumerate() {
            var[i] = r;
        }
        BodyRows {
            touch,
            row,
            elastic,
            var,
        }
    }

    /// Rows of the body's constraints: the first block and `−V ≤ 0`.
    fn rows(&self) -> usize {
        self.touch.len() + self.elastic.len()
    }
}

/// The data of Problem 2c in Clarabel's form, scaled (see the module docs).
struct Qp2c {
    /// Unknowns that both rigid bodies hold at one height (φ_low = φ): one equality row
    /// each, first (an interior point needs room between two inequalities).
    pinned: Vec<usize>,
    /// The obstacle's constraints.
    up: BodyRows,
    /// The body below's constraints (docs/theory.md#second-body: variables V₃), when there
    /// is one.
    low: Option<BodyRows>,
    /// Number of unknowns m.
    n: usize,
    /// Length scale ℓ (`x = ℓ y`).
    length: f64,
    /// Force scale F (`z = F z'`).
    force: f64,
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b: Vec<f64>,
}

impl Qp2c {
    /// Builds P (upper triangle of `diag(S, L̃, L̃_low)`), q, A and b from the model's CSR
    /// data (S and L are symmetric, so their CSR rows are their CSC columns). The rows are
    /// the obstacle's `Ṽ₁ − V₂ ≤ φ̃` (no V₂ where it is rigid) and `−V₂ ≤ 0`, then the body
    /// below's `−Ṽ₁ − V₃ ≤ −φ̃_low` and `−V₃ ≤ 0` (docs/theory.md#second-body).
    fn build(model: &Model) -> Qp2c {
        let n = model.n();
        let pinned: Vec<usize> = match &model.lower {
            Some(b) => (0..n)
                .filter(|&i| {
                    model.can_touch[i]
                        && model.rigid_at(i)
                        && b.can_touch[i]
                        && b.rigid_at(i)
                        && b.phi[i] >= model.phi[i]
                })
                .collect(),
            None => Vec::new(),
        };
        let mut is_pinned = vec![false; n];
        for &i in &pinned {
            is_pinned[i] = true;
        }
        let touch_up: Vec<bool> = (0..n)
            .map(|i| model.can_touch[i] && !is_pinned[i])
            .collect();
        let up = BodyRows::new(n, &touch_up, |i| model.rigid_at(i));
        let low = model.lower.as_ref().map(|b| {
            let touch: Vec<bool> = (0..n).map(|i| b.can_touch[i] && !is_pinned[i]).collect();
            BodyRows::new(n, &touch, |i| b.rigid_at(i))
        });
        let force = model.force_scale();
        let sdiag = model.s.diag();
        let max_diag = (0..n)
            .map(|i| sdiag[i] + model.l.diag(i).max(0.0))
            .fold(0.0f64, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut phi_m = up
            .touch
            .iter()
            .fold(0.0f64, |m, &i| m.max(model.phi[i].abs()));
        if let (Some(rows), Some(b)) = (&low, &model.lower) {
            // The body below sets the length only when the obstacle touches nothing: a far
            // body would otherwise set a scale the solution does not have.
            if up.touch.is_empty() {
                phi_m = rows.touch.iter().fold(phi_m, |m, &i| m.max(b.phi[i].abs()));
            }
        }
        let length = phi_m.max(force / max_diag);
        let pscale = length / force;
        let (ku, kl) = (
            up.elastic.len(),
            low.as_ref().map_or(0, |r| r.elastic.len()),
        );

        // P: column j of S's upper triangle = row j of S with columns ≤ j; then the
        // foundation blocks of the elastic variables.
        let nv = n + ku + kl;
        let mut colptr = Vec::with_capacity(nv + 1);
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        colptr.push(0);
        for j in 0..n {
            let (cols, vals) = model.s.row(j);
            for (&i, &v) in cols.iter().zip(vals) {
                if (i as usize) <= j {
                    rowval.push(i as usize);
                    nzval.push(v * pscale);
                }
            }
            colptr.push(rowval.len());
        }
        let mut foundation_block = |l: &FoundationMatrix, rows: &BodyRows, offset: usize| {
            for (r, &j) in rows.elastic.iter().enumerate() {
                match l {
                    FoundationMatrix::Consistent(l) => {
                        let (cols, vals) = l.row(j);
                        for (&i, &v) in cols.iter().zip(vals) {
                            let i = i as usize;
                            if i <= j && rows.var[i] != usize::MAX && v != 0.0 {
                                rowval.push(offset + rows.var[i]);
                                nzval.push(v * pscale);
                            }
                        }
                    }
                    FoundationMatrix::Lumped(d) => {
                        rowval.push(offset + r);
                        nzval.push(d[j] * pscale);
                    }
                    FoundationMatrix::Rigid => {}
                }
                colptr.push(rowval.len());
            }
        };
        foundation_block(&model.l, &up, n);
        if let (Some(rows), Some(b)) = (&low, &model.lower) {
            foundation_block(&b.l, rows, n + ku);
        }
        let p = CscMatrix::new(nv, nv, colptr, rowval, nzval);
        let mut q: Vec<f64> = model.d.iter().map(|d| -d / force).collect();
        q.resize(nv, 0.0);

        // A, by columns. Rows: the pinned unknowns' equalities (k0), the obstacle's first
        // block (|touch|) and its −V₂ ≤ 0 (ku), then the body below's first block and
        // −V₃ ≤ 0.
        let k0 = pinned.len();
        let mut pinned_row = vec![usize::MAX; n];
        for (r, &i) in pinned.iter().enumerate() {
            pinned_row[i] = r;
        }
        let up_rows = k0 + up.rows();
        let rows_total = up_rows + low.as_ref().map_or(0, BodyRows::rows);
        let ut = up.touch.len();
        let mut colptr = Vec::with_capacity(nv + 1);
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        colptr.push(0);
        for (j, &pr) in pinned_row.iter().enumerate() {
            if pr != usize::MAX {
                rowval.push(pr);
                nzval.push(1.0);
            }
            if up.row[j] != usize::MAX {
                rowval.push(k0 + up.row[j]);
                nzval.push(1.0);
            }
            if let Some(rows) = &low {
                if rows.row[j] != usize::MAX {
                    rowval.push(up_rows + rows.row[j]);
                    nzval.push(-1.0);
                }
            }
            colptr.push(rowval.len());
        }
        for (r, &i) in up.elastic.iter().enumerate() {
            rowval.extend([k0 + up.row[i], k0 + ut + r]);
            nzval.extend([-1.0, -1.0]);
            colptr.push(rowval.len());
        }
        if let Some(rows) = &low {
            let lt = rows.touch.len();
            for (r, &i) in rows.elastic.iter().enumerate() {
                rowval.extend([up_rows + rows.row[i], up_rows + lt + r]);
                nzval.extend([-1.0, -1.0]);
                colptr.push(rowval.len());
            }
        }
        let a = CscMatrix::new(rows_total, nv, colptr, rowval, nzval);
        let mut b: Vec<f64> = pinned.iter().map(|&i| model.phi[i] / length).collect();
        b.extend(up.touch.iter().map(|&i| model.phi[i] / length));
        b.resize(up_rows, 0.0);
        if let (Some(rows), Some(body)) = (&low, &model.lower) {
            b.extend(rows.touch.iter().map(|&i| -body.phi[i] / length));
            b.resize(rows_total, 0.0);
        }
        Qp2c {
            pinned,
            up,
            low,
            n,
            length,
            force,
            p,
            q,
            a,
            b,
        }
    }

    /// A Clarabel solver on this data with tight tolerances.
    fn solver(&self, max_iter: u32) -> Result<DefaultSolver<f64>> {
        let err = |message: String| Error::Solver {
            solver: "qp".into(),
            message,
        };
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(max_iter)
            .tol_gap_abs(TOL_GAP)
            .tol_gap_rel(TOL_GAP)
            .tol_feas(TOL_FEAS)
            .tol_ktratio(1e-10)
            .reduced_tol_gap_abs(REDUCED_TOL)
            .reduced_tol_gap_rel(REDUCED_TOL)
            .reduced_tol_feas(REDUCED_TOL)
            .reduced_tol_ktratio(1e-6)
            .presolve_enable(false)
            .build()
            .map_err(|e| err(format!("invalid Clarabel settings: {e}")))?;
        let k0 = self.pinned.len();
        let cones = if k0 == 0 {
            vec![SupportedConeT::NonnegativeConeT(self.b.len())]
        } else {
            vec![
                SupportedConeT::ZeroConeT(k0),
                SupportedConeT::NonnegativeConeT(self.b.len() - k0),
            ]
        };
        DefaultSolver::new(&self.p, &self.q, &self.a, &self.b, &cones, settings)
            .map_err(|e| err(format!("Clarabel rejected Problem 2c: {e}")))
    }

    /// U and the multipliers `(X₁, X₂)` (and the body below's) over the unknowns from
    /// Clarabel's scaled `x`, `z`.
    fn unscale(&self, model: &Model, x: &[f64], z: &[f64]) -> RawAnswer {
        let u: Vec<f64> = x[..self.n].iter().map(|y| y * self.length).collect();
        let duals = |rows: &BodyRows, offset: usize| {
            let mut x1 = vec![0.0; model.n()];
            let mut x2 = vec![0.0; model.n()];
            let t = rows.touch.len();
            for &i in &rows.touch {
                x1[i] = z[offset + rows.row[i]] * self.force;
                if rows.var[i] != usize::MAX {
                    x2[i] = z[offset + t + rows.var[i]] * self.force;
                }
            }
            (x1, x2)
        };
        let k0 = self.pinned.len();
        let (mut x1, x2) = duals(&self.up, k0);
        let (mut x1_low, x2_low) = match &self.low {
            Some(rows) => duals(rows, k0 + self.up.rows()),
            None => (Vec::new(), Vec::new()),
        };
        // A pinned unknown's equality carries the net force: down is the obstacle's, up
        // the body below's.
        for (r, &i) in self.pinned.iter().enumerate() {
            let zf = z[r] * self.force;
            if zf >= 0.0 {
                x1[i] = zf;
            } else {
                x1_low[i] = -zf;
            }
        }
        RawAnswer {
            u,
            multipliers: Multipliers {
                x1,
                x2,
                x1_low,
                x2_low,
            },
        }
    }

    /// The vertex states read from the interior-point answer: a constraint is active when
    /// its (scaled) dual exceeds its (scaled) slack. Both of a body's constraints active:
    /// touching (held); only the first: penetrating; a rigid body's constraint active: held.
    fn guess_states(&self, model: &Model, s: &[f64], z: &[f64]) -> NewtonStates {
        let mut st = NewtonStates::clear(model);
        // `(held, penetrating)` per unknown for one body.
        let read = |rows: &BodyRows, offset: usize, i: usize| -> (bool, bool) {
            if rows.row[i] == usize::MAX {
                return (false, false);
            }
            let k = offset + rows.row[i];
            let first = z[k] > s[k];
            if rows.var[i] == usize::MAX {
                return (first, false);
            }
            let k2 = offset + rows.touch.len() + rows.var[i];
            let second = z[k2] > s[k2];
            (first && second, first && !second)
        };
        let k0 = self.pinned.len();
        for &i in &self.pinned {
            st.truncated[i] = true;
        }
        for i in 0..model.n() {
            if st.truncated[i] {
                continue;
            }
            let (held, pen) = read(&self.up, k0, i);
            st.truncated[i] = held;
            st.penetrating[i] = pen;
            if let Some(rows) = &self.low {
                let (held_low, pen_low) = read(rows, k0 + self.up.rows(), i);
                if held_low && !held {
                    st.truncated[i] = true;
                    st.at_lower[i] = true;
                }
                st.penetrating_low[i] = pen_low && !st.truncated[i];
            }
        }
        st
    }
}

/// Clarabel's answer in the model's units.
struct RawAnswer {
    u: Vec<f64>,
    multipliers: Multipliers,
}

/// The best polished point.
struct Polished {
    u: Vec<f64>,
    certificate: Certificate,
    rounds: usize,
}

/// Solves the equality-constrained QP of the piece of J selected by `st` exactly: the
/// touching vertices held at φ_i, the free ones solving
/// `Σ_j (S_ij + [i,j penetrating] L_ij) U_j = D_i + Σ_{j penetrating} L_ij φ_j` (rows of
/// penetrating vertices; the sum over L only there), i.e. the 2f equations
/// `r_i = 0` (clear) and `r_i + (L(U − φ))_i = 0` (penetrating).
fn solve_piece(
    model: &Model,
    st: &NewtonStates,
    a: &mut Csr,
    chol: &mut Option<Cholesky>,
) -> Result<Vec<f64>> {
    truncated_hessian(model, st, a);
    let factor = match chol {
        Some(c) => {
            c.refactor(a)?;
            c
        }
        None => chol.insert(Cholesky::new(a)?),
    };
    // Where a held vertex sits: on φ, or on φ_low when held by the body below.
    let held_at = |j: usize| {
        if !st.at_lower.is_empty() && st.at_lower[j] {
            model.lower.as_ref().expect("a body below").phi[j]
        } else {
            model.phi[j]
        }
    };
    // φ on the penetrating vertices, for the L φ term (and φ_low for L_low φ_low).
    let phi_p: Vec<f64> = (0..model.n())
        .map(|j| if st.penetrating[j] { model.phi[j] } else { 0.0 })
        .collect();
    let phi_q: Vec<f64> = match &model.lower {
        Some(low) => (0..model.n())
            .map(|j| if st.below(j) { low.phi[j] } else { 0.0 })
            .collect(),
        None => Vec::new(),
    };
    let mut rhs: Vec<f64> = (0..model.n())
        .map(|i| {
            if st.truncated[i] {
                return held_at(i);
            }
            let (cols, vals) = model.s.row(i);
            let held: f64 = cols
                .iter()
                .zip(vals)
                .filter(|(&j, _)| st.truncated[j as usize])
                .map(|(&j, &v)| v * held_at(j as usize))
                .sum();
            let coupling = if st.penetrating[i] {
                model.l.row_dot(i, &phi_p)
            } else {
                0.0
            };
            let coupling_low = match &model.lower {
                Some(low) if st.below(i) => low.l.row_dot(i, &phi_q),
                _ => 0.0,
            };
            model.d[i] - held + coupling + coupling_low
        })
        .collect();
    factor.solve_in_place(&mut rhs);
    if rhs.iter().any(|v| !v.is_finite()) {
        return Err(Error::Solver {
            solver: "qp".into(),
            message: "the polishing solve produced non-finite values".into(),
        });
    }
    // The held vertices exactly on their kink (the Cholesky solve of an identity row is
    // exact, but make it explicit).
    for (i, v) in rhs.iter_mut().enumerate() {
        if st.truncated[i] {
            *v = held_at(i);
        }
    }
    Ok(rhs)
}

/// Corrects the states from a polished point (a primal-dual active-set update): a clear
/// or penetrating vertex that crossed φ becomes touching; a touching vertex whose contact
/// force `X₁ = D − SU` is negative becomes clear, one whose `X₂ = (L(U − φ)_P)_i − X₁` is
/// negative becomes penetrating.
fn update_states(model: &Model, st: &NewtonStates, u: &[f64]) -> NewtonStates {
    if model.is_extended() {
        return update_states_two(model, st, u);
    }
    let n = model.n();
    let r = model.residual(u);
    let p: Vec<f64> = (0..n)
        .map(|j| {
            if st.penetrating[j] {
                u[j] - model.phi[j]
            } else {
                0.0
            }
        })
        .collect();
    let mut next = st.clone();
    for i in 0..n {
        if !model.can_touch[i] {
            continue;
        }
        let gap = u[i] - model.phi[i];
        if st.truncated[i] {
            let x1 = -r[i];
            let x2 = model.l.row_dot(i, &p) - x1;
            if x1 < 0.0 {
                next.truncated[i] = false;
            } else if !model.is_rigid() && x2 < 0.0 {
                next.truncated[i] = false;
                next.penetrating[i] = true;
            }
        } else if (st.penetrating[i] && gap < 0.0) || (!st.penetrating[i] && gap > 0.0) {
            next.truncated[i] = true;
            next.penetrating[i] = false;
        }
    }
    next
}

/// [`update_states`] with a body below and rigid regions (docs/theory.md#extensions): the
/// same primal-dual rules for each body, with the contact force of a held vertex the net
/// force less the other body's elastic force where that one penetrates.
fn update_states_two(model: &Model, st: &NewtonStates, u: &[f64]) -> NewtonStates {
    let n = model.n();
    let r = model.residual(u);
    let restricted = |pen: &dyn Fn(usize) -> bool, w: &dyn Fn(usize) -> f64| -> Vec<f64> {
        (0..n).map(|j| if pen(j) { w(j) } else { 0.0 }).collect()
    };
    let p = restricted(&|j| st.penetrating[j], &|j| u[j] - model.phi[j]);
    let mut lp = vec![0.0; n];
    model.l.mul_into(&p, &mut lp);
    let (low, mut lq) = (model.lower.as_ref(), vec![0.0; n]);
    if let Some(low) = low {
        let q = restricted(&|j| st.below(j), &|j| low.phi[j] - u[j]);
        low.l.mul_into(&q, &mut lq);
    }
    let mut next = st.clone();
    for i in 0..n {
        let up_touch = model.can_touch[i];
        let low_touch = low.is_some_and(|b| b.can_touch[i]);
        if !up_touch && !low_touch {
            continue;
        }
        let at_low = !st.at_lower.is_empty() && st.at_lower[i];
        if st.truncated[i] {
            let released = if at_low {
                let b = low.expect("a body below");
                // Held on the body below: its force pushes up.
                let x = r[i] + if st.penetrating[i] { lp[i] } else { 0.0 };
                if x < 0.0 {
                    Some((false, false))
                } else if !b.rigid_at(i) && lq[i] - x < 0.0 {
                    Some((false, true))
                } else {
                    None
                }
            } else {
                let x = -r[i] + if st.below(i) { lq[i] } else { 0.0 };
                if x < 0.0 {
                    Some((false, false))
                } else if !model.rigid_at(i) && lp[i] - x < 0.0 {
                    Some((true, false))
                } else {
                    None
                }
            };
            if let Some((pen, pen_low)) = released {
                next.truncated[i] = false;
                if !next.at_lower.is_empty() {
                    next.at_lower[i] = false;
                    next.penetrating_low[i] = pen_low;
                }
                next.penetrating[i] = pen;
            }
            continue;
        }
        // Free: a vertex that crossed a kink is held there.
        let gap = u[i] - model.phi[i];
        let crossed_up =
            up_touch && ((st.penetrating[i] && gap < 0.0) || (!st.penetrating[i] && gap > 0.0));
        let crossed_low = low.is_some_and(|b| {
            let g = b.phi[i] - u[i];
            low_touch && ((st.below(i) && g < 0.0) || (!st.below(i) && g > 0.0))
        });
        if crossed_up || crossed_low {
            next.truncated[i] = true;
            next.penetrating[i] = false;
            if !next.at_lower.is_empty() {
                next.penetrating_low[i] = false;
                // Held on the body whose kink was crossed (above when both were).
                next.at_lower[i] = crossed_low && !crossed_up;
            }
        }
    }
    next
}

/// Polishes from the guessed states: up to [`POLISH_ROUNDS`] exact piece solves, keeping
/// the best certificate; `None` when every piece solve failed.
fn polish(model: &Model, guess: NewtonStates, tolerance: f64) -> Option<Polished> {
    let mut a = Csr::zeros(model.s.pattern.clone());
    let mut chol: Option<Cholesky> = None;
    let mut st = guess;
    let mut best: Option<Polished> = None;
    for round in 1..=POLISH_ROUNDS {
        let Ok(u) = solve_piece(model, &st, &mut a, &mut chol) else {
            break;
        };
        let certificate = model.certificate(&u);
        let better = best
            .as_ref()
            .is_none_or(|b| certificate.kkt() < b.certificate.kkt());
        let done = certificate.kkt() <= tolerance;
        let next = if done {
            None
        } else {
            Some(update_states(model, &st, &u))
        };
        if better {
            best = Some(Polished {
                u,
                certificate,
                rounds: round,
            });
        }
        match next {
            Some(next)
                if next.truncated != st.truncated
                    || next.penetrating != st.penetrating
                    || next.penetrating_low != st.penetrating_low
                    || next.at_lower != st.at_lower =>
            {
                st = next
            }
            _ => break,
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Coefficient, FnCoefficient};
    use crate::mesh::test_square as square;
    use crate::model::testing::model;
    use crate::model::Foundation;
    use crate::solve::{active_set, Silent};
    use crate::sparse::norm_inf;

    fn settings() -> Settings {
        Settings {
            method: Method::Qp,
            tolerance: 1e-11,
            ..Settings::default()
        }
    }

    fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
        let num = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        num / norm_inf(b).max(1e-300)
    }

    /// `max |X₁ − X₁*|` and `max |X₂ − X₂*|` relative to `max(|X₁*|, |X₂*|)`, and the
    /// latter relative to the force scale.
    fn dual_errors(model: &Model, raw: &Multipliers, exact: &Multipliers) -> (f64, f64, f64) {
        let err = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        let scale = norm_inf(&exact.x1).max(norm_inf(&exact.x2)).max(1e-300);
        let (e1, e2) = (err(&raw.x1, &exact.x1), err(&raw.x2, &exact.x2));
        (e1 / scale, e2 / scale, e2 / model.force_scale())
    }

    /// Runs the QP and the active-set method and checks everything the brief asks for.
    fn check(name: &str, model: &Model) -> QpReport {
        let rep = solve_with_report(model, &settings()).unwrap();
        let s = &rep.solution;
        let reference =
            active_set::solve(model, &settings(), None, &mut Silent).expect("active set converges");
        let diff = rel_diff(&s.u, &reference.u);
        eprintln!(
            "{name}: m = {}, |M| = {}, status {:?}, {} IPM iterations, raw certificate \
             {:.2e}, polished {:.2e} ({} rounds), |U_qp − U_as|/|U| = {diff:.2e}, \
             phases {:?}",
            model.n(),
            model.can_touch.iter().filter(|&&c| c).count(),
            rep.status,
            s.iterations,
            rep.raw_certificate.kkt(),
            rep.polished_certificate.map_or(f64::NAN, |c| c.kkt()),
            rep.polish_rounds,
            s.phases
        );
        assert!(rep.polished, "{name}: polishing must win");
        assert!(diff < 1e-8, "{name}: qp vs active set {diff:.3e}");
        assert!(s.certificate.kkt() <= 1e-10, "{name}: {:?}", s.certificate);
        assert!(rel_diff(&rep.raw_u, &reference.u) < 1e-6, "{name}: raw U");
        // Clarabel's own duals (the multipliers of 2d/2e) against the exact ones at the
        // polished U: an independent check of 2e. X₁ is well determined; X₂ vanishes
        // together with V₂ at the clear vertices (a degenerate constraint), where the
        // interior point leaves it at O(√μ): it is checked against the certificates' force
        // scale, and loosely against the size of the multipliers.
        let exact = exact_multipliers(model, &s.u);
        let (d1, d2, d2f) = dual_errors(model, &rep.raw_multipliers, &exact);
        eprintln!(
            "{name}: raw duals vs exact: X₁ {d1:.2e}, X₂ {d2:.2e} (relative to max |X|), \
             X₂ {d2f:.2e} (relative to the force scale)"
        );
        assert!(d1 < 1e-6, "{name}: X₁ {d1:.3e}");
        assert!(d2f < 1e-6 && d2 < 1e-3, "{name}: X₂ {d2:.3e} {d2f:.3e}");
        let m = s.multipliers.as_ref().expect("the QP returns multipliers");
        let small = 1e-12 * model.force_scale();
        for (i, &c) in model.can_touch.iter().enumerate() {
            assert!(m.x1[i] >= -small && m.x2[i] >= -small, "{name}: vertex {i}");
            assert!(rep.raw_multipliers.x1[i] >= -small && rep.raw_multipliers.x2[i] >= -small);
            if !c {
                assert!(m.x1[i] == 0.0 && m.x2[i] == 0.0);
            }
        }
        // 2e's first row: S U − D + X̂₁ = 0 holds exactly for the returned multipliers.
        let r = model.residual(&s.u);
        let eq = r
            .iter()
            .zip(&m.x1)
            .fold(0.0f64, |a, (r, x)| a.max((r + x).abs()));
        assert!(eq <= 1e-11 * model.force_scale(), "{name}: {eq:.3e}");
        rep
    }

    #[test]
    fn consistent_with_varying_h_and_a_touching_vertex() {
        let m = square(12);
        let h = FnCoefficient(|p: [f64; 2]| 1e4 * (1.0 + 0.2 * p[0] * p[1]));
        let model = model(&m, Some(&h), Foundation::Consistent);
        let rep = check("consistent", &model);
        let states = model.states(&rep.solution.u);
        assert!(states.contains(&0) && states.contains(&1) && states.contains(&-1));
    }

    #[test]
    fn consistent_with_large_h() {
        let m = square(16);
        let model = model(&m, Some(&1e6), Foundation::Consistent);
        let rep = check("consistent h = 1e6", &model);
        assert!(model.states(&rep.solution.u).contains(&1));
    }

    #[test]
    fn lumped() {
        let m = square(10);
        let model = model(&m, Some(&200.0), Foundation::Lumped);
        let rep = check("lumped", &model);
        assert!(model.states(&rep.solution.u).contains(&1));
    }

    #[test]
    fn rigid() {
        let m = square(10);
        let model = model(&m, None, Foundation::Consistent);
        let rep = check("rigid", &model);
        let u = &rep.solution.u;
        assert!(u.iter().zip(&model.phi).all(|(u, f)| u <= f));
        assert!(model.states(u).contains(&0));
        assert!(rep.raw_multipliers.x2.iter().all(|&x| x == 0.0));
    }

    #[test]
    fn m_is_a_strict_subset() {
        let m = square(12);
        let h = FnCoefficient(|p: [f64; 2]| if p[0] < 0.5 { 0.0 } else { 500.0 });
        let model = model(&m, Some(&h as &dyn Coefficient), Foundation::Consistent);
        let k = model.can_touch.iter().filter(|&&c| c).count();
        assert!(k > 0 && k < model.n());
        let rep = check("strict subset", &model);
        assert!(model.states(&rep.solution.u).contains(&1));
    }

    #[test]
    fn polishing_corrects_a_wrong_guess() {
        // Start the polish from "everything clear" (the free membrane): the primal-dual
        // updates move the crossing vertices onto φ and on from there.
        let m = square(12);
        let h = FnCoefficient(|p: [f64; 2]| 1e4 * (1.0 + 0.2 * p[0] * p[1]));
        for model in [
            model(&m, Some(&h), Foundation::Consistent),
            model(&m, Some(&200.0), Foundation::Lumped),
            model(&m, None, Foundation::Consistent),
        ] {
            let clear = NewtonStates::clear(&model);
            let p = polish(&model, clear, 1e-11).expect("the piece solves succeed");
            let reference = active_set::solve(&model, &settings(), None, &mut Silent).unwrap();
            eprintln!(
                "wrong guess: {} rounds, certificate {:.2e}, |U − U_as|/|U| {:.2e}",
                p.rounds,
                p.certificate.kkt(),
                rel_diff(&p.u, &reference.u)
            );
            assert!(p.rounds > 1);
            assert!(p.certificate.kkt().is_finite());
            // The best polished point is at least as good as the first (free membrane) one.
            let free = model.certificate(&solve_piece_for_test(&model));
            assert!(p.certificate.kkt() <= free.kkt());
        }
    }

    /// The free membrane S U = D, through the piece solver.
    fn solve_piece_for_test(model: &Model) -> Vec<f64> {
        let st = NewtonStates::clear(model);
        let mut a = Csr::zeros(model.s.pattern.clone());
        solve_piece(model, &st, &mut a, &mut None).unwrap()
    }

    #[test]
    fn no_vertex_can_touch() {
        // h ≡ 0: M is empty, Problem 2c has no constraint and is the linear system S U = D.
        let m = square(8);
        let model = model(&m, Some(&0.0), Foundation::Consistent);
        assert!(model.is_linear());
        let s = solve(&model, &settings()).unwrap();
        let l = crate::solve::linear::solve(&model, &settings()).unwrap();
        assert!(rel_diff(&s.u, &l.u) < 1e-12, "{}", rel_diff(&s.u, &l.u));
        assert!(s.certificate.kkt() <= 1e-12);
    }

    #[test]
    fn the_iteration_limit_is_a_status_with_the_iterate() {
        let m = square(8);
        let model = model(&m, Some(&1e3), Foundation::Consistent);
        let mut s = settings();
        s.max_iterations = Some(1);
        let a = crate::solve::attempt(&model, None, &s, &mut crate::solve::Silent).unwrap();
        assert_eq!(a.status, crate::solve::Status::IterationLimit);
        assert_eq!(a.solution.iterations, 1);
        assert_eq!(a.solution.u.len(), model.n());
        assert_eq!(a.solution.certificate, model.certificate(&a.solution.u));
        assert!(a.solution.certificate.kkt() > s.tolerance);
    }

    /// Timings and certificates on a 64×64 mesh (`--ignored`; prints the numbers quoted
    /// in the module docs).
    #[test]
    #[ignore]
    fn report_64() {
        let m = square(64);
        let h = FnCoefficient(|p: [f64; 2]| 1e4 * (1.0 + 0.2 * p[0] * p[1]));
        let cases: Vec<(&str, Model)> = vec![
            ("consistent 64", model(&m, Some(&h), Foundation::Consistent)),
            (
                "consistent h=1e6 64",
                model(&m, Some(&1e6), Foundation::Consistent),
            ),
            ("lumped 64", model(&m, Some(&200.0), Foundation::Lumped)),
            ("rigid 64", model(&m, None, Foundation::Consistent)),
        ];
        for (name, model) in &cases {
            let t0 = std::time::Instant::now();
            let reference = active_set::solve(model, &settings(), None, &mut Silent).unwrap();
            let t_as = t0.elapsed().as_secs_f64();
            let rep = solve_with_report(model, &settings()).unwrap();
            let s = &rep.solution;
            let exact = exact_multipliers(model, &s.u);
            let (d1, d2, d2f) = dual_errors(model, &rep.raw_multipliers, &exact);
            eprintln!(
                "{name}: m = {}, status {:?}, {} IPM iterations, raw {:.2e}, polished {:.2e} \
                 ({} rounds), vs active set {:.2e} (active set {:.3} s, {} its), duals X₁ \
                 {d1:.2e} X₂ {d2:.2e} ({d2f:.2e} of F), phases {:?}",
                model.n(),
                rep.status,
                s.iterations,
                rep.raw_certificate.kkt(),
                rep.polished_certificate.map_or(f64::NAN, |c| c.kkt()),
                rep.polish_rounds,
                rel_diff(&s.u, &reference.u),
                t_as,
                reference.iterations,
                s.phases
            );
            assert!(s.certificate.kkt() <= 1e-10);
        }
    }
}
