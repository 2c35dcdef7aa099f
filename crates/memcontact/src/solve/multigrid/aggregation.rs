//! An algebraic multigrid hierarchy by **double pairwise aggregation** (Y. Notay, "An
//! aggregation-based algebraic multigrid method", ETNA 37 (2010); the aggregation of
//! AGMG), for meshes that carry no refinement hierarchy.
//!
//! One coarsening step matches every unknown with its most strongly negatively coupled
//! unmatched neighbour (a pair, or a singleton when none is left), forms the Galerkin
//! matrix of those pairs, and matches again: aggregates of up to four unknowns, a
//! coarsening ratio close to 4 in two dimensions. The prolongation is the piecewise-constant
//! one (`P[v, aggregate(v)] = 1`), which fits [`Transfer`] with one parent of weight 1, so
//! that the Galerkin coarse operators `PᵀAP` and their refresh in changed rows are those of
//! the geometric hierarchy. Unknowns whose row is dominated by its diagonal (a stiff
//! foundation) need no coarse correction: they are left out of every aggregate and handled
//! by the smoother alone.
//!
//! Unsmoothed aggregation needs a cycle that keeps its convergence as levels are added:
//! the K-cycle of [`super::cycle::Multigrid::k_cycle`]. The aggregation is built once per
//! solve from `S` plus the foundation's diagonal and reused by every Newton correction.

use super::transfer::Transfer;
use crate::sparse::{Csr, Pattern};
use std::sync::Arc;

/// An unknown not in any aggregate.
pub const NONE: u32 = u32::MAX;

/// Coupling threshold: `j` is a strong neighbour of `i` when
/// `a_ij < −β max_k |a_ik|` over the negative off-diagonal entries of row `i`.
const BETA: f64 = 0.25;

/// A row with `a_ii ≥ DOMINANT Σ_{j≠i} |a_ij|` is left to the smoother.
const DOMINANT: f64 = 5.0;

/// Stop coarsening at this many unknowns by default (the coarsest level is factorised).
pub const COARSEST: usize = 2_000;

/// Stop coarsening when a step keeps more than this fraction of the unknowns.
const STAGNATION: f64 = 0.7;

/// At most this many levels.
const MAX_LEVELS: usize = 40;

/// Rows per block of a parallel matching (see [`pairwise`]).
const MATCH_BLOCK: usize = 1 << 16;

/// One pairwise matching of the rows of `a`: the pair (or singleton) of every row, `NONE`
/// for rows left to the smoother (zero or dominant diagonal); returns the aggregate index
/// of every row and the number of aggregates. Rows are taken in order of fewest unmatched
/// strong neighbours (Notay's rule, which leaves few rows unpaired), each paired with its
/// strongest unmatched neighbour.
///
/// Large matrices are matched by blocks of [`MATCH_BLOCK`] consecutive rows in parallel,
/// pairs never crossing a block's edge (as in parallel aggregation codes: with rows in a
/// locality order, a block is a compact piece of the domain and few rows lie on its
/// edge); aggregates are numbered block by block. The blocks depend on the size alone:
/// the result is the same for any number of threads.
fn pairwise(a: &Csr) -> (Vec<u32>, usize) {
    use rayon::prelude::*;
    let n = a.n();
    if n < 2 * MATCH_BLOCK {
        return pairwise_range(a, 0, n);
    }
    let parts: Vec<(Vec<u32>, usize)> = (0..n.div_ceil(MATCH_BLOCK))
        .into_par_iter()
        .map(|b| pairwise_range(a, b * MATCH_BLOCK, ((b + 1) * MATCH_BLOCK).min(n)))
        .collect();
    let mut agg = Vec::with_capacity(n);
    let mut count = 0usize;
    for (local, c) in parts {
        let offset = count as u32;
        agg.extend(
            local
                .iter()
                .map(|&g| if g == NONE { NONE } else { g + offset }),
        );
        count += c;
    }
    (agg, count)
}

/// [`pairwise`] on the rows `lo..hi` alone (couplings to other rows ignored); aggregates
/// numbered from 0.
fn pairwise_range(a: &Csr, lo: usize, hi: usize) -> (Vec<u32>, usize) {
    let m = hi - lo;
    let mut free = vec![true; m];
    let mut threshold = vec![0.0; m];
    for i in lo..hi {
        let (cols, vals) = a.row(i);
        let (mut diag, mut off, mut strongest) = (0.0, 0.0, 0.0f64);
        for (&j, &v) in cols.iter().zip(vals) {
            if j as usize == i {
                diag = v;
            } else {
                off += v.abs();
                strongest = strongest.max(-v);
            }
        }
        free[i - lo] = diag > 0.0 && diag < DOMINANT * off;
        threshold[i - lo] = BETA * strongest;
    }
    // The strong neighbours of every row taking part, listed once (the matching visits
    // them up to three times): negative couplings above [`BETA`] times the strongest of
    // the row, to rows of the range taking part. Local indices, in column order.
    let mut start = Vec::with_capacity(m + 1);
    let mut strong: Vec<(u32, f64)> = Vec::with_capacity(8 * m);
    start.push(0);
    for i in lo..hi {
        if free[i - lo] {
            let (cols, vals) = a.row(i);
            let t = threshold[i - lo];
            for (&j, &v) in cols.iter().zip(vals) {
                let j = j as usize;
                if j != i && (lo..hi).contains(&j) && free[j - lo] && -v > t {
                    strong.push(((j - lo) as u32, v));
                }
            }
        }
        start.push(strong.len());
    }
    let of = |i: usize| &strong[start[i]..start[i + 1]];
    let mut agg = vec![NONE; m];
    // A bucket queue by the number of unmatched strong neighbours, with lazy deletion.
    let mut degree: Vec<u32> = (0..m).map(|i| of(i).len() as u32).collect();
    let top = degree.iter().copied().max().unwrap_or(0) as usize;
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); top + 1];
    for i in (0..m).rev() {
        if free[i] {
            buckets[degree[i] as usize].push(i as u32);
        }
    }
    let mut lowest = 0usize;
    let mut count = 0u32;
    loop {
        while lowest < buckets.len() && buckets[lowest].is_empty() {
            lowest += 1;
        }
        let Some(i) = buckets.get_mut(lowest).and_then(Vec::pop) else {
            break;
        };
        let i = i as usize;
        if agg[i] != NONE || degree[i] as usize != lowest {
            continue; // matched, or queued again with a smaller degree
        }
        let mut best: Option<(usize, f64)> = None;
        for &(j, v) in of(i) {
            if agg[j as usize] == NONE && best.is_none_or(|(_, b)| v < b) {
                best = Some((j as usize, v));
            }
        }
        for r in std::iter::once(i).chain(best.map(|b| b.0)) {
            agg[r] = count;
            for &(k, _) in of(r) {
                let k = k as usize;
                if agg[k] == NONE && degree[k] > 0 {
                    degree[k] -= 1;
                    buckets[degree[k] as usize].push(k as u32);
                    lowest = lowest.min(degree[k] as usize);
                }
            }
        }
        count += 1;
    }
    number_in_row_order(&mut agg, count as usize);
    (agg, count as usize)
}

/// Renumbers the aggregates `agg` (`NONE` for none) by their first row, so that the coarse
/// unknowns follow the fine rows' order: the matching numbers them in the order the bucket
/// queue visits them, scattered over the rows, and the coarse levels would lose the
/// fine level's locality (in the Galerkin products, the transfers and the smoothing sweeps).
fn number_in_row_order(agg: &mut [u32], count: usize) {
    let mut new = vec![NONE; count];
    let mut next = 0u32;
    for g in agg.iter_mut().filter(|g| **g != NONE) {
        let slot = &mut new[*g as usize];
        if *slot == NONE {
            *slot = next;
            next += 1;
        }
        *g = *slot;
    }
}

/// The transfers of an aggregation hierarchy for the operator `a` (finest level), coarsest
/// level first, with the level sizes and the Galerkin operator patterns (the finest is
/// `a`'s), coarsest first. Coarsening stops at `coarsest` unknowns (see [`COARSEST`]), when
/// a step no longer reduces the size enough, or at [`MAX_LEVELS`].
pub fn hierarchy(a: &Csr, coarsest: usize) -> (Vec<Transfer>, Vec<usize>, Vec<Arc<Pattern>>) {
    use rayon::prelude::*;
    let mut transfers: Vec<Transfer> = Vec::new();
    let mut sizes = vec![a.n()];
    let mut patterns = vec![a.pattern.clone()];
    let mut current: Option<Csr> = None;
    while sizes.len() < MAX_LEVELS {
        let fine = current.as_ref().unwrap_or(a);
        let n = fine.n();
        if n <= coarsest {
            break;
        }
        // Two pairwise matchings, composed.
        let (first, n1) = pairwise(fine);
        let t1 = Transfer::aggregation(&first, n1);
        let a1 = galerkin(fine, &t1);
        let (second, n2) = pairwise(&a1);
        let agg: Vec<u32> = first
            .par_iter()
            .with_min_len(8192)
            .map(|&p| if p == NONE { NONE } else { second[p as usize] })
            .collect();
        if n2 == 0 || n2 as f64 > STAGNATION * n as f64 {
            break;
        }
        let t = Transfer::aggregation(&agg, n2);
        // P = P₁P₂, so PᵀAP = P₂ᵀ(P₁ᵀAP₁)P₂: the product from the half-size matrix, on
        // the same pattern as PᵀAP (aggregation keeps every diagonal).
        let coarse = galerkin(&a1, &Transfer::aggregation(&second, n2));
        transfers.push(t);
        sizes.push(n2);
        patterns.push(coarse.pattern.clone());
        current = Some(coarse);
    }
    transfers.reverse();
    sizes.reverse();
    patterns.reverse();
    (transfers, sizes, patterns)
}

/// The factor by which nested iteration scales the Galerkin stiffness `PᵀSP` of an
/// aggregation step from `n_fine` to `n_coarse` unknowns. A piecewise-constant function on
/// aggregates m vertices across carries its slope in jumps one element wide, so its energy
/// is about m times that of the smooth function it stands for, and the coarse minimiser
/// would deflect m times too little. m grows like √(n_fine / n_coarse) for square
/// aggregates; real ones are not square, and the exponent that serves best,
/// [`STIFFNESS_SCALE_EXPONENT`], was measured a little above ½. The foundation and load
/// terms hold no derivative and need no factor. (The same overestimate is why plain
/// aggregation needs over-corrected or Krylov-accelerated cycles: D. Braess, "Towards
/// algebraic multigrid for elliptic problems of second order", Computing 55 (1995).)
pub fn stiffness_scale(n_fine: usize, n_coarse: usize) -> f64 {
    (n_coarse as f64 / n_fine as f64).powf(STIFFNESS_SCALE_EXPONENT)
}

/// The exponent of [`stiffness_scale`]: `(n_coarse / n_fine)^0.6`, 0.435 for an aggregation
/// step of ratio 4. Measured on the finest level's TNNMG iterations from nested starts
/// (imported Gmsh sites of 10⁵ and 10⁶ vertices, the disc, rigid disc, stepped disc, plinth
/// and roof examples at three to four sizes each): against ½ the iterations fell by one
/// or two on a third of the cases and rose by one on one small case; above 0.6 the rigid
/// disc needed up to twice as many.
pub const STIFFNESS_SCALE_EXPONENT: f64 = 0.6;

/// `PᵀAP` on its own pattern.
fn galerkin(a: &Csr, t: &Transfer) -> Csr {
    let pattern: Pattern = t.galerkin_pattern(&a.pattern);
    let mut c = Csr::zeros(Arc::new(pattern));
    t.galerkin_values(a, &mut c, None);
    c
}

#[cfg(test)]
mod tests {
    use super::super::transfer::galerkin_patterns;
    use super::*;

    /// The 5-point Laplacian on an m × m grid.
    fn lap2d(m: usize) -> Csr {
        let id = |i: usize, j: usize| i * m + j;
        let mut t = Vec::new();
        for i in 0..m {
            for j in 0..m {
                t.push((id(i, j), id(i, j), 4.0));
                if i > 0 {
                    t.push((id(i, j), id(i - 1, j), -1.0));
                }
                if i + 1 < m {
                    t.push((id(i, j), id(i + 1, j), -1.0));
                }
                if j > 0 {
                    t.push((id(i, j), id(i, j - 1), -1.0));
                }
                if j + 1 < m {
                    t.push((id(i, j), id(i, j + 1), -1.0));
                }
            }
        }
        Csr::from_triplets(m * m, &t)
    }

    #[test]
    fn aggregates_are_small_connected_and_cover_the_coupled_rows() {
        // 10⁴ rows: one matching over all rows; 1.6·10⁵: by blocks in parallel.
        for m in [100, 400] {
            check_aggregates(&lap2d(m), m * m);
        }
    }

    fn check_aggregates(a: &Csr, n: usize) {
        let (transfers, sizes, patterns) = hierarchy(a, COARSEST);
        // The patterns built from the half-size products are those of PᵀAP for the
        // composed transfers, computed directly from the finest pattern.
        let direct = galerkin_patterns(&transfers, a.pattern.clone());
        assert_eq!(patterns.len(), direct.len());
        for (p, q) in patterns.iter().zip(&direct) {
            assert_eq!(p.row_ptr, q.row_ptr);
            assert_eq!(p.col, q.col);
        }
        assert!(sizes.len() >= 3, "{sizes:?}");
        assert_eq!(*sizes.last().unwrap(), n);
        assert!(sizes[0] <= COARSEST, "{sizes:?}");
        // Coarsening ratio close to 4 per level.
        for w in sizes.windows(2) {
            let ratio = w[1] as f64 / w[0] as f64;
            assert!(ratio > 3.0 && ratio <= 4.0 + 1e-12, "{sizes:?}");
        }
        let t = transfers.last().unwrap();
        let mut members = vec![Vec::new(); t.n_coarse];
        for (v, p) in t.parents.iter().enumerate() {
            // Every row of the Laplacian is coupled: every row is in an aggregate.
            assert_eq!(t.weights(v), [1.0, 0.0]);
            members[p[0] as usize].push(v);
        }
        for m in &members {
            assert!(!m.is_empty() && m.len() <= 4, "{m:?}");
            // Connected: every member has a neighbour in the aggregate (or is alone).
            for &v in m {
                assert!(m.len() == 1 || m.iter().any(|&u| u != v && a.get(u, v) != 0.0));
            }
        }
    }

    /// Aggregates are numbered in the order of their first rows (the coarse unknowns keep
    /// the fine rows' locality), in one matching and by blocks.
    #[test]
    fn aggregates_are_numbered_in_row_order() {
        for m in [60, 400] {
            let a = lap2d_with_stiff_row(m, 3);
            let (agg, n) = pairwise(&a);
            // In row order, an aggregate not met before has the next number.
            let mut next = 0u32;
            for (v, &g) in agg.iter().enumerate().filter(|(_, &g)| g != NONE) {
                assert!(g <= next, "row {v}: aggregate {g} before {next}");
                next += u32::from(g == next);
            }
            assert_eq!(next as usize, n);
        }
    }

    /// The block-parallel matching gives the same aggregates on one thread as on several.
    #[test]
    fn matching_does_not_depend_on_the_thread_count() {
        let a = lap2d(400);
        assert!(a.n() >= 2 * MATCH_BLOCK);
        let many = pairwise(&a);
        let one = crate::parallel::on_threads(1, || pairwise(&a));
        assert_eq!(many, one);
    }

    /// The Galerkin product of an aggregation (one parent per unknown, read without the
    /// second) is `(PᵀAP)_IJ = Σ a_vw` over v in aggregate I and w in J, rows left to the
    /// smoother taking no part.
    #[test]
    fn aggregation_galerkin_sums_the_couplings_between_aggregates() {
        let a = lap2d_with_stiff_row(30, 7);
        let (agg, n) = pairwise(&a);
        assert_eq!(agg[7], NONE);
        let t = Transfer::aggregation(&agg, n);
        assert!(t.single_parent);
        let c = galerkin(&a, &t);
        let mut expected = vec![vec![0.0; n]; n];
        for v in 0..a.n() {
            let (cols, vals) = a.row(v);
            for (&w, &x) in cols.iter().zip(vals) {
                let (i, j) = (agg[v], agg[w as usize]);
                if i != NONE && j != NONE {
                    expected[i as usize][j as usize] += x;
                }
            }
        }
        for (i, row) in expected.iter().enumerate() {
            for (j, &e) in row.iter().enumerate() {
                assert!(
                    (c.get(i, j) - e).abs() <= 1e-12,
                    "({i}, {j}): {} vs {e}",
                    c.get(i, j)
                );
            }
        }
    }

    /// [`lap2d`] with a huge diagonal in `row` (a stiff foundation there).
    fn lap2d_with_stiff_row(m: usize, row: usize) -> Csr {
        let mut a = lap2d(m);
        let k = a.pattern.find(row, row).unwrap();
        a.val[k] = 1e6;
        a
    }

    #[test]
    fn dominant_rows_are_left_to_the_smoother() {
        let a = lap2d_with_stiff_row(10, 0);
        let (agg, n) = pairwise(&a);
        assert_eq!(agg[0], NONE);
        assert!(agg[1..].iter().all(|&g| (g as usize) < n));
    }
}
