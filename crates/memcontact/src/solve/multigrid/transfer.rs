//! Grid transfer between consecutive levels of a [`crate::mesh::refine::Hierarchy`], over
//! the *unknowns* (the interior vertices, docs/theory.md#triangulation), and the Galerkin
//! coarse operator `A_c = Pᵀ A P`.
//!
//! The mesh refinement says that fine vertex `v` carries `½(c[a] + c[b])` of a coarse P1
//! function (`a = b` when `v` sits on a coarse vertex). Restricted to unknowns, parents on
//! the boundary ∂Ω are dropped (the coarse function vanishes there), so every fine unknown
//! has at most two coarse parents with weights ½ (or one with weight 1). P is stored by
//! rows (fine → parents) for prolongation and by columns (coarse → children) for the
//! restriction `Pᵀ` and for the Galerkin product, so that every coarse entry is a sum in a
//! fixed order: results never depend on the number of threads.

use super::operator::{entry, TopOperator};
use crate::error::{Error, Result};
use crate::mesh::refine::Refinement;
use crate::mesh::DofMap;
use crate::sparse::{par_rows, row_chunks, Csr, Pattern, VECTOR_ROWS};
use rayon::prelude::*;
use std::sync::Arc;

/// The weights a fine unknown can have for its two parents.
const WEIGHTS: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [0.5, 0.0]];

/// The index of `w` in [`WEIGHTS`].
fn weight_code(w: [f32; 2]) -> u8 {
    WEIGHTS
        .iter()
        .position(|&x| x == w)
        .expect("prolongation weights are 0, ½ or 1") as u8
}

/// The prolongation `P` from a coarse level's unknowns to a fine level's unknowns.
#[derive(Debug, Clone)]
pub struct Transfer {
    /// Number of coarse unknowns (columns of P).
    pub n_coarse: usize,
    /// Per fine unknown: its (up to) two coarse parents. A missing second parent repeats
    /// the first with weight 0, so that loops need no branch; a fine unknown with no
    /// interior parent at all has weights `[0, 0]`.
    pub parents: Vec<[u32; 2]>,
    /// The weights of `parents` (½ and ½, or 1 and 0, or 0 where a parent was dropped), as
    /// an index into [`WEIGHTS`]: one byte per fine unknown instead of eight.
    weight_code: Vec<u8>,
    /// The columns of P: the children of every coarse unknown, in increasing order.
    columns: Columns,
    /// Every fine unknown has at most one parent (an aggregation): the second parents
    /// need not be visited.
    pub single_parent: bool,
}

/// The columns of P (the children of each coarse unknown with their weights), stored or
/// read from the fine level's pattern.
#[derive(Debug, Clone)]
enum Columns {
    /// The children of coarse unknown `I` are `children[child_ptr[I]..child_ptr[I + 1]]`,
    /// `P[child, I]` is 1 (code 0) or ½ (code 1) for each.
    Stored {
        child_ptr: Vec<usize>,
        children: Vec<u32>,
        child_code: Vec<u8>,
    },
    /// Nested meshes: the children of coarse unknown `I` are the fine unknown `on[I]` at
    /// the same place and its neighbours that have `I` as a parent, i.e. the entries of
    /// row `on[I]` of the fine level's pattern with `P[w, I] ≠ 0` (sorted like the stored
    /// children, so that every sum over them is the same). Checked when chosen
    /// ([`Transfer::with_columns_from`]); nothing per child is stored.
    /// With `whole`, every entry of those rows is a child, of weight ½ but `on[I]` itself
    /// (weight 1): the weights need not be looked up. Otherwise (a locally refined level,
    /// where most coarse unknowns have no child but the one on them) `masks[I]` marks the
    /// positions of the children in that row, of the same weights: bit k for entry k.
    FineRows {
        on: Vec<u32>,
        fine: Arc<Pattern>,
        whole: bool,
        masks: Vec<u32>,
    },
}

impl Transfer {
    /// P between the unknowns of two consecutive levels. `refinement.parents` must have one
    /// entry per fine vertex, each naming coarse vertices; anything else is an error.
    pub fn new(refinement: &Refinement, coarse: &DofMap, fine: &DofMap) -> Result<Transfer> {
        let n_cv = coarse.n_vertices();
        if refinement.parents.len() != fine.n_vertices() {
            return Err(Error::Mesh(format!(
                "the refinement relation names parents for {} vertices, but the finer level \
                 has {} vertices",
                refinement.parents.len(),
                fine.n_vertices()
            )));
        }
        if let Some((v, p)) = refinement
            .parents
            .iter()
            .enumerate()
            .find(|(_, p)| p[0] as usize >= n_cv || p[1] as usize >= n_cv)
        {
            return Err(Error::Mesh(format!(
                "vertex {v} of the finer level has parent vertices ({}, {}), but the \
                 coarser level has only {n_cv} vertices",
                p[0], p[1]
            )));
        }
        let n_fine = fine.len();
        let map = |&v: &u32| -> ([u32; 2], [f32; 2]) {
            let [a, b] = refinement.parents[v as usize];
            let (da, db) = (coarse.of(a as usize), coarse.of(b as usize));
            if a == b {
                match da {
                    Some(i) => ([i, i], [1.0, 0.0]),
                    None => ([0, 0], [0.0, 0.0]),
                }
            } else {
                match (da, db) {
                    (Some(i), Some(j)) => ([i, j], [0.5, 0.5]),
                    (Some(i), None) => ([i, i], [0.5, 0.0]),
                    (None, Some(j)) => ([j, j], [0.5, 0.0]),
                    (None, None) => ([0, 0], [0.0, 0.0]),
                }
            }
        };
        let (parents, weights): (Vec<[u32; 2]>, Vec<[f32; 2]>) = if n_fine >= VECTOR_ROWS {
            fine.vertex.par_iter().with_min_len(4096).map(map).unzip()
        } else {
            fine.vertex.iter().map(map).unzip()
        };
        Ok(Transfer::from_rows(parents, weights, coarse.len()))
    }

    /// The piecewise-constant prolongation of an aggregation: fine unknown `v` belongs to
    /// aggregate `aggregate[v] < n_coarse` (`P[v, aggregate[v]] = 1`), or to none
    /// (`aggregate[v] = u32::MAX`: a zero row of P).
    pub fn aggregation(aggregate: &[u32], n_coarse: usize) -> Transfer {
        let (parents, weights): (Vec<[u32; 2]>, Vec<[f32; 2]>) = aggregate
            .par_iter()
            .with_min_len(8192)
            .map(|&a| {
                if (a as usize) < n_coarse {
                    ([a, a], [1.0, 0.0])
                } else {
                    ([0, 0], [0.0, 0.0])
                }
            })
            .unzip();
        Transfer::from_rows(parents, weights, n_coarse)
    }

    /// P from its rows (up to two parents per fine unknown; weight 0 for a missing one),
    /// with the columns built by a counting sort (children in increasing fine order,
    /// [`crate::sparse::group_by_key`]).
    fn from_rows(parents: Vec<[u32; 2]>, weights: Vec<[f32; 2]>, n_coarse: usize) -> Transfer {
        let (child_ptr, entries) = crate::sparse::group_by_key(n_coarse, parents.len(), |v| {
            let (p, w) = (parents[v], weights[v]);
            [0, 1].map(|s| (w[s] != 0.0).then_some((p[s], (v as u32, w[s]))))
        });
        let children: Vec<u32> = entries.par_iter().with_min_len(4096).map(|e| e.0).collect();
        let child_code = entries
            .par_iter()
            .with_min_len(4096)
            .map(|e| {
                let w = e.1;
                assert!(w == 1.0 || w == 0.5, "a child's weight is 1 or ½, not {w}");
                (w == 0.5) as u8
            })
            .collect();
        drop(entries);
        let single_parent = weights.par_iter().with_min_len(4096).all(|w| w[1] == 0.0);
        let weight_code = weights
            .par_iter()
            .with_min_len(4096)
            .map(|&w| weight_code(w))
            .collect();
        Transfer {
            n_coarse,
            parents,
            weight_code,
            columns: Columns::Stored {
                child_ptr,
                children,
                child_code,
            },
            single_parent,
        }
    }

    /// This transfer with its columns read from `fine`, the pattern of the fine level's
    /// operator, when that pattern holds them: every coarse unknown has a fine unknown of
    /// weight 1 on it whose row lists exactly its children (nested meshes, where a coarse
    /// vertex's children are the fine vertex on it and the midpoints of its edges, all
    /// neighbours of that vertex). Otherwise (aggregation, other patterns) unchanged. The
    /// same children in the same order: every result is bitwise the same, and the columns
    /// take 4 bytes per coarse unknown (8 on a locally refined level, with the children's
    /// positions) instead of about 7 per fine one.
    pub fn with_columns_from(self, fine: &Arc<Pattern>) -> Transfer {
        let Columns::Stored {
            child_ptr,
            children,
            child_code,
        } = &self.columns
        else {
            return self;
        };
        if fine.n() != self.n_fine() {
            return self;
        }
        // The child of weight 1 of every coarse unknown, and its row's matching entries
        // counted against the stored children.
        // Per coarse unknown: (the fine unknown on it, whether its row holds nothing but
        // its children, the positions of the children in its row).
        let on: Option<Vec<(u32, bool, Option<u32>)>> = (0..self.n_coarse)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let (lo, hi) = (child_ptr[i], child_ptr[i + 1]);
                let k = (lo..hi).find(|&k| child_code[k] == 0)?;
                let v = children[k] as usize;
                let row = &fine.col[fine.ptr(v)..fine.ptr(v + 1)];
                let mut next = lo;
                // The children's positions (none when one lies beyond the 32nd entry).
                let mut mask = Some(0u32);
                for (pos, &w) in row.iter().enumerate() {
                    if self.weight_of(w as usize, i) != 0.0 {
                        // Weight 1 on v itself and ½ on every other child, as the rows'
                        // columns assume.
                        if next == hi
                            || children[next] != w
                            || child_code[next] != (w as usize != v) as u8
                        {
                            return None;
                        }
                        mask = mask.filter(|_| pos < 32).map(|m| m | 1 << pos);
                        next += 1;
                    }
                }
                // Codes are 0 (weight 1) or 1 (weight ½): one child of weight 1, v itself.
                let ones = child_code[lo..hi].iter().filter(|&&c| c == 0).count();
                let whole = row.len() == hi - lo && ones == 1;
                (next == hi).then_some((v as u32, whole, mask))
            })
            .collect();
        match on {
            Some(on) => {
                let whole = on.par_iter().all(|x| x.1);
                let masks = if whole {
                    Vec::new()
                } else {
                    match on.par_iter().with_min_len(4096).map(|x| x.2).collect() {
                        Some(masks) => masks,
                        None => return self,
                    }
                };
                Transfer {
                    columns: Columns::FineRows {
                        on: on.into_par_iter().map(|x| x.0).collect(),
                        fine: fine.clone(),
                        whole,
                        masks,
                    },
                    ..self
                }
            }
            None => self,
        }
    }

    /// `P[w, I]`: the weight of coarse unknown `i` in fine unknown `w` (0 unless a parent).
    #[inline(always)]
    fn weight_of(&self, w: usize, i: usize) -> f64 {
        let [p0, p1] = self.parents[w];
        let [w0, w1] = self.weights(w);
        if p0 as usize == i && w0 != 0.0 {
            f64::from(w0)
        } else if p1 as usize == i && w1 != 0.0 {
            f64::from(w1)
        } else {
            0.0
        }
    }

    /// Calls `f(w, P[w, i])` for the children `w` of coarse unknown `i`, in increasing
    /// order.
    #[inline(always)]
    fn for_children(&self, i: usize, mut f: impl FnMut(usize, f64)) {
        match &self.columns {
            Columns::Stored {
                child_ptr,
                children,
                child_code,
            } => {
                for k in child_ptr[i]..child_ptr[i + 1] {
                    f(
                        children[k] as usize,
                        f64::from([1.0f32, 0.5][child_code[k] as usize]),
                    );
                }
            }
            Columns::FineRows {
                on,
                fine,
                whole,
                masks,
            } => {
                let v = on[i] as usize;
                let row = &fine.col[fine.ptr(v)..fine.ptr(v + 1)];
                let weight = |w: usize| if w == v { 1.0 } else { 0.5 };
                if *whole {
                    for &w in row {
                        f(w as usize, weight(w as usize));
                    }
                } else {
                    // The set bits, lowest first: the children in increasing order.
                    let mut mask = masks[i];
                    while mask != 0 {
                        let w = row[mask.trailing_zeros() as usize] as usize;
                        mask &= mask - 1;
                        f(w, weight(w));
                    }
                }
            }
        }
    }

    /// Whether the columns are read from the fine level's pattern
    /// ([`Transfer::with_columns_from`]).
    pub fn columns_from_fine_rows(&self) -> bool {
        matches!(self.columns, Columns::FineRows { .. })
    }

    /// Whether the columns are whole rows of the fine level's pattern (their weights then
    /// follow from the place alone).
    #[cfg(test)]
    pub(crate) fn columns_are_whole_rows(&self) -> bool {
        matches!(self.columns, Columns::FineRows { whole: true, .. })
    }

    /// The weights of fine unknown `v`'s two parents.
    #[inline(always)]
    pub fn weights(&self, v: usize) -> [f32; 2] {
        WEIGHTS[self.weight_code[v] as usize]
    }

    /// Number of fine unknowns (rows of P).
    pub fn n_fine(&self) -> usize {
        self.parents.len()
    }

    /// `(P x_c)_v`.
    #[inline]
    fn row(&self, v: usize, xc: &[f64]) -> f64 {
        let [a, b] = self.parents[v];
        let [wa, wb] = self.weights(v);
        f64::from(wa) * xc[a as usize] + f64::from(wb) * xc[b as usize]
    }

    /// `x_f = P x_c`.
    pub fn prolongate(&self, xc: &[f64], xf: &mut [f64]) {
        if xc.is_empty() {
            xf.iter_mut().for_each(|x| *x = 0.0);
            return;
        }
        par_rows(xf, |v, x| *x = self.row(v, xc));
    }

    /// `x_f += P x_c`.
    pub fn prolongate_add(&self, xc: &[f64], xf: &mut [f64]) {
        if xc.is_empty() {
            return;
        }
        par_rows(xf, |v, x| *x += self.row(v, xc));
    }

    /// `r_c = Pᵀ r_f`.
    pub fn restrict(&self, rf: &[f64], rc: &mut [f64]) {
        par_rows(rc, |i, r| {
            let mut s = 0.0;
            self.for_children(i, |w, wt| s += wt * rf[w]);
            *r = s;
        });
    }

    /// The coarse unknown sitting on the same vertex as each fine unknown, inverted: for
    /// every coarse unknown, the fine unknown at the same place (the child of weight 1).
    pub fn injection(&self) -> Vec<u32> {
        match &self.columns {
            Columns::Stored {
                child_ptr,
                children,
                child_code,
            } => (0..self.n_coarse)
                .map(|i| {
                    (child_ptr[i]..child_ptr[i + 1])
                        .find(|&k| child_code[k] == 0)
                        .map_or(children[child_ptr[i]], |k| children[k])
                })
                .collect(),
            Columns::FineRows { on, .. } => on.clone(),
        }
    }

    /// The sparsity pattern of `Pᵀ A P` for A on `fine` (the symbolic Galerkin product,
    /// computed once per hierarchy). The diagonal is always stored.
    pub fn galerkin_pattern(&self, fine: &Pattern) -> Pattern {
        const ROWS: usize = 4096;
        /// Rows up to this long are sorted by rank.
        const SMALL: usize = 32;
        let n_coarse = self.n_coarse;
        // Per block of coarse rows: the row lengths and the concatenated sorted columns.
        // `seen[j] == i` marks column j as already in row i (no sort of duplicates).
        let block = |seen: &mut Vec<u32>, b: usize| -> (Vec<u32>, Vec<u32>) {
            let (lo, hi) = (b * ROWS, ((b + 1) * ROWS).min(n_coarse));
            let mut lens = Vec::with_capacity(hi - lo);
            let mut cols = Vec::with_capacity((hi - lo) * 9);
            let mut r: Vec<u32> = Vec::with_capacity(64);
            for i in lo..hi {
                r.clear();
                r.push(i as u32);
                seen[i] = i as u32;
                self.for_children(i, |v, _| {
                    for &w in &fine.col[fine.ptr(v)..fine.ptr(v + 1)] {
                        let (p, wt) = (self.parents[w as usize], self.weights(w as usize));
                        for s in 0..2 {
                            if wt[s] != 0.0 && seen[p[s] as usize] != i as u32 {
                                seen[p[s] as usize] = i as u32;
                                r.push(p[s]);
                            }
                        }
                    }
                });
                if r.len() <= SMALL {
                    // The row's columns by rank (the count of smaller ones): branch-free
                    // on the distinct columns, where a comparison sort mispredicts.
                    let mut sorted = [0u32; SMALL];
                    for &x in &r {
                        let rank: usize = r.iter().map(|&y| (y < x) as usize).sum();
                        sorted[rank] = x;
                    }
                    cols.extend_from_slice(&sorted[..r.len()]);
                } else {
                    r.sort_unstable();
                    cols.extend_from_slice(&r);
                }
                lens.push(r.len() as u32);
            }
            (lens, cols)
        };
        let nb = n_coarse.div_ceil(ROWS);
        let blocks: Vec<(Vec<u32>, Vec<u32>)> = if n_coarse >= VECTOR_ROWS {
            (0..nb)
                .into_par_iter()
                .map_init(|| vec![u32::MAX; n_coarse], block)
                .collect()
        } else {
            let mut seen = vec![u32::MAX; n_coarse];
            (0..nb).map(|b| block(&mut seen, b)).collect()
        };
        Pattern::from_blocks(&blocks)
    }

    /// The numeric Galerkin product: fills the rows of `coarse` (on
    /// [`Transfer::galerkin_pattern`] of `fine`'s pattern) with `Pᵀ A P`, only the rows
    /// flagged in `dirty` when given. Every entry is summed in a fixed order (children of
    /// the row, then the fine row's entries), whatever the number of threads.
    pub fn galerkin_values<A: TopOperator>(
        &self,
        op: &A,
        coarse: &mut Csr,
        dirty: Option<&[bool]>,
    ) {
        let n_coarse = self.n_coarse;
        let cpat = coarse.pattern.clone();
        let fine = op.matrix();
        let fpat = &fine.pattern;
        let row = |i: usize, vals: &mut [f64], marker: &mut [u32]| {
            let cols = &cpat.col[cpat.ptr(i)..cpat.ptr(i + 1)];
            for (k, &j) in cols.iter().enumerate() {
                marker[j as usize] = k as u32;
                vals[k] = 0.0;
            }
            self.for_children(i, |v, wv| {
                if !A::PLAIN && op.held(v) {
                    return; // a zero row
                }
                let (s, e) = (fpat.ptr(v), fpat.ptr(v + 1));
                for (&w, &a) in fpat.col[s..e].iter().zip(&fine.val[s..e]) {
                    let a = entry(op, v, w as usize, a);
                    if a == 0.0 {
                        continue;
                    }
                    let a = a * wv;
                    let w = w as usize;
                    let [p0, p1] = self.parents[w];
                    let [w0, w1] = self.weights(w).map(f64::from);
                    if w0 != 0.0 {
                        vals[marker[p0 as usize] as usize] += a * w0;
                        // A dropped second parent repeats the first with weight 0.
                        if !self.single_parent {
                            vals[marker[p1 as usize] as usize] += a * w1;
                        }
                    }
                }
            });
        };
        let chunks = row_chunks(&cpat, &mut coarse.val, 512);
        let work = |marker: &mut Vec<u32>, (start, vals): (usize, &mut [f64])| {
            let mut off = 0;
            let end = (start + 512).min(n_coarse);
            for i in start..end {
                let len = cpat.ptr(i + 1) - cpat.ptr(i);
                if dirty.is_none_or(|d| d[i]) {
                    row(i, &mut vals[off..off + len], marker);
                }
                off += len;
            }
        };
        if n_coarse >= VECTOR_ROWS / 4 {
            chunks
                .into_par_iter()
                .for_each_init(|| vec![0u32; n_coarse], work);
        } else {
            let mut marker = vec![0u32; n_coarse];
            for c in chunks {
                work(&mut marker, c);
            }
        }
    }

    /// Coarse rows to recompute when the fine rows flagged `dirty_fine` changed.
    pub fn coarse_dirty(&self, dirty_fine: &[bool], dirty_coarse: &mut [bool]) {
        par_rows(dirty_coarse, |i, d| {
            let mut any = false;
            self.for_children(i, |v, _| any |= dirty_fine[v]);
            *d = any;
        });
    }
}

/// The Galerkin patterns of a chain of transfers, coarsest first, ending with `finest`
/// (the tests' check of the patterns the levels build as they go).
#[cfg(test)]
pub fn galerkin_patterns(transfers: &[Transfer], finest: Arc<Pattern>) -> Vec<Arc<Pattern>> {
    let mut pats = vec![finest];
    for t in transfers.iter().rev() {
        let p = t.galerkin_pattern(pats.last().expect("at least the finest"));
        pats.push(Arc::new(p));
    }
    pats.reverse();
    pats
}
