//! Gauss-Seidel smoothing of the linear multigrid: forward and backward sweeps in fixed
//! blocks (independent of the thread count), fused with the residual or with the product
//! the flexible CG needs, and the seams between the blocks precomputed once per level.

use super::operator::TopOperator;
use crate::sparse::{par_copy_from, par_rows, Csr, Pattern};

/// `1 / A_ii`, or 0 where `A_ii ≤ 0` (zero rows, held rows).
pub(crate) fn fill_inv_diag<A: TopOperator>(op: &A, inv: &mut [f64]) {
    let a = op.matrix();
    let pat = &a.pattern;
    par_rows(inv, |i, d| {
        let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
        let k = pat.col[s..e].partition_point(|&j| (j as usize) < i);
        let aii = if s + k < e && pat.col[s + k] as usize == i {
            super::operator::entry(op, i, i, a.val[s + k])
        } else {
            0.0
        };
        *d = if aii > 0.0 { 1.0 / aii } else { 0.0 };
    });
}

/// Where a sweep finds `1 / A_ii` (0 where `A_ii ≤ 0`, as [`fill_inv_diag`] stores it):
/// a stored vector, or A's diagonal entry of the row the sweep reads anyway, divided on the
/// way (the top level, whose vector would be the size of the problem). Both give the same
/// number, so that a sweep's result does not depend on which.
#[derive(Clone, Copy)]
pub(crate) enum InvDiag<'a> {
    /// The vector filled by [`fill_inv_diag`].
    Stored(&'a [f64]),
    /// From the row, the diagonal's offset looked up in the pattern's [`SweepRows`].
    Rows(&'a SweepRows),
    /// From the row, the diagonal searched (A's pattern has no [`SweepRows`] at hand).
    Search,
}

impl InvDiag<'_> {
    /// `1 / A_ii` of row `i`, whose sorted columns and stored values are `cols`, `vals`.
    #[inline(always)]
    pub(crate) fn at<A: TopOperator>(&self, op: &A, i: usize, cols: &[u32], vals: &[f64]) -> f64 {
        let k = match self {
            InvDiag::Stored(inv) => return inv[i],
            InvDiag::Rows(rows) => rows.diag_of(i, cols),
            InvDiag::Search => cols.partition_point(|&j| (j as usize) < i),
        };
        let aii = match cols.get(k) {
            Some(&c) if c as usize == i => super::operator::entry(op, i, i, vals[k]),
            _ => 0.0,
        };
        if aii > 0.0 {
            1.0 / aii
        } else {
            0.0
        }
    }
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
        let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
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
    inv: InvDiag,
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
            let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
            let (cols, vals) = (&pat.col[s..e], &a.val[s..e]);
            let d = inv.at(op, i, cols, vals);
            if d == 0.0 {
                return;
            }
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
        let row = |i: usize| &pattern.col[pattern.ptr(i)..pattern.ptr(i + 1)];
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
    inv: InvDiag,
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
            let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
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
            let xi = (b[i] - lower) * inv.at(op, i, cols, vals);
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
            let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
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
    inv: InvDiag,
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
            let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
            let (cols, vals) = (&pat.col[s..e], &a.val[s..e]);
            let inside = within(cols, lo, hi);
            let ax = block_row_sum(cols, vals, lo, xs, outside, inside) + shift_term(op, i, xs[k]);
            let d = inv.at(op, i, cols, vals);
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
