//! Linear geometric multigrid on a [`Hierarchy`]: the V-cycle that computes the truncated
//! Newton correction of TNNMG, and, on the untruncated stiffness matrix S, the linear
//! Poisson solve used as the benchmark's yardstick.
//!
//! * Levels: the unknowns (interior vertices) of every mesh of the hierarchy that has
//!   any; prolongations [`Transfer`] between consecutive ones.
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
//!   replaced by the identity.

use super::operator::{apply, values_into, zero_held, TopOperator};
use super::transfer::{galerkin_patterns, par_copy_from, par_rows, Transfer};
use crate::error::{Error, Result};
use crate::mesh::refine::{Hierarchy, Refinement};
use crate::mesh::{DofMap, Mesh};
use crate::sparse::{filled, zeroed, Cholesky, Csr, Pattern};
use std::sync::Arc;

/// Where the coarse levels of a multigrid come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Nested meshes of uniform refinement (the exact P1 prolongation).
    Geometric,
    /// Aggregation of the matrix's unknowns ([`super::aggregation`]).
    Algebraic,
}

/// The static structure of a multigrid hierarchy over unknowns: per level its size and
/// operator pattern (and, for a geometric hierarchy, its dof map), and the prolongations.
/// Built once per hierarchy.
#[derive(Debug, Clone)]
pub struct Levels {
    /// Geometric or algebraic.
    pub kind: Kind,
    /// Unknowns of every level, coarsest first.
    pub sizes: Vec<usize>,
    /// Geometric hierarchies: the unknowns of every level's mesh but the finest (the
    /// model's own), coarsest first (levels without unknowns are left out). Empty for an
    /// algebraic hierarchy.
    pub dofs: Vec<DofMap>,
    /// Operator patterns, coarsest first; the finest is the pattern of S.
    pub patterns: Vec<Arc<Pattern>>,
    /// `transfers[k]` prolongates level `k` to level `k + 1`.
    pub transfers: Vec<Transfer>,
    /// What the smoother reads from every level's pattern, coarsest first.
    pub(crate) sweep_rows: Vec<SweepRows>,
}

impl Levels {
    /// Checks that `hierarchy` ends with the mesh of the unknowns `finest` (whose operator
    /// pattern is `pattern`) and builds the transfers and Galerkin patterns. A hierarchy
    /// that does not fit is an error.
    pub fn new(hierarchy: &Hierarchy, finest: &DofMap, pattern: Arc<Pattern>) -> Result<Levels> {
        let nl = hierarchy.levels.len();
        if nl == 0 || hierarchy.refinements.len() + 1 != nl {
            return Err(Error::Mesh(format!(
                "a hierarchy of {nl} levels needs {} refinement relations, it has {}",
                nl.saturating_sub(1),
                hierarchy.refinements.len()
            )));
        }
        let last = hierarchy.finest();
        if last.n_vertices() != finest.dof.len() || pattern.n() != finest.len() {
            return Err(Error::Mesh(format!(
                "the finest level of the hierarchy has {} vertices, but the model was \
                 assembled on a mesh of {} vertices: the hierarchy must end with the model's \
                 mesh",
                last.n_vertices(),
                finest.dof.len()
            )));
        }
        check_pattern(last, finest, &pattern)?;
        // The unknowns of the coarser levels, from the finer ones: a coarse vertex is
        // interior exactly when the fine vertex sitting on it is (nested meshes). The
        // finest level's unknowns are the model's own: no copy is kept.
        let mut dofs: Vec<DofMap> = Vec::with_capacity(nl - 1);
        for k in (0..nl - 1).rev() {
            let coarse = coarse_dofs(
                &hierarchy.refinements[k],
                hierarchy.levels[k].n_vertices(),
                dofs.last().unwrap_or(finest),
            )?;
            dofs.push(coarse);
        }
        dofs.reverse();
        let level = |k: usize| dofs.get(k).unwrap_or(finest);
        // Levels without unknowns cannot carry a correction: start above them.
        let first = (0..nl).position(|k| !level(k).is_empty()).unwrap_or(nl - 1);
        let mut transfers = Vec::with_capacity(nl - 1 - first);
        for k in first..nl - 1 {
            let t = Transfer::new(&hierarchy.refinements[k], level(k), level(k + 1))?;
            transfers.push(t);
        }
        let sizes = (first..nl).map(|k| level(k).len()).collect();
        let dofs: Vec<DofMap> = dofs.into_iter().skip(first).collect();
        let patterns = galerkin_patterns(&transfers, pattern);
        Ok(Levels {
            kind: Kind::Geometric,
            sizes,
            dofs,
            sweep_rows: patterns.iter().map(|p| SweepRows::of(p)).collect(),
            patterns,
            transfers,
        })
    }

    /// An algebraic hierarchy for the operator `a` (the finest level; its pattern is the
    /// finest pattern) by double pairwise aggregation, down to about `coarsest` unknowns.
    pub fn algebraic(a: &Csr, coarsest: usize) -> Levels {
        let (transfers, sizes, patterns) = super::aggregation::hierarchy(a, coarsest);
        Levels {
            kind: Kind::Algebraic,
            sizes,
            dofs: Vec::new(),
            sweep_rows: patterns.iter().map(|p| SweepRows::of(p)).collect(),
            patterns,
            transfers,
        }
    }

    /// Number of levels.
    pub fn len(&self) -> usize {
        self.sizes.len()
    }

    /// `true` when there is no level (never, after [`Levels::new`]).
    pub fn is_empty(&self) -> bool {
        self.sizes.is_empty()
    }

    /// Number of unknowns of level `k`.
    pub fn n(&self, k: usize) -> usize {
        self.sizes[k]
    }
}

/// The unknowns of a coarse level of `n_vertices` vertices, given those of the level
/// refined from it: coarse vertex `c` is interior iff the fine vertex on it (parents
/// `[c, c]`) is. A coarse vertex without such a fine vertex is an error.
fn coarse_dofs(refinement: &Refinement, n_vertices: usize, fine: &DofMap) -> Result<DofMap> {
    if refinement.parents.len() != fine.dof.len() {
        return Err(Error::Mesh(format!(
            "the refinement relation names parents for {} vertices, but the finer level has \
             {} vertices",
            refinement.parents.len(),
            fine.dof.len()
        )));
    }
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU8, Ordering::Relaxed};
    // Per coarse vertex: 0 while no fine vertex sits on it, then FIXED or INTERIOR. A
    // refinement puts one fine vertex on each coarse one; should a broken one put two, the
    // larger state is kept, whatever the order the threads write in.
    const FIXED: u8 = 1;
    const INTERIOR: u8 = 2;
    let state: Vec<AtomicU8> = (0..n_vertices)
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| AtomicU8::new(0))
        .collect();
    let bad = refinement
        .parents
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(v, &[a, b])| {
            if a as usize >= n_vertices || b as usize >= n_vertices {
                return Some((v, a, b));
            }
            if a == b {
                let on = if fine.dof[v].is_some() {
                    INTERIOR
                } else {
                    FIXED
                };
                state[a as usize].fetch_max(on, Relaxed);
            }
            None
        })
        .find_first(Option::is_some)
        .flatten();
    if let Some((v, a, b)) = bad {
        return Err(Error::Mesh(format!(
            "vertex {v} of the finer level has parent vertices ({a}, {b}), but the coarser \
             level has only {n_vertices} vertices"
        )));
    }
    let state: Vec<u8> = state.into_par_iter().map(AtomicU8::into_inner).collect();
    if let Some(c) = crate::sparse::first_where(&state, |x| x == 0) {
        return Err(Error::Mesh(format!(
            "the refinement relation keeps no vertex on vertex {c} of the coarser level"
        )));
    }
    let fixed: Vec<bool> = state.par_iter().map(|&x| x == FIXED).collect();
    Ok(DofMap::from_fixed(&fixed))
}

/// Checks that the operator pattern couples the unknowns along the edges of the triangles
/// of `mesh` (every triangle of small meshes, every 16th of large ones): a cheap test that
/// the model was assembled on this mesh.
fn check_pattern(mesh: &Mesh, dofs: &DofMap, pattern: &Pattern) -> Result<()> {
    use rayon::prelude::*;
    let step = if mesh.n_triangles() > 100_000 { 16 } else { 1 };
    let bad = mesh
        .triangles
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .filter(|(k, _)| k % step == 0)
        .find_any(|(_, t)| {
            t.iter().any(|&a| {
                t.iter()
                    .any(|&b| match (dofs.dof[a as usize], dofs.dof[b as usize]) {
                        (Some(i), Some(j)) => pattern.find(i as usize, j as usize).is_none(),
                        _ => false,
                    })
            })
        });
    match bad {
        Some((k, _)) => Err(Error::Mesh(format!(
            "triangle {k} of the finest level of the hierarchy couples unknowns that the \
             model's matrices do not: the hierarchy must end with the mesh the model was \
             assembled on"
        ))),
        None => Ok(()),
    }
}

/// Gauss-Seidel smoothing steps and operators of a linear multigrid on levels `0..=top` of
/// a [`Levels`], with the work arrays of a V-cycle (allocated once).
pub struct Multigrid<'a> {
    levels: &'a Levels,
    top: usize,
    /// Operators of levels `0..top` (the finest is the caller's).
    coarse: Vec<Csr>,
    /// `1 / A_ii`, or 0 on zero rows, for levels `0..=top`.
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
            inv_diag: (0..=top).map(zeros).collect(),
            x: (0..top).map(zeros).collect(),
            b: (0..top).map(zeros).collect(),
            r: (0..=top).map(zeros).collect(),
            dirty: (0..top).map(|k| filled(levels.n(k), true)).collect(),
            coarsest: Csr::zeros(levels.patterns[0].clone()),
            chol: None,
            smoothing: (1, 1),
            krylov: (0..top)
                .map(|k| {
                    if levels.kind == Kind::Algebraic && k > 0 {
                        [zeros(k), zeros(k), zeros(k)]
                    } else {
                        Default::default()
                    }
                })
                .collect(),
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
        while steps < max_steps {
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

    /// One cycle for `A x = b` on the top level: the V-cycle on a geometric hierarchy, the
    /// K-cycle on an algebraic one (see [`Multigrid::v_cycle`], [`Multigrid::k_cycle`]).
    pub fn cycle<A: TopOperator>(&mut self, fine: &A, x: &mut [f64], b: &[f64]) {
        match self.levels.kind {
            Kind::Geometric => self.v_cycle(fine, x, b),
            Kind::Algebraic => self.k_cycle(fine, x, b),
        }
    }

    /// [`Multigrid::cycle`] from `x = 0`, whatever `x` holds on entry (the preconditioner
    /// of [`Multigrid::fcg`]): the first smoothing sweep and the residual after it are then
    /// one pass over A ([`gauss_seidel_from_zero`]).
    pub fn cycle_from_zero<A: TopOperator>(&mut self, fine: &A, x: &mut [f64], b: &[f64]) {
        self.cycle_from_zero_with_product(fine, x, b, None);
    }

    /// [`Multigrid::cycle_from_zero`], and `A x` after it into `product` when the last
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
        let krylov = self.levels.kind == Kind::Algebraic;
        self.cycle_below(fine, x, b, product, krylov)
    }

    /// Whether `fine`'s pattern is the top level's own, so that the fused kernels may use
    /// the top level's seam rows.
    fn fused_on_top<A: TopOperator>(&self, fine: &A) -> bool {
        Arc::ptr_eq(&fine.matrix().pattern, &self.levels.patterns[self.top])
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
            let (inv, rows) = (&self.inv_diag[top], &self.levels.sweep_rows[top]);
            gauss_seidel_from_zero(fine, inv, x, b, &mut self.r[top], rows);
            return;
        }
        if from_zero {
            x.iter_mut().for_each(|v| *v = 0.0);
        } else {
            zero_held(fine, x);
        }
        for _ in 0..nu1 {
            gauss_seidel(fine, &self.inv_diag[top], x, b, &mut self.r[top], false);
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
            let (inv, rows) = (&self.inv_diag[top], &self.levels.sweep_rows[top]);
            gauss_seidel_back_with_product(fine, inv, x, b, &mut self.r[top], y, rows);
            return true;
        }
        for _ in 0..nu2 {
            gauss_seidel(fine, &self.inv_diag[top], x, b, &mut self.r[top], true);
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
        let (a, inv) = (&self.coarse[k], &self.inv_diag[k]);
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
            &self.inv_diag[k],
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

    /// Number of levels used.
    pub fn depth(&self) -> usize {
        self.top + 1
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
        fill_inv_diag(fine, &mut self.inv_diag[top]);
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
                    for k in pat.row_ptr[i]..pat.row_ptr[i + 1] {
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
            for k in (1..top).rev() {
                self.presmooth_and_restrict(k);
            }
            // Bottom: the direct solve.
            self.solve_coarsest_in_place(Some(0));
            // Up: prolongate the correction, smooth.
            for k in 1..top {
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
    if a.len() >= super::transfer::PAR_ROWS {
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

/// `1 / A_ii`, or 0 where `A_ii ≤ 0` (zero rows, held rows).
pub(crate) fn fill_inv_diag<A: TopOperator>(op: &A, inv: &mut [f64]) {
    let a = op.matrix();
    let pat = &a.pattern;
    par_rows(inv, |i, d| {
        let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
        let k = pat.col[s..e].partition_point(|&j| (j as usize) < i);
        let aii = if s + k < e && pat.col[s + k] as usize == i {
            super::operator::entry(op, i, i, a.val[s + k])
        } else {
            0.0
        };
        *d = if aii > 0.0 { 1.0 / aii } else { 0.0 };
    });
}

/// `r = b − A x` (x zero on held unknowns).
pub(crate) fn residual<A: TopOperator>(op: &A, x: &[f64], b: &[f64], r: &mut [f64]) {
    let a = op.matrix();
    let pat = &a.pattern;
    par_rows(r, |i, ri| {
        if !A::PLAIN && op.held(i) {
            *ri = b[i];
            return;
        }
        let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
        *ri = b[i] - (row_sum(&pat.col[s..e], &a.val[s..e], |j| x[j]) + shift_term(op, i, x[i]));
    });
}

/// `shift_i x_i`: the part of row i's product that the stored matrix lacks (none for an
/// assembled matrix, not even a rounding of zero).
#[inline(always)]
fn shift_term<A: TopOperator>(op: &A, i: usize, xi: f64) -> f64 {
    if A::PLAIN {
        0.0
    } else {
        op.shift(i) * xi
    }
}

/// Rows per block of the block Gauss-Seidel smoother. The blocks are fixed by the matrix
/// size alone, so the result does not depend on the number of threads.
pub(crate) const GS_BLOCK: usize = 32_768;

/// The smoothing blocks' size for a level of `n` rows: [`GS_BLOCK`], or a quarter of it up
/// to four blocks of [`GS_BLOCK`], so that the smaller levels (visited most often by the
/// K-cycle) are smoothed on all threads too. A function of `n` alone.
#[inline]
pub(crate) fn gs_block(n: usize) -> usize {
    if n > 4 * GS_BLOCK {
        GS_BLOCK
    } else {
        GS_BLOCK / 4
    }
}

/// `Σ_k vals[k] x(cols[k])` with two partial sums (a shorter dependency chain).
#[inline(always)]
fn row_sum(cols: &[u32], vals: &[f64], x: impl Fn(usize) -> f64) -> f64 {
    let (mut s0, mut s1) = (0.0, 0.0);
    let mut pairs = cols.chunks_exact(2).zip(vals.chunks_exact(2));
    for (c, v) in &mut pairs {
        s0 += v[0] * x(c[0] as usize);
        s1 += v[1] * x(c[1] as usize);
    }
    if cols.len() % 2 == 1 {
        let k = cols.len() - 1;
        s0 += vals[k] * x(cols[k] as usize);
    }
    s0 + s1
}

/// Whether the sorted columns `cols` all lie in `lo..hi` (a row of a smoothing block that
/// does not couple to another block: the hybrid sweeps need not look where its columns are).
#[inline(always)]
fn within(cols: &[u32], lo: usize, hi: usize) -> bool {
    match (cols.first(), cols.last()) {
        (Some(&f), Some(&l)) => f as usize >= lo && (l as usize) < hi,
        _ => true,
    }
}

/// Row `cols`/`vals` times the current iterate of a hybrid sweep over the block starting at
/// `lo`: the block's own values `xs`, and `outside` elsewhere (not looked at when the row
/// is `inside` its block, [`within`]).
#[inline(always)]
fn block_row_sum(
    cols: &[u32],
    vals: &[f64],
    lo: usize,
    xs: &[f64],
    outside: &[f64],
    inside: bool,
) -> f64 {
    if inside {
        row_sum(cols, vals, |j| xs[j - lo])
    } else {
        let hi = lo + xs.len();
        row_sum(cols, vals, |j| {
            if j >= lo && j < hi {
                xs[j - lo]
            } else {
                outside[j]
            }
        })
    }
}

/// One Gauss-Seidel sweep for `A x = b` (rows with `inv_diag = 0` skipped), forward or
/// backward. Up to one block ([`gs_block`]) of unknowns it is the classical sweep; beyond, the rows are cut
/// into such blocks that are swept in parallel, each by Gauss-Seidel inside the
/// block and with the values of the other blocks from before the sweep (hybrid
/// Gauss-Seidel, kept in `snapshot`). `x` is zero on held unknowns, and stays so.
pub(crate) fn gauss_seidel<A: TopOperator>(
    op: &A,
    inv: &[f64],
    x: &mut [f64],
    b: &[f64],
    snapshot: &mut [f64],
    backward: bool,
) {
    use rayon::prelude::*;
    let a = op.matrix();
    let pat = &a.pattern;
    let n = x.len();
    let sweep = |lo: usize, xs: &mut [f64], outside: &[f64]| {
        let hi = lo + xs.len();
        let mut relax = |i: usize| {
            let d = inv[i];
            if d == 0.0 {
                return;
            }
            let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
            let (cols, vals) = (&pat.col[s..e], &a.val[s..e]);
            let inside = within(cols, lo, hi);
            let ax =
                block_row_sum(cols, vals, lo, xs, outside, inside) + shift_term(op, i, xs[i - lo]);
            xs[i - lo] += (b[i] - ax) * d;
        };
        if backward {
            (lo..hi).rev().for_each(&mut relax);
        } else {
            (lo..hi).for_each(&mut relax);
        }
    };
    let block = gs_block(n);
    if n <= block {
        sweep(0, x, &[]);
        return;
    }
    par_copy_from(snapshot, x);
    let outside: &[f64] = snapshot;
    x.par_chunks_mut(block)
        .enumerate()
        .for_each(|(k, xs)| sweep(k * block, xs, outside));
}

/// What the fused sweeps ([`gauss_seidel_from_zero`], [`gauss_seidel_back_with_product`])
/// read from a level's pattern besides the matrix, found once per hierarchy.
#[derive(Debug, Clone, Default)]
pub(crate) struct SweepRows {
    /// The rows that couple to another smoothing block ([`gs_block`] rows; none up to one
    /// block): the rows whose residual or product a sweep completes at the end.
    pub seams: Vec<u32>,
    /// Per row, the number of its columns before the diagonal (the diagonal's offset in
    /// the row when it is stored), or [`SweepRows::MANY`] from that many on. Looked up
    /// rather than counted: on an unstructured mesh the count varies from row to row, and
    /// a counting loop's exit is then mispredicted in almost every row. One byte per row
    /// (a 16.8 M-unknown level keeps 17 MB, not 67).
    pub diag: Vec<u8>,
}

impl SweepRows {
    /// The seam rows and diagonal offsets of `pattern`: one pass of a few comparisons per
    /// row (columns are sorted: a row stays inside its block when its first and last
    /// columns do).
    pub(crate) fn of(pattern: &Pattern) -> SweepRows {
        use rayon::prelude::*;
        let n = pattern.n();
        let block = gs_block(n);
        let row = |i: usize| &pattern.col[pattern.row_ptr[i]..pattern.row_ptr[i + 1]];
        let seams = if n <= block {
            Vec::new()
        } else {
            (0..n)
                .into_par_iter()
                .with_min_len(4096)
                .filter(|&i| {
                    let (lo, hi) = (i / block * block, (i / block + 1) * block);
                    !within(row(i), lo, hi)
                })
                .map(|i| i as u32)
                .collect()
        };
        let diag = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let before: usize = row(i).iter().map(|&c| ((c as usize) < i) as usize).sum();
                before.min(Self::MANY as usize) as u8
            })
            .collect();
        SweepRows { seams, diag }
    }

    /// The stored offsets saturate here: rows with this many columns before the diagonal
    /// or more (a vertex in hundreds of triangles) count them.
    pub(crate) const MANY: u8 = u8::MAX;

    /// The number of columns before the diagonal in row `i`, whose sorted columns are
    /// `cols`.
    #[inline(always)]
    pub(crate) fn diag_of(&self, i: usize, cols: &[u32]) -> usize {
        match self.diag[i] {
            Self::MANY => cols.partition_point(|&c| (c as usize) < i),
            d => d as usize,
        }
    }
}

/// One forward sweep of [`gauss_seidel`] from `x = 0` (whatever `x` holds on entry), with
/// the residual `r = b − A x` after it, in one pass over a symmetric A instead of two.
/// When row i sets x_i, the part `Σ_{j ≤ i} a_ij x_j` of its own product is complete
/// (later unknowns of its block are still 0); the later rows' part reaches r_i from
/// them, `a_ki x_k = a_ik x_k` scattered from row k as soon as x_k is known. Unknowns of
/// other blocks are 0 during the sweep (the hybrid sweep's start), so their part is added
/// at the end, on the seam rows alone (`rows`: [`SweepRows::of`] A's pattern). Held rows
/// keep `x = 0` and `r = b`.
pub(crate) fn gauss_seidel_from_zero<A: TopOperator>(
    op: &A,
    inv: &[f64],
    x: &mut [f64],
    b: &[f64],
    r: &mut [f64],
    rows: &SweepRows,
) {
    use rayon::prelude::*;
    let a = op.matrix();
    let pat = &a.pattern;
    let n = x.len();
    let sweep = |lo: usize, xs: &mut [f64], rs: &mut [f64]| {
        let hi = lo + xs.len();
        for (k, i) in (lo..hi).enumerate() {
            let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
            let (cols, vals) = (&pat.col[s..e], &a.val[s..e]);
            // Columns are sorted: those of the block before i are `first..diag` (the ones
            // before the block, and i's later neighbours, are still 0 in this sweep).
            let first: usize = if within(cols, lo, hi) {
                0
            } else {
                cols.iter().map(|&c| ((c as usize) < lo) as usize).sum()
            };
            let diag = rows.diag_of(i, cols);
            let (lc, lv) = (&cols[first..diag], &vals[first..diag]);
            let lower: f64 = lc
                .iter()
                .zip(lv)
                .map(|(&c, &v)| v * xs[c as usize - lo])
                .sum();
            let xi = (b[i] - lower) * inv[i];
            xs[k] = xi;
            let aii = match cols.get(diag) {
                Some(&c) if c as usize == i => vals[diag] + shift_term(op, i, 1.0),
                _ => 0.0,
            };
            rs[k] = b[i] - lower - aii * xi;
            for (&c, &v) in lc.iter().zip(lv) {
                rs[c as usize - lo] -= v * xi;
            }
        }
    };
    // A free row scatters its part into a held neighbour's residual: put back `r = b`.
    let restore_held = |r: &mut [f64]| {
        if !A::PLAIN {
            par_rows(r, |i, ri| {
                if op.held(i) {
                    *ri = b[i];
                }
            });
        }
    };
    let block = gs_block(n);
    if n <= block {
        sweep(0, x, r);
        restore_held(r);
        return;
    }
    x.par_chunks_mut(block)
        .zip(r.par_chunks_mut(block))
        .enumerate()
        .for_each(|(k, (xs, rs))| sweep(k * block, xs, rs));
    // The other blocks' unknowns, now known, on the rows that see them.
    let x: &[f64] = x;
    add_outside_blocks(a, &rows.seams, r, -1.0, |j| x[j]);
    restore_held(r);
}

/// `out_i += sign · Σ_j a_ij value(j)` over the columns j outside row i's smoothing block
/// ([`gs_block`] rows), for the rows of `seams` ([`SweepRows::seams`] of A's pattern):
/// the hybrid sweeps' contribution of the other blocks, added once they are done.
fn add_outside_blocks(
    a: &Csr,
    seams: &[u32],
    out: &mut [f64],
    sign: f64,
    value: impl Fn(usize) -> f64 + Sync,
) {
    use rayon::prelude::*;
    let pat = &a.pattern;
    let block = gs_block(out.len());
    out.par_chunks_mut(block).enumerate().for_each(|(k, os)| {
        let lo = k * block;
        let hi = lo + os.len();
        let from = seams.partition_point(|&i| (i as usize) < lo);
        let to = seams.partition_point(|&i| (i as usize) < hi);
        for &i in &seams[from..to] {
            let i = i as usize;
            let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
            let outside: f64 = pat.col[s..e]
                .iter()
                .zip(&a.val[s..e])
                .filter(|(&j, _)| (j as usize) < lo || (j as usize) >= hi)
                .map(|(&j, &v)| v * value(j as usize))
                .sum();
            os[i - lo] += sign * outside;
        }
    });
}

/// One backward sweep of [`gauss_seidel`], with the product `y = A x` after it, in one
/// pass over a symmetric A instead of two. When row i is relaxed, its product with the
/// current x is known; x_i's change then reaches the rows after it in the block, swept
/// already, as `a_ki Δx_i = a_ik Δx_i` from row i's own entries, and the rows before it
/// send theirs when they are relaxed. Unknowns of other blocks change during the sweep
/// (the hybrid sweep reads them from `snapshot`, as they were before it), so their changes
/// are added at the end, on the seam rows alone (`rows`: [`SweepRows::of`] A's pattern).
/// Held rows keep x and get `y = 0`, as [`apply`] gives.
pub(crate) fn gauss_seidel_back_with_product<A: TopOperator>(
    op: &A,
    inv: &[f64],
    x: &mut [f64],
    b: &[f64],
    snapshot: &mut [f64],
    y: &mut [f64],
    rows: &SweepRows,
) {
    use rayon::prelude::*;
    let a = op.matrix();
    let pat = &a.pattern;
    let n = x.len();
    let sweep = |lo: usize, xs: &mut [f64], ys: &mut [f64], outside: &[f64]| {
        let hi = lo + xs.len();
        for k in (0..xs.len()).rev() {
            let i = lo + k;
            let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
            let (cols, vals) = (&pat.col[s..e], &a.val[s..e]);
            let inside = within(cols, lo, hi);
            let ax = block_row_sum(cols, vals, lo, xs, outside, inside) + shift_term(op, i, xs[k]);
            let d = inv[i];
            if d == 0.0 {
                ys[k] = ax;
                continue;
            }
            let dx = (b[i] - ax) * d;
            xs[k] += dx;
            // Columns are sorted: i's later neighbours in the block are `diag + 1..last`.
            let diag = rows.diag_of(i, cols);
            let last: usize = if inside {
                cols.len()
            } else {
                cols.iter().map(|&c| ((c as usize) < hi) as usize).sum()
            };
            let aii = match cols.get(diag) {
                Some(&c) if c as usize == i => vals[diag] + shift_term(op, i, 1.0),
                _ => 0.0,
            };
            ys[k] = ax + aii * dx;
            if diag < last {
                for (&c, &v) in cols[diag + 1..last].iter().zip(&vals[diag + 1..last]) {
                    ys[c as usize - lo] += v * dx;
                }
            }
        }
    };
    let clear_held = |y: &mut [f64]| {
        if !A::PLAIN {
            par_rows(y, |i, yi| {
                if op.held(i) {
                    *yi = 0.0;
                }
            });
        }
    };
    let block = gs_block(n);
    if n <= block {
        sweep(0, x, y, &[]);
        clear_held(y);
        return;
    }
    par_copy_from(snapshot, x);
    let before: &[f64] = snapshot;
    x.par_chunks_mut(block)
        .zip(y.par_chunks_mut(block))
        .enumerate()
        .for_each(|(k, (xs, ys))| sweep(k * block, xs, ys, before));
    // The other blocks' changes, now known, on the rows that see them.
    let x: &[f64] = x;
    add_outside_blocks(a, &rows.seams, y, 1.0, |j| x[j] - before[j]);
    clear_held(y);
}

/// The result of a linear multigrid solve.
#[derive(Debug, Clone)]
pub struct LinearSolve {
    /// The solution.
    pub x: Vec<f64>,
    /// V-cycles done.
    pub cycles: usize,
    /// `‖b − A x‖∞ / ‖b‖∞` at the end.
    pub relative_residual: f64,
    /// Wall-clock seconds per phase (setup, coarse operators, cycles).
    pub phases: Vec<(String, f64)>,
}

/// Solves the linear system `S x = rhs` (S on the finest level of `hierarchy`, over the
/// unknowns `dofs`) by V(1,1)-cycles from `x = 0` until `‖rhs − S x‖∞ ≤ tol · scale`: the
/// linear Poisson multigrid that the contact solver is measured against. `scale = None`
/// means `‖rhs‖∞` (the plain relative residual); the benchmark passes the model's force
/// scale, the scaling of the contact solver's KKT certificates, so that both stop at the
/// same residual (with `‖D‖∞` alone, 1e-10 is below the rounding floor of `S x` from about
/// a million unknowns on). Not reaching the tolerance (within `max_cycles`, or because the
/// residual stagnates at rounding level) is an error.
pub fn poisson_solve(
    s: &Csr,
    rhs: &[f64],
    hierarchy: &Hierarchy,
    dofs: &DofMap,
    tol: f64,
    scale: Option<f64>,
    max_cycles: usize,
) -> Result<LinearSolve> {
    let t0 = std::time::Instant::now();
    let levels = Levels::new(hierarchy, dofs, s.pattern.clone())?;
    let setup = t0.elapsed().as_secs_f64();
    let mut out = linear_solve(s, rhs, &levels, tol, scale, max_cycles)?;
    out.phases.insert(0, ("setup".into(), setup));
    Ok(out)
}

/// [`poisson_solve`] on prebuilt [`Levels`].
pub fn linear_solve(
    a: &Csr,
    rhs: &[f64],
    levels: &Levels,
    tol: f64,
    scale: Option<f64>,
    max_cycles: usize,
) -> Result<LinearSolve> {
    if rhs.len() != a.n() || a.n() != levels.n(levels.len() - 1) {
        return Err(Error::Solver {
            solver: "multigrid".into(),
            message: "right-hand side, matrix and hierarchy sizes differ".into(),
        });
    }
    let mut timer = crate::solve::PhaseTimer::default();
    let mut mg = Multigrid::new(levels, levels.len() - 1);
    timer.time("coarse operators", || mg.update(a, None))?;
    let t0 = std::time::Instant::now();
    let norm_b = scale.unwrap_or_else(|| crate::sparse::norm_inf(rhs));
    let mut x = vec![0.0; a.n()];
    let mut r = vec![0.0; a.n()];
    let mut cycles = 0;
    let mut rel = if crate::sparse::norm_inf(rhs) == 0.0 {
        0.0
    } else {
        crate::sparse::norm_inf(rhs) / norm_b
    };
    // The best residual so far and when it was reached (stagnation test).
    let mut best = (rel, 0);
    while rel > tol && cycles < max_cycles && cycles < best.1 + 4 {
        mg.v_cycle(a, &mut x, rhs);
        cycles += 1;
        residual(a, &x, rhs, &mut r);
        rel = crate::sparse::norm_inf(&r) / norm_b;
        if !rel.is_finite() {
            break;
        }
        if rel < 0.9 * best.0 {
            best = (rel, cycles);
        }
    }
    if rel.is_nan() || rel > tol {
        return Err(Error::Solver {
            solver: "multigrid".into(),
            message: format!(
                "linear multigrid stopped after {cycles} V-cycles at scaled residual {rel:.3e} \
                 (tolerance {tol:.1e})"
            ),
        });
    }
    timer.add("v-cycles", t0.elapsed().as_secs_f64());
    Ok(LinearSolve {
        x,
        cycles,
        relative_residual: rel,
        phases: timer.into_phases(),
    })
}
