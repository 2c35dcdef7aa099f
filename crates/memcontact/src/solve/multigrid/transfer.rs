//! Grid transfer between consecutive levels of a [`crate::mesh::refine::Hierarchy`], over the *unknowns* (the
//! interior vertices, SPEC §2), and the Galerkin coarse operator `A_c = Pᵀ A P`.
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
    /// Columns of P: the children of coarse unknown `I` are
    /// `children[child_ptr[I]..child_ptr[I + 1]]`, in increasing order.
    pub child_ptr: Vec<usize>,
    /// Fine unknowns, grouped by coarse parent.
    pub children: Vec<u32>,
    /// `P[child, I]` for every entry of `children`: 1 (code 0) or ½ (code 1).
    child_code: Vec<u8>,
    /// Every fine unknown has at most one parent (an aggregation): the second parents
    /// need not be visited.
    pub single_parent: bool,
}

impl Transfer {
    /// P between the unknowns of two consecutive levels. `refinement.parents` must have one
    /// entry per fine vertex, each naming coarse vertices; anything else is an error.
    pub fn new(refinement: &Refinement, coarse: &DofMap, fine: &DofMap) -> Result<Transfer> {
        let n_cv = coarse.dof.len();
        if refinement.parents.len() != fine.dof.len() {
            return Err(Error::Mesh(format!(
                "the refinement relation names parents for {} vertices, but the finer level \
                 has {} vertices",
                refinement.parents.len(),
                fine.dof.len()
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
            let (da, db) = (coarse.dof[a as usize], coarse.dof[b as usize]);
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
        let children = entries.par_iter().with_min_len(4096).map(|e| e.0).collect();
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
            child_ptr,
            children,
            child_code,
            single_parent,
        }
    }

    /// The weights of fine unknown `v`'s two parents.
    #[inline(always)]
    pub fn weights(&self, v: usize) -> [f32; 2] {
        WEIGHTS[self.weight_code[v] as usize]
    }

    /// `P[children[k], I]` for the entry `k` of the columns.
    #[inline(always)]
    fn child_weight(&self, k: usize) -> f32 {
        [1.0, 0.5][self.child_code[k] as usize]
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
            for k in self.child_ptr[i]..self.child_ptr[i + 1] {
                s += f64::from(self.child_weight(k)) * rf[self.children[k] as usize];
            }
            *r = s;
        });
    }

    /// The coarse unknown sitting on the same vertex as each fine unknown, inverted: for
    /// every coarse unknown, the fine unknown at the same place (the child of weight 1).
    pub fn injection(&self) -> Vec<u32> {
        (0..self.n_coarse)
            .map(|i| {
                (self.child_ptr[i]..self.child_ptr[i + 1])
                    .find(|&k| self.child_weight(k) == 1.0)
                    .map_or(self.children[self.child_ptr[i]], |k| self.children[k])
            })
            .collect()
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
                for &v in &self.children[self.child_ptr[i]..self.child_ptr[i + 1]] {
                    let v = v as usize;
                    for &w in &fine.col[fine.row_ptr[v]..fine.row_ptr[v + 1]] {
                        let (p, wt) = (self.parents[w as usize], self.weights(w as usize));
                        for s in 0..2 {
                            if wt[s] != 0.0 && seen[p[s] as usize] != i as u32 {
                                seen[p[s] as usize] = i as u32;
                                r.push(p[s]);
                            }
                        }
                    }
                }
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
            let cols = &cpat.col[cpat.row_ptr[i]..cpat.row_ptr[i + 1]];
            for (k, &j) in cols.iter().enumerate() {
                marker[j as usize] = k as u32;
                vals[k] = 0.0;
            }
            for c in self.child_ptr[i]..self.child_ptr[i + 1] {
                let v = self.children[c] as usize;
                if !A::PLAIN && op.held(v) {
                    continue; // a zero row
                }
                let wv = f64::from(self.child_weight(c));
                let (s, e) = (fpat.row_ptr[v], fpat.row_ptr[v + 1]);
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
            }
        };
        let chunks = row_chunks(&cpat, &mut coarse.val, 512);
        let work = |marker: &mut Vec<u32>, (start, vals): (usize, &mut [f64])| {
            let mut off = 0;
            let end = (start + 512).min(n_coarse);
            for i in start..end {
                let len = cpat.row_ptr[i + 1] - cpat.row_ptr[i];
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
            *d = self.children[self.child_ptr[i]..self.child_ptr[i + 1]]
                .iter()
                .any(|&v| dirty_fine[v as usize]);
        });
    }
}

/// The Galerkin patterns of a chain of transfers, coarsest first, ending with `finest`.
pub fn galerkin_patterns(transfers: &[Transfer], finest: Arc<Pattern>) -> Vec<Arc<Pattern>> {
    let mut pats = vec![finest];
    for t in transfers.iter().rev() {
        let p = t.galerkin_pattern(pats.last().expect("at least the finest"));
        pats.push(Arc::new(p));
    }
    pats.reverse();
    pats
}
