//! Linear geometric multigrid on a [`crate::mesh::refine::Hierarchy`]: the V-cycle that computes the truncated
//! Newton correction of TNNMG, and, on the untruncated stiffness matrix S, the linear
//! Poisson solve used as the benchmark's yardstick.
//!
//! * Levels: the unknowns (interior vertices) of every mesh of the hierarchy that has
//!   any; prolongations [`super::transfer::Transfer`] between consecutive ones.
//! * Operators: the finest one is given by the caller (S, or the truncated Hessian of
//!   TNNMG, whose truncated rows and columns are zero, assembled or read from S with a
//!   diagonal shift: [`super::operator`]); the coarser ones are the Galerkin
//!   products `A_{k-1} = Pₖᵀ A_k Pₖ` on patterns computed once ([`Levels`]), refilled
//!   value by value, and only in the rows that changed when the caller says which.
//! * Smoother: Gauss-Seidel, forward before and backward after the coarse correction (the
//!   V-cycle is then a symmetric operator). Rows whose diagonal is zero (truncated
//!   vertices, or coarse vertices all of whose children are truncated) are left alone: in
//!   a positive semidefinite matrix they are zero rows, decoupled from the rest. A sweep
//!   from zero (every cycle of the flexible CG, every coarse level) and the residual after
//!   it are one pass over the matrix ([`gauss_seidel_from_zero`]).
//! * Coarsest level: sparse Cholesky ([`Cholesky`], symbolic analysis once), zero rows
//!   replaced by the identity. Below a large coarsest mesh the hierarchy ends with
//!   aggregation levels ([`Levels::with_aggregation_below`]): the V-cycle's correction on
//!   the coarsest mesh is then the K-cycle's on them.

use super::levels::Levels;
use super::operator::{apply, values_into, zero_held, TopOperator};
use super::smoother::*;

use crate::error::{Error, Result};
use crate::sparse::{filled, par_rows, zeroed, Cholesky, Csr};
use std::sync::Arc;

/// Gauss-Seidel smoothing steps and operators of a linear multigrid on levels `0..=top` of
/// a [`Levels`], with the work arrays of a V-cycle (allocated once).
pub struct Multigrid<'a> {
    levels: &'a Levels,
    top: usize,
    /// Operators of levels `0..top` (the finest is the caller's).
    coarse: Vec<Csr>,
    /// `1 / A_ii`, or 0 on zero rows, for levels `0..top` (and for level 0 when it is the
    /// top); the top level's sweeps divide by the diagonal they read ([`InvDiag`]).
    inv_diag: Vec<Vec<f64>>,
    /// Iterate, right-hand side and residual per level `0..top`, and the residual on top.
    /// A level's residual vector is also the block smoother's copy of the iterate
    /// ([`gauss_seidel`]) whenever it is free: before the residual is computed, and after
    /// it was restricted.
    x: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    r: Vec<Vec<f64>>,
    dirty: Vec<Vec<bool>>,
    /// Level 0's operator with zero rows replaced by the identity, and its factor.
    coarsest: Csr,
    chol: Option<Cholesky>,
    /// Pre- and post-smoothing steps per level.
    pub smoothing: (usize, usize),
    /// Work vectors of the K-cycle's Krylov steps per level (`[v1, w1, w2]`; empty on
    /// geometric hierarchies, which use the V-cycle).
    krylov: Vec<[Vec<f64>; 3]>,
    /// Ends [`Multigrid::fcg`] early when cancelled (the caller then stops).
    pub cancel: crate::parallel::Cancel,
}

impl<'a> Multigrid<'a> {
    /// A multigrid on levels `0..=top` (`top` is the level of the caller's operator).
    pub fn new(levels: &'a Levels, top: usize) -> Multigrid<'a> {
        let coarse: Vec<Csr> = (0..top)
            .map(|k| Csr::zeros(levels.patterns[k].clone()))
            .collect();
        let zeros = |k: usize| zeroed(levels.n(k));
        Multigrid {
            levels,
            top,
            coarse,
            inv_diag: (0..top.max(1)).map(zeros).collect(),
            x: (0..top).map(zeros).collect(),
            b: (0..top).map(zeros).collect(),
            r: (0..=top).map(zeros).collect(),
            dirty: (0..top).map(|k| filled(levels.n(k), true)).collect(),
            coarsest: Csr::zeros(levels.patterns[0].clone()),
            chol: None,
            smoothing: (1, 1),
            krylov: (0..top)
                .map(|k| {
                    if k > 0 && k <= levels.aggregated {
                        [zeros(k), zeros(k), zeros(k)]
                    } else {
                        Default::default()
                    }
                })
                .collect(),
            cancel: crate::parallel::Cancel::default(),
        }
    }

    /// Flexible conjugate gradients (FCG(1): each direction A-orthogonal to the previous
    /// one, so that a preconditioner that varies from step to step is allowed) for
    /// `A x = b` on the top level from `x = 0`, preconditioned by one [`Multigrid::cycle`]
    /// per step, until `‖b − A x‖∞ ≤ target` or `max_steps` steps; rows flagged in `held`
    /// (zero rows of A) stay 0. `b` is overwritten by the final residual `b − A x` (it is
    /// the iteration's residual vector: no copy of it is kept). Returns the steps done.
    /// Every step lowers the quadratic `½xᵀAx − bᵀx`, so `x` is a descent direction of it
    /// from the first step on.
    #[allow(clippy::too_many_arguments)]
    pub fn fcg<A: TopOperator>(
        &mut self,
        a: &A,
        x: &mut [f64],
        b: &mut [f64],
        target: f64,
        max_steps: usize,
        held: &[bool],
        work: &mut FcgWork,
    ) -> usize {
        let n = x.len();
        work.resize(n);
        let FcgWork { z, p, ap, az } = work;
        let r = b;
        par_rows(x, |_, v| *v = 0.0);
        let mut pap_prev = 0.0;
        let mut steps = 0;
        // z with its held and non-finite entries taken as 0.
        let masked = |z: &[f64], i: usize| {
            if held[i] || !z[i].is_finite() {
                0.0
            } else {
                z[i]
            }
        };
        while steps < max_steps && !self.cancel.is_cancelled() {
            let known = self.cycle_from_zero_with_product(a, z, r, Some(az));
            let (z, az): (&[f64], &[f64]) = (z, az);
            // zᵀ A p of the previous direction, and whether z is finite: the held rows'
            // entries leave A z as it is (their rows and columns of A are zero), a
            // non-finite one does not, and A p is then formed by a product.
            let [zap, bad] = sum_block_parts(per_block(p, ap, |lo, _, apc| {
                let mut s = [0.0, 0.0];
                for (j, apj) in apc.iter().enumerate() {
                    s[0] += masked(z, lo + j) * apj;
                    s[1] += (!z[lo + j].is_finite()) as u8 as f64;
                }
                s
            }));
            let beta = if steps == 0 { 0.0 } else { -zap / pap_prev };
            // p = z + β p with β making p A-orthogonal to the previous direction; A p is
            // A z + β A p when the cycle gave A z, else one product. Then pᵀ A p and pᵀ r.
            let first = steps == 0;
            let [pap, pr] = if known && bad == 0.0 {
                sum_block_parts(per_block(p, ap, |lo, pc, apc| {
                    let mut s = [0.0, 0.0];
                    for (j, (pj, apj)) in pc.iter_mut().zip(apc.iter_mut()).enumerate() {
                        let i = lo + j;
                        if first {
                            (*pj, *apj) = (masked(z, i), az[i]);
                        } else {
                            *pj = masked(z, i) + beta * *pj;
                            *apj = az[i] + beta * *apj;
                        }
                        s[0] += *pj * *apj;
                        s[1] += *pj * r[i];
                    }
                    s
                }))
            } else {
                par_rows(p, |i, v| {
                    *v = if first {
                        masked(z, i)
                    } else {
                        masked(z, i) + beta * *v
                    }
                });
                apply(a, p, ap);
                sum_block_parts(per_block(p, ap, |lo, pc, apc| {
                    let mut s = [0.0, 0.0];
                    for (j, (pj, apj)) in pc.iter().zip(apc.iter()).enumerate() {
                        s[0] += pj * apj;
                        s[1] += pj * r[lo + j];
                    }
                    s
                }))
            };
            if !(pap > 0.0 && pap.is_finite()) {
                break;
            }
            let alpha = pr / pap;
            let (p, ap): (&[f64], &[f64]) = (p, ap);
            let norm = per_block(x, r, |lo, xc, rc| {
                let mut m: f64 = 0.0;
                for (j, (xj, rj)) in xc.iter_mut().zip(rc.iter_mut()).enumerate() {
                    *xj += alpha * p[lo + j];
                    *rj -= alpha * ap[lo + j];
                    m = m.max(rj.abs());
                }
                [m]
            })
            .iter()
            .fold(0.0, |m: f64, v| m.max(v[0]));
            pap_prev = pap;
            steps += 1;
            if norm <= target {
                break;
            }
        }
        steps
    }

    /// One cycle for `A x = b` on the top level: the V-cycle on mesh levels (with the
    /// K-cycle's correction on aggregation levels below a large coarsest mesh), the K-cycle
    /// on an algebraic hierarchy (see [`Multigrid::v_cycle`], [`Multigrid::k_cycle`]).
    pub fn cycle<A: TopOperator>(&mut self, fine: &A, x: &mut [f64], b: &[f64]) {
        if self.k_cycle_on_top() {
            self.k_cycle(fine, x, b)
        } else {
            self.v_cycle(fine, x, b)
        }
    }

    /// [`Multigrid::cycle`] from `x = 0`, whatever `x` holds on entry (the preconditioner
    /// of [`Multigrid::fcg`]: the first smoothing sweep and the residual after it are then
    /// one pass over A), and `A x` after it into `product` when the last
    /// smoothing sweep can form it on the way ([`gauss_seidel_back_with_product`]): returns
    /// whether it did.
    pub fn cycle_from_zero_with_product<A: TopOperator>(
        &mut self,
        fine: &A,
        x: &mut [f64],
        b: &[f64],
        product: Option<&mut [f64]>,
    ) -> bool {
        if self.top == 0 {
            x.iter_mut().for_each(|v| *v = 0.0);
            self.cycle(fine, x, b);
            return false;
        }
        self.presmooth_top(fine, x, b, true);
        let krylov = self.k_cycle_on_top();
        self.cycle_below(fine, x, b, product, krylov)
    }

    /// Whether the top level and all below it are aggregation levels (an algebraic
    /// hierarchy, or nested iteration on the aggregation levels below a large coarsest
    /// mesh): the K-cycle's, not the V-cycle's, descent from the top.
    fn k_cycle_on_top(&self) -> bool {
        self.top <= self.levels.aggregated
    }

    /// Whether `fine`'s pattern is the top level's own, so that the fused kernels may use
    /// the top level's seam rows.
    fn fused_on_top<A: TopOperator>(&self, fine: &A) -> bool {
        Arc::ptr_eq(&fine.matrix().pattern, &self.levels.patterns[self.top])
    }

    /// Where the top level's sweeps find `1 / A_ii`: divided on the way, with the
    /// diagonal's offsets of the top level's pattern when the operator's pattern is it
    /// (`fused`); stored only when the top is the coarsest level.
    fn top_inv<'b>(
        levels: &'b Levels,
        inv_diag: &'b [Vec<f64>],
        top: usize,
        fused: bool,
    ) -> InvDiag<'b> {
        if top == 0 {
            InvDiag::Stored(&inv_diag[0])
        } else if fused {
            InvDiag::Rows(&levels.sweep_rows[top])
        } else {
            InvDiag::Search
        }
    }

    /// Pre-smoothing on the top level and its residual into `r[top]`; from `x = 0` when
    /// `from_zero` (then fused into one pass when A's pattern is the top level's own).
    fn presmooth_top<A: TopOperator>(
        &mut self,
        fine: &A,
        x: &mut [f64],
        b: &[f64],
        from_zero: bool,
    ) {
        let top = self.top;
        let nu1 = self.smoothing.0;
        if from_zero && nu1 == 1 && self.fused_on_top(fine) {
            let inv = Self::top_inv(self.levels, &self.inv_diag, top, self.fused_on_top(fine));
            let rows = &self.levels.sweep_rows[top];
            gauss_seidel_from_zero(fine, inv, x, b, &mut self.r[top], rows);
            return;
        }
        if from_zero {
            x.iter_mut().for_each(|v| *v = 0.0);
        } else {
            zero_held(fine, x);
        }
        for _ in 0..nu1 {
            let inv = Self::top_inv(self.levels, &self.inv_diag, top, self.fused_on_top(fine));
            gauss_seidel(fine, inv, x, b, &mut self.r[top], false);
        }
        residual(fine, x, b, &mut self.r[top]);
    }

    /// One K-cycle (Y. Notay, P. S. Vassilevski, "Recursive Krylov-based multigrid
    /// cycles", Numer. Linear Algebra Appl. 15 (2008)) for `A x = b` on the top level,
    /// improving `x` in place: Gauss-Seidel before and after the coarse correction, as in
    /// the V-cycle, but the correction on every coarse level but the coarsest is computed
    /// by two steps of flexible conjugate gradients preconditioned by the cycle on the
    /// next level (one step when it already reduces the residual by 4). With the
    /// piecewise-constant prolongation of aggregation, the V-cycle's convergence degrades
    /// with every level; the K-cycle's does not. Zero rows of A leave their x unchanged.
    pub fn k_cycle<A: TopOperator>(&mut self, fine: &A, x: &mut [f64], b: &[f64]) {
        let top = self.top;
        if top == 0 {
            return self.v_cycle(fine, x, b);
        }
        self.presmooth_top(fine, x, b, false);
        self.cycle_below(fine, x, b, None, true);
    }

    /// On the top level: the correction of the level below prolongated into `x` (zero on
    /// held unknowns), then `ν₂` Gauss-Seidel sweeps in reverse order; with a `product`,
    /// `A x` into it when a single sweep can form it (returns whether it did).
    fn prolongate_and_postsmooth_top<A: TopOperator>(
        &mut self,
        fine: &A,
        x: &mut [f64],
        b: &[f64],
        product: Option<&mut [f64]>,
    ) -> bool {
        let top = self.top;
        self.levels.transfers[top - 1].prolongate_add(&self.x[top - 1], x);
        zero_held(fine, x);
        let nu2 = self.smoothing.1;
        if let Some(y) = product.filter(|_| nu2 == 1 && self.fused_on_top(fine)) {
            let inv = Self::top_inv(self.levels, &self.inv_diag, top, self.fused_on_top(fine));
            let rows = &self.levels.sweep_rows[top];
            gauss_seidel_back_with_product(fine, inv, x, b, &mut self.r[top], y, rows);
            return true;
        }
        for _ in 0..nu2 {
            let inv = Self::top_inv(self.levels, &self.inv_diag, top, self.fused_on_top(fine));
            gauss_seidel(fine, inv, x, b, &mut self.r[top], true);
        }
        false
    }

    /// `x[k] ≈ A_k⁻¹ b[k]` for a coarse level `k < top`: the direct solve on level 0, else
    /// two flexible CG steps preconditioned by [`Multigrid::coarse_k_cycle`] (`b[k]` is
    /// overwritten by the residual after the first step). Each cycle's last smoothing sweep
    /// forms the product `A_k v` of its result on the way, and the step's reductions share
    /// one pass over the vectors.
    fn krylov_correction(&mut self, k: usize) {
        if k == 0 {
            self.solve_coarsest_in_place(Some(0));
            return;
        }
        /// Accept one step when it reduces the residual's norm by this factor.
        const ONE_STEP: f64 = 0.25;
        let [mut v1, mut w1, mut w2] = std::mem::take(&mut self.krylov[k]);
        // v₁ = the cycle's result, w₁ = A v₁; ρ₁ = v₁ᵀw₁, α₁ = v₁ᵀr, ‖r‖².
        self.coarse_k_cycle(k, &mut w1);
        std::mem::swap(&mut self.x[k], &mut v1);
        let [rho1, alpha1, rr] = {
            let (v1, w1, r) = (&v1, &w1, &self.b[k]);
            sums(v1.len(), |i| [v1[i] * w1[i], v1[i] * r[i], r[i] * r[i]])
        };
        if !(rho1 > 0.0 && rho1.is_finite()) {
            par_rows(&mut self.x[k], |_, v| *v = 0.0);
        } else {
            // r̃ = r − (α₁/ρ₁) w₁ in b[k] (the right-hand side of the second cycle).
            let c1 = alpha1 / rho1;
            let [rt] = sum_block_parts(per_block(&mut self.b[k], &mut w1, |_, bc, wc| {
                let mut m = 0.0;
                for (b, w) in bc.iter_mut().zip(wc.iter()) {
                    *b -= c1 * w;
                    m += *b * *b;
                }
                [m]
            }));
            if rt.sqrt() <= ONE_STEP * rr.sqrt() {
                let v1: &[f64] = &v1;
                par_rows(&mut self.x[k], |i, x| *x = c1 * v1[i]);
            } else {
                // v₂ = the second cycle's result (in x[k]), w₂ = A v₂; v₂ is made
                // A-orthogonal to v₁ and the pair's minimiser of the quadratic is taken.
                self.coarse_k_cycle(k, &mut w2);
                let [gamma, beta, alpha2] = {
                    let (v2, w1, w2, r) = (&self.x[k], &w1, &w2, &self.b[k]);
                    sums(v2.len(), |i| [v2[i] * w1[i], v2[i] * w2[i], v2[i] * r[i]])
                };
                let rho2 = beta - gamma * gamma / rho1;
                let (ca, cb) = if rho2 > 0.0 && rho2.is_finite() {
                    (c1 - gamma * alpha2 / (rho1 * rho2), alpha2 / rho2)
                } else {
                    (c1, 0.0)
                };
                let v1: &[f64] = &v1;
                par_rows(&mut self.x[k], |i, x| *x = ca * v1[i] + cb * *x);
            }
        }
        self.krylov[k] = [v1, w1, w2];
    }

    /// On coarse level `k ≥ 1`: `x[k] = 0`, `ν₁` Gauss-Seidel sweeps on `A_k x[k] = b[k]`,
    /// and the residual restricted into `b[k − 1]`.
    fn presmooth_and_restrict(&mut self, k: usize) {
        let (a, inv) = (&self.coarse[k], InvDiag::Stored(&self.inv_diag[k]));
        let (xk, bk) = (&mut self.x[k], &self.b[k]);
        if self.smoothing.0 == 1 {
            gauss_seidel_from_zero(a, inv, xk, bk, &mut self.r[k], &self.levels.sweep_rows[k]);
        } else {
            xk.iter_mut().for_each(|v| *v = 0.0);
            for _ in 0..self.smoothing.0 {
                gauss_seidel(a, inv, xk, bk, &mut self.r[k], false);
            }
            residual(a, xk, bk, &mut self.r[k]);
        }
        let (bl, _) = self.b.split_at_mut(k);
        self.levels.transfers[k - 1].restrict(&self.r[k], &mut bl[k - 1]);
    }

    /// On coarse level `k ≥ 1`: the correction of level `k − 1` prolongated into `x[k]`,
    /// then `ν₂` Gauss-Seidel sweeps (in reverse order) on `A_k x[k] = b[k]`; with a
    /// `product`, `A_k x[k]` into it (formed by the sweep when it is a single one).
    fn prolongate_and_postsmooth(&mut self, k: usize, mut product: Option<&mut [f64]>) {
        let (xl, xu) = self.x.split_at_mut(k);
        self.levels.transfers[k - 1].prolongate_add(&xl[k - 1], &mut xu[0]);
        let (a, inv, b, r) = (
            &self.coarse[k],
            InvDiag::Stored(&self.inv_diag[k]),
            &self.b[k],
            &mut self.r[k],
        );
        if let Some(y) = product.as_deref_mut().filter(|_| self.smoothing.1 == 1) {
            let rows = &self.levels.sweep_rows[k];
            gauss_seidel_back_with_product(a, inv, &mut xu[0], b, r, y, rows);
            return;
        }
        for _ in 0..self.smoothing.1 {
            gauss_seidel(a, inv, &mut xu[0], b, r, true);
        }
        if let Some(y) = product {
            a.mul_into(&xu[0], y);
        }
    }

    /// One K-cycle on coarse level `k ≥ 1` for `A_k x[k] = b[k]`, from `x[k] = 0`, with
    /// `A_k x[k]` after it into `product`.
    fn coarse_k_cycle(&mut self, k: usize, product: &mut [f64]) {
        self.presmooth_and_restrict(k);
        self.krylov_correction(k - 1);
        self.prolongate_and_postsmooth(k, Some(product));
    }

    /// Recomputes the coarse operators from the finest one, `fine` (on the pattern of the
    /// top level). With `dirty_fine`, only the coarse rows that depend on the flagged fine
    /// rows are recomputed (the caller guarantees the other fine rows did not change since
    /// the last update).
    pub fn update<A: TopOperator>(&mut self, fine: &A, dirty_fine: Option<&[bool]>) -> Result<()> {
        let top = self.top;
        if fine.matrix().n() != self.levels.n(top) {
            return Err(Error::Solver {
                solver: "multigrid".into(),
                message: format!(
                    "operator of {} rows for a level of {} unknowns",
                    fine.matrix().n(),
                    self.levels.n(top)
                ),
            });
        }
        if top == 0 {
            fill_inv_diag(fine, &mut self.inv_diag[0]);
        }
        let first = self.chol.is_none();
        for k in (0..top).rev() {
            let t = &self.levels.transfers[k];
            let (lower, upper) = self.coarse.split_at_mut(k + 1);
            let (dl, du) = self.dirty.split_at_mut(k + 1);
            let dirty_here = &mut dl[k];
            let use_dirty = match (k + 1 == top, dirty_fine) {
                (_, _) if first => false,
                (true, Some(d)) => {
                    t.coarse_dirty(d, dirty_here);
                    true
                }
                (false, Some(_)) => {
                    t.coarse_dirty(&du[0], dirty_here);
                    true
                }
                (_, None) => false,
            };
            if !use_dirty {
                dirty_here.iter_mut().for_each(|d| *d = true);
            }
            if k + 1 == top {
                t.galerkin_values(fine, &mut lower[k], Some(dirty_here));
            } else {
                t.galerkin_values(&upper[0], &mut lower[k], Some(dirty_here));
            }
            fill_inv_diag(&lower[k], &mut self.inv_diag[k]);
        }
        // The coarsest level: refactor when anything changed there.
        let changed = first || top == 0 || self.dirty[0].iter().any(|&d| d);
        if changed {
            if top == 0 {
                values_into(fine, &mut self.coarsest.val);
            } else {
                self.coarsest.val.copy_from_slice(&self.coarse[0].val);
            }
            let pat = self.coarsest.pattern.clone();
            for i in 0..pat.n() {
                if self.inv_diag[0][i] == 0.0 {
                    for k in pat.ptr(i)..pat.ptr(i + 1) {
                        self.coarsest.val[k] = if pat.col[k] as usize == i { 1.0 } else { 0.0 };
                    }
                }
            }
            match &mut self.chol {
                Some(c) => c.refactor(&self.coarsest)?,
                None => self.chol = Some(Cholesky::new(&self.coarsest)?),
            }
        }
        Ok(())
    }

    /// One V-cycle for `A x = b` on the top level (`fine` = its operator, as given to the
    /// last [`Multigrid::update`]), improving `x` in place. Zero rows of A leave their x
    /// unchanged (the caller may zero them afterwards).
    pub fn v_cycle<A: TopOperator>(&mut self, fine: &A, x: &mut [f64], b: &[f64]) {
        let top = self.top;
        if top == 0 {
            // One level: the direct solve, on the residual equation.
            zero_held(fine, x);
            let r = &mut self.r[0];
            residual(fine, x, b, r);
            self.solve_coarsest_in_place(None);
            let r = &self.r[0];
            for (i, xi) in x.iter_mut().enumerate() {
                if self.inv_diag[0][i] != 0.0 {
                    *xi += r[i];
                }
            }
            return;
        }
        // Down: smooth, restrict the residual.
        self.presmooth_top(fine, x, b, false);
        self.cycle_below(fine, x, b, None, false);
    }

    /// The cycle after the top level's pre-smoothing (its residual is in `r[top]`): the
    /// residual restricted, the correction of the levels below (the K-cycle's Krylov
    /// correction when `krylov`, else the V-cycle's descent and ascent), the top level's
    /// post-smoothing; with a `product`, see [`Multigrid::prolongate_and_postsmooth_top`].
    fn cycle_below<A: TopOperator>(
        &mut self,
        fine: &A,
        x: &mut [f64],
        b: &[f64],
        product: Option<&mut [f64]>,
        krylov: bool,
    ) -> bool {
        let top = self.top;
        self.levels.transfers[top - 1].restrict(&self.r[top], &mut self.b[top - 1]);
        if krylov {
            self.krylov_correction(top - 1);
        } else {
            // Down to the coarsest mesh level, whose correction is the direct solve, or
            // the K-cycle's on the aggregation levels below it.
            let base = self.levels.aggregated;
            for k in (base + 1..top).rev() {
                self.presmooth_and_restrict(k);
            }
            if base == 0 {
                self.solve_coarsest_in_place(Some(0));
            } else {
                self.krylov_correction(base);
            }
            // Up: prolongate the correction, smooth.
            for k in base + 1..top {
                self.prolongate_and_postsmooth(k, None);
            }
        }
        self.prolongate_and_postsmooth_top(fine, x, b, product)
    }

    /// Level 0: `x₀ = A₀⁻¹ b₀` (into `self.x[0]` when `into = Some(0)`, else in place in
    /// `self.r[0]`), zero on the zero rows.
    fn solve_coarsest_in_place(&mut self, into: Option<usize>) {
        let inv = &self.inv_diag[0];
        let target: &mut Vec<f64> = match into {
            Some(_) => {
                self.x[0].copy_from_slice(&self.b[0]);
                &mut self.x[0]
            }
            None => &mut self.r[0],
        };
        for (t, &d) in target.iter_mut().zip(inv) {
            if d == 0.0 {
                *t = 0.0;
            }
        }
        if let Some(c) = &self.chol {
            c.solve_in_place(target);
        }
        for (t, &d) in target.iter_mut().zip(inv) {
            if d == 0.0 {
                *t = 0.0;
            }
        }
    }
}

/// The work vectors of [`Multigrid::fcg`] (allocated once per solve).
#[derive(Debug, Default)]
pub struct FcgWork {
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    /// `A z`, when the cycle formed it.
    az: Vec<f64>,
}

impl FcgWork {
    fn resize(&mut self, n: usize) {
        for v in [&mut self.z, &mut self.p, &mut self.ap, &mut self.az] {
            if v.len() != n {
                // Written on all threads (the first use of fresh pages).
                *v = zeroed(n);
            }
        }
    }
}

/// Rows per block of the reductions of the Krylov methods.
const DOT_BLOCK: usize = crate::sparse::REDUCE_BLOCK;

/// `f(first row, a's block, b's block)` on the blocks of [`DOT_BLOCK`] rows of `a` and
/// `b` (in parallel for long vectors), the results in block order: one pass of several
/// vector updates and reductions instead of one pass each.
fn per_block<const K: usize>(
    a: &mut [f64],
    b: &mut [f64],
    f: impl Fn(usize, &mut [f64], &mut [f64]) -> [f64; K] + Sync + Send,
) -> Vec<[f64; K]> {
    use rayon::prelude::*;
    if a.len() >= crate::sparse::VECTOR_ROWS {
        a.par_chunks_mut(DOT_BLOCK)
            .zip(b.par_chunks_mut(DOT_BLOCK))
            .enumerate()
            .map(|(k, (x, y))| f(k * DOT_BLOCK, x, y))
            .collect()
    } else {
        a.chunks_mut(DOT_BLOCK)
            .zip(b.chunks_mut(DOT_BLOCK))
            .enumerate()
            .map(|(k, (x, y))| f(k * DOT_BLOCK, x, y))
            .collect()
    }
}

/// `Σ_i f(i)` over `0..n` for `K` sums at once, in blocks of [`DOT_BLOCK`] rows added in
/// block order (the same for any number of threads): several reductions in one pass.
fn sums<const K: usize>(n: usize, f: impl Fn(usize) -> [f64; K] + Sync + Send) -> [f64; K] {
    sum_block_parts(crate::sparse::map_blocks(n, |rows| {
        let mut s = [0.0; K];
        for i in rows {
            for (a, x) in s.iter_mut().zip(f(i)) {
                *a += x;
            }
        }
        s
    }))
}

/// The sums of per-block results in block order (the same for any number of threads).
fn sum_block_parts<const K: usize>(parts: Vec<[f64; K]>) -> [f64; K] {
    parts.iter().fold([0.0; K], |mut acc, v| {
        for (a, x) in acc.iter_mut().zip(v) {
            *a += x;
        }
        acc
    })
}
